// The checks of `rigbake validate`: plain functions from a loaded baked character (plus its landmarks,
// its muscle set and what formats/baked_gltf.h decoded from the file, pipeline/baked_file.h) to a Report
// of issues with stable codes, a severity, a threshold and the measured value (pipeline/check_report.h),
// in the manner of the Khronos glTF-Validator (every check runs; none stops at the first problem). The
// report also carries the data its plots draw. docs/validate.md lists every code with its default
// threshold (pipeline/check_registry.h). The checks live in pipeline/muscle_checks.cpp (landmarks,
// locators, muscle lengths, jiggles, muscle skin), pipeline/skin_checks.cpp (influences, deformation
// quality) and pipeline/checks.cpp (the file's structure, and the run of them all); the plot data in
// pipeline/report_figures.cpp.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "pipeline/baked_file.h"
#include "pipeline/check_registry.h"
#include "pipeline/check_report.h"
#include "pipeline/pose.h"

namespace rigbake {

// The reason the muscle checks give when ValidationInputs::muscles is null, in the report's own words;
// `rigbake validate` prints the flag that gives one beside it on stderr (cli/ knows the flag, the
// report does not: build's reports come from a manifest).
inline constexpr const char* kNoMuscleFile = "no muscle file given";

struct ValidationInputs {
  std::string character_name;
  const Character* character = nullptr;
  const LandmarkSet* landmarks = nullptr;  // nullptr when they did not resolve
  std::string landmark_problem;            // the resolver's message when they did not
  const MuscleSet* muscles = nullptr;      // nullptr: no muscle file given (the muscle checks skip, kNoMuscleFile)
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
// `clips`: the jiggles baked into the clips, else the extension's run by the runtime library
// (simulateFileJiggles()), whose `refused` ones fail.
CheckResult checkJiggleWithinClamp(const ValidationInputs& inputs, const std::vector<ClipJiggles>& clips,
                                   const std::vector<FileIssue>& refused, const ValidationConfig& config);
CheckResult checkWeightsSum(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkWeightsNonNegative(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkJointIndexInRange(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkInfluenceCount(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkPackedDeformationError(const ValidationInputs& inputs, const std::vector<ClipDeformation>& per_clip,
                                        const ValidationConfig& config);
CheckResult checkRegionVolumeLoss(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkSeamOpening(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkRoughnessRise(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkStrain(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkBodyVolume(const ValidationInputs& inputs, const ValidationConfig& config);
CheckResult checkOccupiedVolume(const ValidationInputs& inputs, const ValidationConfig& config);
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
