// Muscle data as JSON, in the talk's export shape ("Import/Export Muscle Data": group -> Left/Right
// -> <Side><Part>_muscleOrigin/_muscleInsertion/_muscleDriver world positions) plus a "rigbake" block
// with what a bake and a retarget need (attach joints, local positions, factors). Specified in
// docs/muscle-json.md.
#pragma once

#include <string>

#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "anatomy/presets.h"

namespace rigbake {

constexpr int kMuscleSchemaVersion = 1;

// Deterministic text (sorted keys, fixed indentation, shortest round-trip numbers), newline-terminated.
std::string muscleJson(const MuscleSet& muscles, const Skeleton& skeleton, const std::string& preset_name);

// Reads a muscle file for `character`. With a rigbake block, locators ride on the named joints
// (MUSCLES_MISMATCH if the character lacks one). A file with only the talk's positions gets its
// attach joints from `preset` (parts matched by name) resolved on `landmarks`.
MuscleSet readMuscleJson(const std::string& path, const Character& character, const LandmarkSet& landmarks,
                         const MusclePreset& preset);

}  // namespace rigbake
