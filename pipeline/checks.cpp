// The checks of `rigbake validate`. Organised like the Khronos glTF-Validator (stable issue codes with
// a default severity, every check always runs, each result says where): a CI job can gate on error
// severity and keep the warnings as a trend. This file holds the checks of the file itself (its
// structure, the Khronos validator's verdict, a rig or influences a tool stripped) and the run of every
// check in the registry's order (pipeline/check_registry.h); the muscle checks are
// pipeline/muscle_checks.cpp, the skin checks pipeline/skin_checks.cpp, the plot data
// pipeline/report_figures.cpp.
#include "pipeline/checks.h"

#include <algorithm>
#include <cassert>

#include "pipeline/check_support.h"
#include "pipeline/influences.h"

namespace rigbake {

const char* severityName(Severity severity) {
  switch (severity) {
    case Severity::kError: return "error";
    case Severity::kWarning: return "warning";
    case Severity::kInfo: return "info";
  }
  return "error";
}

const char* statusName(CheckStatus status) {
  switch (status) {
    case CheckStatus::kPass: return "pass";
    case CheckStatus::kFail: return "fail";
    case CheckStatus::kSkipped: return "skipped";
  }
  return "fail";
}

bool parseSeverity(const std::string& name, Severity* severity) {
  for (Severity s : {Severity::kError, Severity::kWarning, Severity::kInfo}) {
    if (name == severityName(s)) {
      *severity = s;
      return true;
    }
  }
  return false;
}

bool Report::passed() const {
  for (const CheckResult& check : checks) {
    if (check.severity == Severity::kError && check.status == CheckStatus::kFail) return false;
  }
  return true;
}

static bool drivenByChannels(const BakedFileData& file, const FileMuscleJoint& joint) {
  return file.animations > 0 && joint.animations_moving_it == file.animations;
}

int undrivenMuscleJoints(const BakedFileData& file) {
  if (file.rig.present) return 0;
  int undriven = 0;
  for (const FileMuscleJoint& joint : file.muscle_joints) undriven += drivenByChannels(file, joint) ? 0 : 1;
  return undriven;
}

CheckResult checkRigExtensionMissing(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("RIG_EXTENSION_MISSING")>(), config);
  const BakedFileData& file = *inputs.file;
  if (file.muscle_joints.empty()) return skippedCheck(result, "the file has no muscle joints (by name or extras.rigbake)");
  const int joints = static_cast<int>(file.muscle_joints.size());
  result.has_measured = true;
  if (file.rig.present) {
    result.status = CheckStatus::kPass;
    result.message = std::to_string(joints) + " muscle joints, driven by the RIGBAKE_muscle_rig extension";
    return result;
  }
  // Without the extension only channels move a muscle joint: a sampled bake animates every one of them
  // in every clip; a runtime bake that lost its extension animates none.
  const int undriven = undrivenMuscleJoints(file);
  for (const FileMuscleJoint& joint : file.muscle_joints) {
    if (drivenByChannels(file, joint)) continue;
    if (result.findings.size() < static_cast<size_t>(kMaxFindings))
      result.findings.push_back({"/nodes/" + std::to_string(joint.node), 1.0,
                                 joint.name + ": no RIGBAKE_muscle_rig, channels in " +
                                     std::to_string(joint.animations_moving_it) + " of " +
                                     std::to_string(file.animations) + " animations"});
  }
  result.measured = undriven;
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  if (undriven == 0) {
    result.message = std::to_string(joints) + " muscle joints, every one animated in every clip (a sampled bake)";
    return result;
  }
  result.location = result.findings.front().location;
  result.message = std::to_string(undriven) + " of " + std::to_string(joints) +
                   " muscle joints without RIGBAKE_muscle_rig or channels: the rig was stripped (gltfpack and "
                   "glTF-Transform without rigbake's config drop it; docs/pipelines.md)";
  return result;
}

