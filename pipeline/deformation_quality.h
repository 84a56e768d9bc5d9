// How well skinning keeps the body's volume, the figure the muscles exist for (docs/deformation-
// quality.md): for every clip, the volume of the whole skinned surface and of each body region against
// the bind pose, for (a) the input's own linear blend skinning, (b) dual-quaternion skinning of the
// input weights, the reference riggers compare with, and (c) the baked rig; and for every muscle, at
// its most compressed and most stretched sample, how far the skin it drives moves along the surface
// normal relative to (a): a bulge out or a deflation in.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/deformation_error.h"
#include "pipeline/influences.h"
#include "pipeline/quantize_for_motion.h"
#include "pipeline/region_loss_place.h"
#include "pipeline/skin_volume.h"

namespace rigbake {

// One sampled clip as the measures see it: skin matrices of the skeleton's joints followed by the
// muscles' skinned joints, and each muscle's clamped length ratio, per sampled time.
struct MeasuredClip {
  std::string name;
  std::vector<double> times;
  const std::vector<SkinFrame>* frames = nullptr;
  std::vector<std::vector<double>> ratio;  // ratio[t][m], clamped
};

// A skinned mesh part and its three weight sets (skeleton indices; the muscles' skinned joints follow
// the skeleton's joints, muscle m at skeleton.size() + m).
struct MeasuredPart {
  int mesh_part = -1;
  InfluenceSet input;  // the input's weights, normalized
  InfluenceSet rig;    // the weights written (muscles included)
};

// The point single-precision skinning of `parts` is done about (pipeline/skinning_batch.h): the middle
// of their vertices' bounding box, so that the rounding is relative to the body's size, not to its
// distance from the scene origin (the origin when there are no finite positions).
Eigen::Vector3d skinCentre(const Character& character, const std::vector<MeasuredPart>& parts);

// The volume change V(t) / V(bind) - 1 with the largest magnitude over a clip, and when.
struct VolumeExtreme {
  double change = 0.0;
  double time = 0.0;
};

struct SkinningVolumes {
  VolumeExtreme input, dual_quaternion, rig;
};

// How much more of its volume a body region loses under the rig than under the input skinning, in
// percent points: max(0, min(input change, 0) - rig change) (a region growing is not a loss). What
// validate's SKIN_REGION_VOLUME_LOSS judges and bake's region line names.
inline double regionLossBeyondInput(const SkinningVolumes& v) {
  return std::max(0.0, 100.0 * (std::min(v.input.change, 0.0) - v.rig.change));
}

// Skin vertices that share a bind position, their largest separation over a clip (pipeline/
// seam_opening.h), in scene units; measured only where DeformationQuality::seam_places > 0.
struct SeamOpening {
  double input = 0.0;  // the input's weights, linear blend: 0 wherever the input gave a place one skin
  double rig = 0.0;    // the weights written, with the muscle joints
  double time = 0.0;   // when the rig's peaks
};

// The skin's smoothness and the centre-of-rotation yardstick over a clip (pipeline/surface_figures.h),
// at its most deformed samples (surfaceSamples()). Skinnings in the order input (linear blend), dual
// quaternions, centres of rotation, rig.
constexpr int kSurfaceSkinnings = 4;
// The body height at which rigbake's length constants are stated: the fit's length weights
// (pipeline/response_fit.h) and the roughness floor below. At another height they scale with it, as the
// presets' offsets do (anatomy/presets.h reference_height), so that a character's unit changes nothing.
constexpr double kReferenceBodyHeight = 1.8;
// Below these a clip's plain skinning is as smooth (a roughness rise of 0.01 mm on a body
// kReferenceBodyHeight tall, in proportion on any other) or as unstretched (a fraction of strain) as its
// bind pose, and a ratio to it says nothing: ratios of the rig's figure to plain skinning's (validate's
// checks, bake's lines) take plain skinning's as at least these.
constexpr double kRoughnessFloorPerHeight = 1e-5 / kReferenceBodyHeight;
constexpr double kStrainFloor = 0.01;
struct SurfaceFigures {
  bool measured = false;
  // kRoughnessFloorPerHeight times the body's height, scene units.
  double roughness_floor = 0.0;
  // The 95th percentile, over the skin that moves, of each welded vertex's roughness rise over the bind
  // pose (|umbrella Laplacian . normal| posed minus bind), scene units; the largest over the samples.
  double roughness_rise[kSurfaceSkinnings] = {0.0, 0.0, 0.0, 0.0};
  // Strain of the same skin, as fractions: the 95th percentile of |posed / bind - 1| of the areas of the
  // welded surface's triangles that have a corner in the skin that moves, and of their edges' lengths
  // (each triangle's three, so an edge inside the surface counts once per side); the largest over the
  // samples.
  double edge_strain[kSurfaceSkinnings] = {0.0, 0.0, 0.0, 0.0};
  double area_strain[kSurfaceSkinnings] = {0.0, 0.0, 0.0, 0.0};
  VolumeExtreme centre_of_rotation;  // the whole body's volume change, centres of rotation
  LumpPlace lumpiest;
  // The whole body's change of occupied volume (pipeline/occupied_volume.h: each point inside the skin
  // counted once, so skin pushed through opposing skin keeps nothing), per skinning as roughness_rise;
  // the largest over the same samples.
  VolumeExtreme occupied[kSurfaceSkinnings];
};

// The rig's figure over plain skinning's (kSurfaceSkinnings order), plain skinning's taken as at least
// `floor`; and the two ratios validate's SKIN_ROUGHNESS_RISE and SKIN_STRAIN judge a clip by (strain: the
// larger of the edges' and the triangles').
inline double rigOverPlain(const double (&figure)[kSurfaceSkinnings], double floor) {
  return figure[3] / std::max(figure[0], floor);
}
inline double roughnessRatio(const SurfaceFigures& f) { return rigOverPlain(f.roughness_rise, f.roughness_floor); }
inline double strainRatio(const SurfaceFigures& f) {
  return std::max(rigOverPlain(f.edge_strain, kStrainFloor), rigOverPlain(f.area_strain, kStrainFloor));
}

// Opposing skin at a crease (pipeline/crease_contact.h), one skinning at the crease's peak bend.
struct CreaseMethodContact {
  bool opposed = false;  // some skin faces skin across the crease within reach
  double closest = 0.0;  // scene units: the closest approach of opposing skin (when opposed)
  int through = 0;       // skin vertices behind the opposing skin's surface
  double deepest = 0.0;  // scene units: how far the deepest of them is behind it
};
// One crease of one clip: the sample where its bend peaks, and the four skinnings' contact there
// (input, dual quaternions, centres of rotation, rig, as SurfaceFigures).
struct CreaseContact {
  std::string crease;
  double time = 0.0;
  double bend = 0.0;  // radians: the distal joint's turn relative to the proximal one since bind
  CreaseMethodContact skinning[kSurfaceSkinnings];
};

// One joint region of one clip (pipeline/joint_regions.h), at the sample where the rig loses most
// beyond plain skinning: the two volume changes against the bind pose (fractions) and the loss.
struct JointRegionLoss {
  double input = 0.0, rig = 0.0;
  double loss = 0.0;  // max(0, min(input, 0) - rig)
  double time = 0.0;
};

struct ClipQuality {
  std::string clip;
  SkinningVolumes body;
  SeamOpening seams;
  SurfaceFigures surface;
  std::vector<CreaseContact> creases;  // the creases this clip bends at least kMinCreaseBend
  std::vector<SkinningVolumes> regions;  // DeformationQuality::regions order
  // Per region (same order): where the rig takes most of the region's volume against plain skinning at
  // the rig's extreme sample (pipeline/region_loss_place.h); measured only where the region loses
  // beyond plain skinning (regionLossBeyondInput() > 0), at.found = false elsewhere.
  std::vector<RegionLossPlace> region_places;
  std::vector<JointRegionLoss> joint_regions;  // DeformationQuality::joint_regions order
  int worst_frame = -1;  // the sample where the rig's whole-body change peaks
};

// Skin moved by one muscle at one sample, along the input skinning's surface normal: positive out.
struct MuscleSkinMove {
  bool measured = false;  // false when the muscle never reaches that side of rest, or drives no skin
  std::string clip;
  double time = 0.0;
  double ratio = 1.0;
  double mean = 0.0;      // metres, weighted by the muscle's skin weight
  double max_out = 0.0;   // metres, the largest outward move (>= 0)
  double max_in = 0.0;    // metres, the largest inward move (>= 0)
  int vertices = 0;       // vertices with at least kMuscleSkinWeight of the muscle
};

struct MuscleQuality {
  std::string muscle;
  PartKind kind = PartKind::kMuscle;  // a corrective's skin may move either way; the muscle checks skip it
  MuscleSkinMove compressed, stretched;
};

// A vertex counts as driven by a muscle from this skin weight up.
constexpr double kMuscleSkinWeight = 0.05;

// A welded vertex of a muscle's skin and the muscle's weight there.
struct MuscleSkinVertex {
  int welded = -1;
  double weight = 0.0;
};

// Per muscle m (joint joint_count + m of `rig`), the welded vertices (vertex_of_weld: welded -> vertex
// of `rig`) with at least kMuscleSkinWeight of it, ascending, and that weight summed over the vertex's
// slots in slot order: a muscle's skin as the figures, the fit and the pictures take it.
std::vector<std::vector<MuscleSkinVertex>> muscleSkin(const InfluenceSet& rig, const std::vector<int>& vertex_of_weld,
                                                      int joint_count, int muscle_count);

struct DeformationQuality {
  double body_volume = 0.0;  // bind pose, cubic scene units
  std::vector<std::string> regions;
  std::vector<double> region_volumes;  // bind pose
  // Regions whose closed piece is too flat to measure (pipeline/skin_volume.h kMinRegionCompactness).
  std::vector<std::string> unmeasured_regions;
  std::vector<ClipQuality> clips;
  std::vector<MuscleQuality> muscles;
  // Joints whose skin is measured as a joint region (pipeline/joint_regions.h), by name.
  std::vector<std::string> joint_regions;
  int seam_places = 0;  // places where skinned vertices share a bind position (pipeline/seam_opening.h)
};

// Frames are measured on `threads` threads (pipeline/parallel.h); the figures are the same at any count.
DeformationQuality measureDeformationQuality(const Character& character, const std::vector<BodyRegion>& regions,
                                             const std::vector<MeasuredPart>& parts, const MuscleSet& muscles,
                                             const std::vector<MeasuredClip>& clips, int threads = 1);

// Rounded weights to measure in the same pass: how far `approximation` moves each vertex from where
// `reference` skins it (pipeline/deformation_error.h), for one part.
struct ErrorWeights {
  const InfluenceSet* reference = nullptr;
  const InfluenceSet* approximation = nullptr;
};

// One frame's skinningDeformationError() of one part, from single-precision skinning: max_displacement
// and rms_displacement are within `bound` of the double figures, and max_vertex is the double figure's
// unless another vertex comes within 2 * bound of it.
struct ScreenedError {
  DeformationError error;
  double bound = 0.0;
};

struct DeformationMeasures {
  DeformationQuality quality;  // empty unless asked for
  // screened[a][f][p]: approximation a, frame f (every clip's frames in clip order), part p.
  std::vector<std::vector<std::vector<ScreenedError>>> screened;
};

// One pass over every frame of every clip that skins each vertex once per frame (pipeline/
// skinning_batch.h) for both measures: the deformation quality when `quality` is set (as
// measureDeformationQuality()), and the error of each errors[a] (one ErrorWeights per part, in
// `parts` order; at most two approximations).
DeformationMeasures measureDeformation(const Character& character, const std::vector<BodyRegion>& regions,
                                       const std::vector<MeasuredPart>& parts, const MuscleSet& muscles,
                                       const std::vector<MeasuredClip>& clips, bool quality,
                                       const std::vector<std::vector<ErrorWeights>>& errors, int threads);

}  // namespace rigbake
