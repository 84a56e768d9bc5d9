// The checks of `rigbake validate`: plain functions from a loaded baked character (plus its landmarks,
// its muscle set and what formats/baked_gltf.h decoded from the file) to a Report of issues with stable
// codes, a severity, a threshold and the measured value, in the manner of the Khronos glTF-Validator
// (every check runs; none stops at the first problem). The report also carries the data its plots
// draw. docs/validate.md lists every code with its default threshold.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/jiggle.h"
#include "pipeline/memory_table.h"
#include "pipeline/pack_influences.h"
#include "pipeline/pose.h"
#include "pipeline/render.h"
#include "runtime/muscle_rig.h"

namespace rigbake {

enum class Severity { kError, kWarning, kInfo };
enum class CheckStatus { kPass, kFail, kSkipped };
// How the measured value must relate to the threshold for the check to pass.
enum class Comparison { kAtMost, kAtLeast };

const char* severityName(Severity severity);  // "error", "warning", "info"
const char* statusName(CheckStatus status);   // "pass", "fail", "skipped"
// False when `name` is not one of severityName()'s results.
bool parseSeverity(const std::string& name, Severity* severity);

// A check's code, what it measures and its defaults; the table docs/validate.md documents.
struct CheckDefinition {
  const char* code;
  Severity severity;
  double threshold;
  Comparison comparison;
  const char* unit;   // of threshold and measured value
  const char* title;  // what it measures, one line
};

// Every check, in report order. Codes are never renamed or reused.
const std::vector<CheckDefinition>& checkDefinitions();
const CheckDefinition* findCheckDefinition(const std::string& code);  // nullptr when unknown

// Per-code overrides from a `--config` file (formats/report_json.h reads it).
struct ValidationConfig {
  std::map<std::string, Severity> severity;
  std::map<std::string, double> threshold;
};

// One offending (or, for a passing check, the worst) item of a check.
struct CheckFinding {
  std::string location;  // JSON pointer into the glTF, or a muscle / landmark name
  double measured = 0.0;
  std::string message;
};

struct CheckResult {
  std::string code;
  std::string title;
  Severity severity = Severity::kError;
  CheckStatus status = CheckStatus::kSkipped;
  Comparison comparison = Comparison::kAtMost;
  double threshold = 0.0;
  std::string unit;
  bool has_measured = false;
  double measured = 0.0;   // the worst value over everything the check looked at
  std::string location;    // where that worst value is
  std::string message;     // a one-line summary, or why the check was skipped
  std::vector<CheckFinding> findings;  // failing items first, worst first, at most kMaxFindings
};

constexpr int kMaxFindings = 20;

// ---- What formats/baked_gltf.h decodes from the file, beyond the Character ----

// A skinned primitive's influences exactly as the file stores them, with skin-local joint indices.
struct FileSkinAttributes {
  int mesh_part = -1;   // index into Character::meshes
  std::string pointer;  // "/meshes/M/primitives/P"
  int skin_joint_count = 0;
  int slots = 0;                // 4 per JOINTS_n/WEIGHTS_n pair
  std::vector<int> joints;      // every slot, zero-weight ones too: joints[v * slots + k]
  std::vector<double> weights;  // as decoded (normalized integers mapped to [0, 1])
  bool has_packed = false;      // the _RIGBAKE_PACKED_* carrier attributes were present and decodable
  bool carries_packed = false;  // some _RIGBAKE_PACKED_* attribute is present, decodable or not
  PackedInfluences packed;      // skin-local indices; joint_count = skin_joint_count
};

// A muscle joint node the bake added, from its extras {"rigbake": {...}}.
struct FileMuscleNode {
  int node = -1;
  std::string name;
  std::string muscle;  // e.g. LeftBicep
  std::string role;    // base, tip, driver, skinned
  std::string origin_joint;
  std::string insertion_joint;
  std::string carrier_joint;  // "" when the file does not say
  double compression = 0.0;
  double stretch = 0.0;
};

struct FileIssue {
  std::string pointer;
  std::string message;
};

// A node that is one of the bake's muscle joints by its name (pipeline/bake.h muscleJointName(): the
// suffixes _muscleSkinned, _muscleBase, _muscleTip, _muscleDriver) or by its extras.rigbake: what is left
// of the rig when a tool that does not know rigbake drops the extension (gltfpack drops extras too,
// and keeps names).
struct FileMuscleJoint {
  int node = -1;
  std::string name;
  int animations_moving_it = 0;  // animations with a channel that targets the node
};

// A baked jiggle's angle from its animated direction and its cone's half-angle in that direction,
// degrees, at each sample time, as the bake recorded them in the animation's extras (the animated
// direction itself is no longer in the file once the jiggle replaced the channels).
struct JiggleSeries {
  std::string joint;
  std::string host;  // "joint" or "muscle"
  std::vector<double> angle_deg;
  std::vector<double> clamp_deg;
};

struct ClipJiggles {
  std::string clip;
  std::string pointer;  // "/animations/A/extras/rigbake"
  std::vector<double> times;
  std::vector<JiggleSeries> jiggles;
};

// A jiggle the extension leaves to the runtime (a default bake with --jiggle), on the loaded skeleton:
// setup.joint is the jiggling node's joint, setup.root its rootNode's (-1: model space), setup.name its
// name; axes, length and parameters as stored (not checked: jiggleSetupProblem says what is wrong).
struct FileJiggle {
  JiggleSetup setup;
  int parent = -1;  // parentNode's joint, -1: model space
  int muscle = -1;  // the rig muscle whose skinned node jiggles, -1 for a skeleton joint
  std::string pointer;  // "/extensions/RIGBAKE_muscle_rig/jiggles/i"
};

// The RIGBAKE_muscle_rig extension as read (formats/muscle_rig_extension.h): the rig in terms of the
// loaded skeleton's joints, and which joint each muscle's skinned node is.
struct FileMuscleRig {
  bool present = false;
  runtime::MuscleRig<double> rig;
  std::vector<std::string> names;
  std::vector<int> skinned_joint;
  std::vector<PartKind> kinds;
  std::vector<FileJiggle> jiggles;
  std::vector<std::string> problems;
};

struct BakedFileData {
  std::vector<FileSkinAttributes> skins;
  FileMuscleRig rig;
  std::vector<ClipJiggles> jiggles;
  std::vector<FileMuscleNode> muscle_nodes;
  std::vector<FileMuscleJoint> muscle_joints;  // by name or extras, in node order
  int animations = 0;                          // the file's animations
  std::vector<FileIssue> structure;  // structural problems found while reading
};

// The Khronos glTF-Validator's verdict on the file, when it ran.
struct ExternalValidation {
  bool ran = false;
  std::string skip_reason;
  int errors = 0;
  int warnings = 0;
  std::vector<FileIssue> issues;  // "CODE: message" per issue, errors first
};

// ---- Plot data ----

// Positions in the body's frame (anatomy/landmarks.h BodyFrame) relative to its midline: x towards the
// character's left, y up, z forward. Front view draws (x, y), side view (z, y).
struct FigureSegment {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
};

struct FigureMuscle {
  std::string name;   // LeftBicep
  std::string group;  // Arms
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d driver = Eigen::Vector3d::Zero();
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero();
  bool flagged = false;  // a locator of this muscle failed LOCATOR_NEAR_SURFACE or LOCATOR_SYMMETRY
};

struct FigureLandmark {
  std::string name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

// A silhouette as filled runs of a grid: cells [begin, end) of row `row`, row 0 at the bottom.
struct Silhouette {
  double min_u = 0.0, min_v = 0.0;  // body-frame coordinates of the grid's lower left corner
  double cell = 0.0;                // cell size, scene units
  int columns = 0, rows = 0;
  std::vector<std::array<int, 3>> runs;  // {row, begin, end}
};

struct Figure {
  double height = 0.0;  // body height, scene units
  Silhouette front;     // (x, y)
  Silhouette side;      // (z, y)
  std::vector<FigureSegment> bones;
  std::vector<FigureLandmark> landmarks;
  std::vector<FigureMuscle> muscles;
};

struct MuscleRatioSeries {
  std::string muscle;
  std::string group;
  double compression = 0.0;
  double stretch = 0.0;
  std::vector<double> ratio;  // unclamped L / L_rest at each of the clip's times
};

struct ClipRatios {
  std::string clip;
  std::vector<double> times;
  std::vector<MuscleRatioSeries> muscles;
};

struct ClipDeformation {
  std::string clip;
  int samples = 0;
  double max_displacement = 0.0;  // scene units
  double rms_displacement = 0.0;
};

// Deformation quality of the file (pipeline/baked_quality.h). A picture: the input skinning and the
// baked rig side by side at one sample, framed on one part of the body.
struct QualityPicture {
  std::string title;    // what is shown: a clip's worst region or a muscle at its peak compression
  std::string clip;
  double time = 0.0;
  std::string subject;  // the region or muscle framed
  double scale = 0.0;   // scene units at full heatmap colour
  double max_out = 0.0, max_in = 0.0;  // displacement of the rig along the input's normal, scene units
  // One image: input skinning | baked rig | heatmap of the rig's displacement (red out, blue in), or
  // for a crease the four skinnings side by side (`panels` names them, `note` has the crease's figures).
  RgbImage image;
  std::string panels = "input | rig | move";
  std::string note;
};

struct BakedQuality {
  bool measured = false;
  std::string skip_reason;  // when not measured
  DeformationQuality quality;
  std::vector<QualityPicture> pictures;
};

struct Report {
  std::string character;  // file name without directories
  int joints = 0;
  int vertices = 0;       // skinned vertices
  int muscles = 0;        // muscle parts checked (0 without --muscles)
  int influences = 0;     // packed influence count of the bake, 0 when the file has no packed data
  std::vector<CheckResult> checks;
  Figure figure;
  std::vector<ClipRatios> ratios;
  std::vector<std::int64_t> influence_histogram;  // [n] = vertices with n non-zero influences
  std::vector<ClipDeformation> deformation;
  std::vector<SkinLayoutSize> memory;
  // Baked into the clips (read from their extras), else the extension's runtime jiggles evaluated over
  // the file's clips (pipeline/file_jiggle.h); empty when the bake had no --jiggle.
  std::vector<ClipJiggles> jiggles;
  BakedQuality quality;              // measured = false without muscle joints or landmarks