CheckResult checkInfluencesTruncated(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("INFLUENCES_TRUNCATED")>(), config);
  bool any_packed = false;
  for (const FileSkinAttributes& skin : inputs.file->skins) any_packed = any_packed || skin.has_packed;
  if (!any_packed) return skippedCheck(result, "the file has no decodable _RIGBAKE_PACKED_* attributes to compare with");
  CheckMeasurement measurement(&result);
  int total = 0;
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    const int count = skin.slots ? static_cast<int>(skin.weights.size()) / skin.slots : 0;
    // An index out of range stops the decoder; JOINT_INDEX_IN_RANGE reports it.
    if (!skin.has_packed || skin.packed.vertex_count != count || !packedInfluencesProblem(skin.packed).empty()) continue;
    const QuantizedInfluences packed = unpackInfluences(skin.packed);
    int truncated = 0, worst_vertex = -1, worst_packed = 0, worst_standard = 0;
    for (int v = 0; v < count; ++v) {
      int in_packed = 0, in_standard = 0;
      for (int k = 0; k < packed.slots_per_vertex; ++k)
        in_packed += packed.weights[static_cast<size_t>(v) * packed.slots_per_vertex + k] != 0;
      for (int k = 0; k < skin.slots; ++k) in_standard += skin.weights[static_cast<size_t>(v) * skin.slots + k] != 0.0;
      if (in_standard >= in_packed) continue;
      ++truncated;
      if (worst_vertex < 0 || in_packed - in_standard > worst_packed - worst_standard) {
        worst_vertex = v;
        worst_packed = in_packed;
        worst_standard = in_standard;
      }
    }
    total += truncated;
    measurement.add(truncated, skin.pointer + "/attributes",
                    "packed buffers hold " + std::to_string(skin.packed.influences) + " influences, JOINTS_n/WEIGHTS_n " +
                        std::to_string(skin.slots) + " slots" +
                        (truncated ? "; vertex " + std::to_string(worst_vertex) + " has " + std::to_string(worst_packed) +
                                         " packed and " + std::to_string(worst_standard) + " in WEIGHTS_n"
                                   : std::string()));
  }
  if (!result.has_measured) return skippedCheck(result, "no packed primitive has as many vertices as its WEIGHTS_n");
  measurement.finish(total == 0 ? "every vertex keeps in WEIGHTS_n the influences its packed buffers hold"
                                : std::to_string(total) + " vertices have fewer influences in JOINTS_n/WEIGHTS_n than "
                                  "in the packed buffers: a tool cut them (gltfpack keeps 4, glTF-Transform's optimize without "
                                  "rigbake's config stores 8-bit weights; docs/pipelines.md)");
  return result;
}

CheckResult checkGltfStructure(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("GLTF_STRUCTURE")>(), config);
  std::vector<FileIssue> issues = inputs.file->structure;
  // Muscles the --muscles file names must all have been baked into this file (their skinned joints;
  // the helpers are optional, bake --helper-joints).
  if (inputs.muscles) {
    static const char* kRoles[] = {"skinned"};
    for (const MusclePart& part : inputs.muscles->parts) {
      for (const char* role : kRoles) {
        bool found = false;
        for (const FileMuscleNode& node : inputs.file->muscle_nodes) {
          found = found || (node.muscle == part.fullName() && node.role == role);
        }
        if (!found)
          issues.push_back({"/nodes", "muscle " + part.fullName() + " of the muscle file has no " + role +
                                          " joint node in the baked file"});
      }
    }
  }
  result.has_measured = true;
  result.measured = static_cast<double>(issues.size());
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  for (const FileIssue& issue : issues) {
    if (result.findings.size() >= static_cast<size_t>(kMaxFindings)) break;
    result.findings.push_back({issue.pointer, 1.0, issue.message});
  }
  if (!issues.empty()) result.location = issues.front().pointer;
  result.message = std::to_string(inputs.file->skins.size()) + " skinned primitives, " +
                   std::to_string(inputs.file->muscle_nodes.size()) + " muscle joint nodes, " +
                   std::to_string(issues.size()) + " structural issues";
  return result;
}

