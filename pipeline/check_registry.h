// The registry of `rigbake validate`'s checks: every code with its default severity, threshold and
// unit, in report order, as one constexpr table (the table docs/validate.md documents and `rigbake
// validate` runs in this order). A check names its code through checkAt<checkIndex("CODE")>(), so a
// code that is not in the table does not compile; the table's codes are checked unique when it compiles.
// Codes are never renamed or reused.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

#include "pipeline/check_report.h"

namespace rigbake {

// Thresholds relative to body height keep one default meaningful for a 1.2 m robot and a 1.9 m
// soldier, whatever the file's units.
inline constexpr std::array<CheckDefinition, 22> kCheckDefinitions = {{
    {"LANDMARKS_RESOLVED", Severity::kError, 0.0, Comparison::kAtMost, "landmarks",
     "Required canonical landmarks that match no joint and cannot be derived"},
    {"LOCATOR_SYMMETRY", Severity::kWarning, 0.02, Comparison::kAtMost, "x body height",
     "Largest distance between a left locator mirrored across the sagittal plane and its right twin"},
    {"LOCATOR_NEAR_SURFACE", Severity::kError, 0.1, Comparison::kAtMost, "x body height",
     "Largest distance from a muscle locator (origin, insertion, driver) to the body surface"},
    // A warning by default: past its band the skinned joint saturates, as the talk's clamp intends,
    // so the file is usable; a studio that wants every clip inside sets it to error in --config.
    {"MUSCLE_RATIO_IN_RANGE", Severity::kWarning, 0.0, Comparison::kAtLeast, "ratio",
     "Smallest margin of a muscle's length ratio inside [compression, stretch] over every clip sample"},
    {"WEIGHTS_SUM", Severity::kError, 0.001, Comparison::kAtMost, "weight",
     "Largest |sum of a vertex's WEIGHTS_n - 1|"},
    {"WEIGHTS_NON_NEGATIVE", Severity::kError, 0.0, Comparison::kAtLeast, "weight",
     "Smallest skin weight in WEIGHTS_n"},
    {"JOINT_INDEX_IN_RANGE", Severity::kError, 0.0, Comparison::kAtMost, "indices",
     "JOINTS_n and packed joint indices at or above the skin's joint count"},
    {"INFLUENCE_COUNT", Severity::kError, 10.0, Comparison::kAtMost, "influences",
     "Most non-zero influences on one vertex"},
    {"PACKED_DEFORMATION_ERROR", Severity::kError, 0.0005, Comparison::kAtMost, "m",
     "Largest displacement between skinning with the packed weights and with WEIGHTS_n, over every clip sample"},
    {"JIGGLE_WITHIN_CLAMP", Severity::kError, 1e-6, Comparison::kAtMost, "deg",
     "Largest amount by which a baked jiggle's angle exceeds its cone's half-angle, over every clip sample"},
    // Deformation quality (docs/deformation-quality.md), on the file's own clips and any --rom clips.
    {"SKIN_REGION_VOLUME_LOSS", Severity::kError, 1.0, Comparison::kAtMost, "points of volume",
     "Largest volume a body region loses under the baked rig beyond what the input skinning loses, per clip"},
    {"SKIN_SEAM_OPEN", Severity::kError, 0.05, Comparison::kAtMost, "mm",
     "Largest amount by which skin vertices sharing a bind position move apart under the rig beyond the input skinning, per clip"},
    {"SKIN_ROUGHNESS_RISE", Severity::kWarning, 1.2, Comparison::kAtMost, "x plain skinning's",
     "Largest ratio, per clip, of the rig's roughness rise over the bind pose (95th percentile of the moving skin) to the input skinning's"},
    {"SKIN_STRAIN", Severity::kWarning, 1.2, Comparison::kAtMost, "x plain skinning's",
     "Largest ratio, per clip, of the rig's edge-length or triangle-area strain (95th percentile of the moving skin) to the input skinning's"},
    {"SKIN_BODY_VOLUME", Severity::kWarning, 0.0, Comparison::kAtMost, "points of volume",
     "Largest amount by which the rig's whole-body volume change exceeds the input skinning's, per clip"},
    {"SKIN_OCCUPIED_VOLUME", Severity::kWarning, 0.0, Comparison::kAtMost, "points of volume",
     "Largest amount by which the rig's change of the space the skin occupies (each point once) exceeds the input skinning's, per clip"},
    {"MUSCLE_BULGE_OUTWARD", Severity::kWarning, -0.0005, Comparison::kAtLeast, "x body height",
     "Smallest mean move of a muscle's skin along the normal at its most compressed sample (positive: out)"},
    {"MUSCLE_STRETCH_NO_HOLLOW", Severity::kWarning, -0.001, Comparison::kAtLeast, "x body height",
     "Smallest mean move of a muscle's skin along the normal at its most stretched sample (negative: a hollow)"},
    // Issue 31: tools that do not know rigbake (gltfpack, glTF-Transform without rigbake's config) drop
    // the extension or cut the influences without an error; a CI gate must see it.
    {"RIG_EXTENSION_MISSING", Severity::kError, 0.0, Comparison::kAtMost, "joints",
     "Muscle joints that neither the RIGBAKE_muscle_rig extension nor every clip's channels drive (a tool stripped the rig)"},
    {"INFLUENCES_TRUNCATED", Severity::kError, 0.0, Comparison::kAtMost, "vertices",
     "Vertices whose JOINTS_n/WEIGHTS_n hold fewer influences than the packed buffers (a tool cut them)"},
    {"GLTF_STRUCTURE", Severity::kError, 0.0, Comparison::kAtMost, "issues",
     "Structural problems: accessor counts and types, skins, muscle joint nodes and their animation"},
    {"KHRONOS_VALIDATOR", Severity::kError, 0.0, Comparison::kAtMost, "errors",
     "Errors the Khronos glTF-Validator reports"},
}};

// Every check, in report order.
constexpr const std::array<CheckDefinition, 22>& checkDefinitions() { return kCheckDefinitions; }

// The index of `code` in the table, or the table's size when it is not there.
constexpr size_t checkIndex(std::string_view code) {
  for (size_t i = 0; i < kCheckDefinitions.size(); ++i) {
    if (code == kCheckDefinitions[i].code) return i;
  }
  return kCheckDefinitions.size();
}

// nullptr when `code` is not a check's.
constexpr const CheckDefinition* findCheckDefinition(std::string_view code) {
  const size_t index = checkIndex(code);
  return index < kCheckDefinitions.size() ? &kCheckDefinitions[index] : nullptr;
}

// The definition at kIndex, from checkIndex("CODE") as a template argument: evaluated when the program is
// compiled, so a mistyped code is a compile error rather than a check without a definition.
template <size_t kIndex>
constexpr const CheckDefinition& checkAt() {
  static_assert(kIndex < kCheckDefinitions.size(), "not a check code of pipeline/check_registry.h");
  return kCheckDefinitions[kIndex];
}

namespace check_registry_detail {
constexpr bool everyCodeOnce() {
  for (size_t i = 0; i < kCheckDefinitions.size(); ++i) {
    if (kCheckDefinitions[i].code == nullptr || checkIndex(kCheckDefinitions[i].code) != i) return false;
  }
  return true;
}
}  // namespace check_registry_detail
// Also catches a table declared longer than its rows (the rest would have no code).
static_assert(check_registry_detail::everyCodeOnce(), "a check code is missing or repeated in kCheckDefinitions");

}  // namespace rigbake