  // True when every check at error severity passed or was skipped.
  bool passed() const;
};

// ---- Inputs and checks ----

struct ValidationInputs {
  std::string character_name;
  const Character* character = nullptr;
  const LandmarkSet* landmarks = nullptr;  // nullptr when they did not resolve
  std::string landmark_problem;            // the resolver's message when they did not
  const MuscleSet* muscles = nullptr;      // nullptr without --muscles
  const BakedFileData* file = nullptr;
  const BakedQuality* quality = nullptr;  // nullptr: not measured (the checks say why)
  ExternalValidation khronos;
  int threads = 1;  // for the per-frame measures (pipeline/parallel.h); every figure is the same at any count
};

// The extension's runtime jiggles (FileMuscleRig::jiggles, what a default bake with --jiggle writes)
// simulated over the file's clips the way an engine runs them: the runtime's MuscleRigJob moves a
// muscle's skinned joint, its JiggleJob steps the jiggle at 240 Hz (pipeline/jiggle.h
// simulateJiggleFrames), at every key time of each clip. A jiggle the runtime would refuse (a cone
// wider than 90 degrees, axes not unit or not perpendicular, a muscle of a malformed rig) is not run
// and is listed in `refused` with the reason.
struct RuntimeJiggles {
  std::vector<ClipJiggles> clips;  // pointer: the extension's jiggles
  std::vector<FileIssue> refused;
};
RuntimeJiggles simulateFileJiggles(const Character& character, const FileMuscleRig& rig);

// Every check of checkDefinitions(), in that order, plus the plot data.
Report validateBakedCharacter(const ValidationInputs& inputs, const ValidationConfig& config);

// The individual checks; each returns a result with the code's effective severity and threshold.
CheckResult checkLandmarksResolved(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkLocatorSymmetry(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkLocatorNearSurface(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkMuscleRatioInRange(const ValidationInputs& inputs, const std::vector<ClipRatios>& ratios,
                                    const ValidationConfig& config);
CheckResult checkWeightsSum(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkWeightsNonNegative(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkJointIndexInRange(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkInfluenceCount(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkPackedDeformationError(const ValidationInputs& inputs, const std::vector<ClipDeformation>& per_clip,
                                        const ValidationConfig& config);
CheckResult checkRegionVolumeLoss(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkSeamOpening(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkRoughnessRise(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkBodyVolume(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkMuscleBulgeOutward(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkMuscleStretchNoHollow(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkRigExtensionMissing(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkInfluencesTruncated(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkGltfStructure(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkKhronosValidator(const ValidationInputs& inputs, const ValidationConfig& config);

// Muscle joints of the file that nothing drives: all of them that no channel moves in every animation,
// when the file has no RIGBAKE_muscle_rig extension; 0 when it has (RIG_EXTENSION_MISSING's measure,
// and why `rigbake view` refuses a file).
int undrivenMuscleJoints(const BakedFileData& file);

// Plot data (and inputs of the checks above that take them).
std::vector<ClipRatios> muscleRatiosOverClips(const Character& character, const MuscleSet& muscles);
std::vector<std::int64_t> influenceHistogram(const BakedFileData& file);
// Skins every vertex with the packed weights and with the file's standard weights at every sample time
// of every clip (the clip's key times) and measures the displacement between them.
// On `threads` threads (pipeline/parallel.h: 0 one per core); the same figures at any count.
std::vector<ClipDeformation> packedDeformationPerClip(const Character& character, const BakedFileData& file, int threads = 1);
Figure bodyFigure(const Character& character, const LandmarkSet& landmarks, const MuscleSet* muscles);

// The skin matrices of a baked file's skeleton for a pose (joint world * inverse bind), with each
// muscle's skinned joint evaluated by the runtime rig when the file carries the extension: what an
// engine running the rig skins with.
std::vector<Eigen::Affine3d> bakedSkinMatrices(const Character& character, const BakedFileData& file, const Pose& pose);

}  // namespace rigbake