CheckResult checkKhronosValidator(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("KHRONOS_VALIDATOR")>(), config);
  if (!inputs.khronos.ran) return skippedCheck(result, inputs.khronos.skip_reason);
  result.has_measured = true;
  result.measured = inputs.khronos.errors;
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  for (const FileIssue& issue : inputs.khronos.issues) {
    if (result.findings.size() >= static_cast<size_t>(kMaxFindings)) break;
    result.findings.push_back({issue.pointer, 1.0, issue.message});
  }
  result.message = std::to_string(inputs.khronos.errors) + " errors, " + std::to_string(inputs.khronos.warnings) +
                   " warnings";
  return result;
}

Report validateBakedCharacter(const ValidationInputs& inputs, const ValidationConfig& config) {
  assert(inputs.character && inputs.file);
  const Character& character = *inputs.character;
  const BakedFileData& file = *inputs.file;
  Report report;
  report.character = inputs.character_name;
  report.joints = character.skeleton.size();
  for (const FileSkinAttributes& skin : file.skins) {
    report.vertices += static_cast<int>(character.meshes[skin.mesh_part].positions.size());
    if (skin.has_packed) report.influences = std::max(report.influences, skin.packed.influences);
  }
  report.muscles = inputs.muscles ? static_cast<int>(inputs.muscles->parts.size()) : 0;
  if (inputs.muscles) report.ratios = muscleRatiosOverClips(character, *inputs.muscles);
  report.deformation = packedDeformationPerClip(character, file, inputs.threads);
  report.influence_histogram = influenceHistogram(file);
  report.memory = skinMemoryTable(report.vertices);
  // Jiggle baked into the clips, else the extension's, run by the runtime library.
  RuntimeJiggles runtime_jiggles;
  if (file.jiggles.empty() && !file.rig.jiggles.empty()) runtime_jiggles = simulateFileJiggles(character, file.rig);
  report.jiggles = file.jiggles.empty() ? runtime_jiggles.clips : file.jiggles;
  if (inputs.quality) report.quality = *inputs.quality;

  report.checks.push_back(checkLandmarksResolved(inputs, config));
  report.checks.push_back(checkLocatorSymmetry(inputs, config));
  report.checks.push_back(checkLocatorNearSurface(inputs, config));
  report.checks.push_back(checkMuscleRatioInRange(inputs, report.ratios, config));
  report.checks.push_back(checkWeightsSum(inputs, config));
  report.checks.push_back(checkWeightsNonNegative(inputs, config));
  report.checks.push_back(checkJointIndexInRange(inputs, config));
  report.checks.push_back(checkInfluenceCount(inputs, config));
  report.checks.push_back(checkPackedDeformationError(inputs, report.deformation, config));
  report.checks.push_back(checkJiggleWithinClamp(inputs, report.jiggles, runtime_jiggles.refused, config));
  report.checks.push_back(checkRegionVolumeLoss(inputs, config));
  report.checks.push_back(checkSeamOpening(inputs, config));
  report.checks.push_back(checkRoughnessRise(inputs, config));
  report.checks.push_back(checkStrain(inputs, config));
  report.checks.push_back(checkBodyVolume(inputs, config));
  report.checks.push_back(checkOccupiedVolume(inputs, config));
  report.checks.push_back(checkMuscleBulgeOutward(inputs, config));
  report.checks.push_back(checkMuscleStretchNoHollow(inputs, config));
  report.checks.push_back(checkRigExtensionMissing(inputs, config));
  report.checks.push_back(checkInfluencesTruncated(inputs, config));
  report.checks.push_back(checkGltfStructure(inputs, config));
  report.checks.push_back(checkKhronosValidator(inputs, config));
  assert(report.checks.size() == checkDefinitions().size());

  if (inputs.landmarks) {
    report.figure = bodyFigure(character, *inputs.landmarks, inputs.muscles);
    // Mark the muscles whose locators a locator check found over its threshold.
    for (const CheckResult& check : report.checks) {
      if (check.code != "LOCATOR_NEAR_SURFACE" && check.code != "LOCATOR_SYMMETRY") continue;
      for (const CheckFinding& finding : check.findings) {
        if (withinThreshold(check, finding.measured)) continue;
        const std::string muscle = finding.location.substr(0, finding.location.find('/'));
        for (FigureMuscle& m : report.figure.muscles) m.flagged = m.flagged || m.name == muscle;
      }
    }
  }
  return report;
}

}  // namespace rigbake
