// The bake: turns placed muscles into joints, animation and skin weights for a character, as plain
// data that formats/gltf_bake.cpp writes into the glTF. Following the talk's "Muscle Joint Group":
// per muscle a base joint (at the origin, aimed at the insertion), a tip joint (at the insertion,
// aimed at the origin), a driver between them and one skinned joint on the driver with a
// volume-preserving scale (docs/muscle-model.md). Influences are pruned to 4, 7 or 10 per vertex and
// quantized to 0.001 ("Increase Bone Influences per Vertex"; docs/packed-influences.md).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "anatomy/body_regions.h"
#include "pipeline/deformation_error.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/influences.h"
#include "pipeline/jiggle.h"
#include "pipeline/muscle_weights.h"
#include "pipeline/pack_influences.h"
#include "pipeline/progress.h"
#include "pipeline/response_fit.h"

namespace rigbake {

// Whether the bake fits the muscles' response to the clips (pipeline/response_fit.h).
enum class ResponseMode {
  kAuto,  // fit the parts that still have their preset's response; keep curves a muscle file brings
  kFit,   // fit every part (a file's curves are the starting point and the prior)
  kKeep,  // fit nothing
};
const char* responseModeName(ResponseMode mode);
bool parseResponseMode(const std::string& name, ResponseMode* mode);

// How the muscle joints move in the written file (docs/runtime.md, "Choosing a mode").
enum class MuscleMotion {
  kRuntime,  // the RIGBAKE_muscle_rig extension only: engines evaluate the rig; +0 sampled channels
  kSampled,  // channels for the skinned joints (and the helpers with helper_joints), no extension
  kBoth,     // the extension and the skinned joints' channels, for players that may not run the rig
};
const char* muscleMotionName(MuscleMotion motion);
bool parseMuscleMotion(const std::string& name, MuscleMotion* motion);

struct BakeOptions {
  int influences = 4;  // 4, 7 or 10
  GltfWeights gltf_weights = GltfWeights::kMilli;
  double fps = 0.0;    // 0: sample each clip at its own key times
  MuscleWeightOptions weights;
  // Secondary motion baked into every clip (docs/jiggle.md): setups from resolveJiggles() against
  // this character and these muscles, and the hits that kick them.
  std::vector<JiggleSetup> jiggles;
  std::vector<HitImpulse> hits;
  // Body regions (anatomy/body_regions.h) for the deformation-quality figures; none: whole body only.
  std::vector<BodyRegion> regions;
  // Creases (anatomy/creases.h) for the crease contact figures; none: not measured.
  std::vector<Crease> creases;
  bool measure_quality = true;  // volumes against plain and dual-quaternion skinning, per clip and region
  // With measure_quality, the skin's surface figures too (issue 29): seams, joint regions, roughness
  // against dual quaternions and centres of rotation, crease contact. They cost more than the rest of
  // the bake together (bench/run: 3.4 s of the 100k sample's 4 s first bake), so the CLI asks for them
  // only when figures are written (--stats, --json); `rigbake validate` measures them from the file.
  bool measure_skin = true;
  ResponseMode response = ResponseMode::kAuto;
  ResponseFitOptions fit;
  // Threads for the per-vertex, per-frame and per-pose loops; 0: one per core. Every output is the same
  // at any count (pipeline/parallel.h).
  int threads = 0;
  MuscleMotion motion = MuscleMotion::kRuntime;
  bool helper_joints = false;  // also write base, tip and driver as nodes (and, when sampled, channels)
  // Told of each stage as it starts and of the fit's passes (pipeline/progress.h); may be empty.
  ProgressReport progress;
};

// The four joints of one muscle group. Each is a new node: the skinned joint is also added to every
// skin; base, driver and skinned ride on the origin attach joint, the tip on the insertion joint.
enum class MuscleJointRole { kBase, kTip, kDriver, kSkinned };

struct BakedJoint {
  std::string name;        // e.g. LeftBicep_muscleSkinned
  int muscle = -1;         // index into MuscleSet::parts
  MuscleJointRole role = MuscleJointRole::kSkinned;
  int parent = -1;         // skeleton joint the node is a child of
  Trs rest_local;          // node TRS at the skeleton's rest pose
  Eigen::Affine3d bind_world = Eigen::Affine3d::Identity();  // scene world at the bind pose
};

// Where a deformation error peaks, so a user can look at it: one vertex of a skinned mesh part at one
// sampled time of a clip.
struct ErrorPeak {
  int mesh_part = -1;  // index into Character::meshes; -1 when nothing moved
  int vertex = -1;     // index into that part's vertices
  double time = 0.0;   // seconds into the clip
};

// How far one set of rounded weights moves the skin from the full-precision weights, in metres, over
// every sampled frame of every clip (per_clip and peaks in BakeResult::clips order).
struct DeformationFigures {
  std::vector<DeformationError> per_clip;  // max_vertex there counts every frame's vertices in turn;
  std::vector<ErrorPeak> peaks;            // the peaks say which part, vertex and time
  DeformationError overall;
  int peak_clip = -1;  // the clip holding overall.max_displacement; -1 when nothing moved
};

struct BakedClip {
  int gltf_animation = -1;
  bool measure_only = false;  // Clip::measure_only: measured on (weights, errors), not written
  std::string name;
  std::vector<double> times;
  // local[t][k]: TRS of baked joint k (relative to its parent) at times[t]; empty when the motion is
  // MuscleMotion::kRuntime, whose file has no channels for the muscle joints.
  std::vector<std::vector<Trs>> local;
  // ratio[t][m]: muscle m's length ratio L / L_rest (unclamped) at times[t].
  std::vector<std::vector<double>> ratio;
  // One track per BakeOptions::jiggles entry, in that order, sampled at `times`. A muscle jiggle's
  // local TRS is already in `local` (its skinned joint); a skeleton joint's replaces the clip's own
  // channels of that joint.
  std::vector<JiggleTrack> jiggles;
};

struct BakedPart {
  int mesh_part = -1;               // index into Character::meshes
  std::vector<int> skin_joints;     // skeleton indices of the written skin, muscles appended
  InfluenceSet full;                // muscles added, before pruning (skeleton indices)
  QuantizedInfluences quantized;    // pruned to N, 0.001 steps (skin-local indices)
  std::vector<VertexAttributeData> standard;  // JOINTS_n / WEIGHTS_n
  PackedInfluences packed;                    // skin-local indices
  std::vector<VertexAttributeData> packed_attributes;
};

struct BakeResult {
  int influences = 0;
  // The muscles as baked: each part's carrier joint chosen and its response as used (fitted when
  // BakeOptions asked for it). Write these, not the input, into the file and any muscle JSON.
  MuscleSet muscles;
  std::vector<BakedJoint> joints;  // 4 per muscle: base, tip, driver, skinned
  std::vector<int> skinned_joint_of_muscle;  // index into joints
  std::vector<BakedClip> clips;
  std::vector<BakedPart> parts;
  int vertex_count = 0;  // skinned vertices written
  // Of them, those on pieces of skin the input moves rigidly, which no muscle takes weight on
  // (rigidPieces(), MuscleWeightOptions::rigid_pieces_stay_rigid).
  int rigid_piece_vertices = 0;
  // Pruning + 0.001 rounding: the packed buffers' weights (and WEIGHTS_n' with GltfWeights::kMilli).
  DeformationFigures error;
  GltfWeights gltf_weights = GltfWeights::kMilli;
  DeformationFigures gltf_error;  // GltfWeights::kUnorm16 only: the 1/65535 WEIGHTS_n
  // Volume against the input's own and dual-quaternion skinning, with the WEIGHTS_n written.
  DeformationQuality quality;
  ResponseFitReport fit;  // parameters == 0 when nothing was fitted
  MuscleMotion motion = MuscleMotion::kRuntime;
  bool helper_joints = false;
  std::vector<JiggleSetup> jiggles;  // as baked (for the extension)
};

// Wall-clock seconds of the bake's stages, for bench/ only (never written into outputs).
struct BakeTimings {
  double evaluate = 0.0;  // sampling every clip and evaluating the muscle joints
  double weights = 0.0;   // muscle weights, smoothing, pruning and rounding
  double fit = 0.0;       // fitting the muscles' response
  double pack = 0.0;      // glTF attributes and packed buffers
  // The one pass over every frame that skins each vertex once (pipeline/deformation_quality.h
  // measureDeformation()): the deformation-quality volumes and the deformation error in single precision.
  double quality = 0.0;
  double error = 0.0;     // each clip's largest deformation error, recomputed in double where it could be
};

// Throws Error MUSCLES_MISMATCH when a muscle does not fit the skeleton, InvalidOption (core/error.h) naming
// the BakeOptions field ("influences", "fps") for a bad option.
BakeResult bakeCharacter(const Character& character, const MuscleSet& muscles, const BakeOptions& options,
                         BakeTimings* timings = nullptr);

std::string muscleJointName(const MusclePart& part, MuscleJointRole role);

}  // namespace rigbake
