// Places a muscle preset's locators on a resolved skeleton, left side first, and mirrors them to the
// right across the body's sagittal plane (the talk: TrapezusMuscles(side='Right').mirror(trapBuilder)).
#pragma once

#include <string>

#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "anatomy/presets.h"

namespace rigbake {

enum class Sides { kLeft, kRight, kBoth };

// Throws LANDMARK_UNRESOLVED when an attach landmark or a formula input is missing, naming the
// preset file and JSON pointer.
MuscleSet placeMuscles(const Character& character, const LandmarkSet& landmarks, const MusclePreset& preset,
                       Sides sides);

// The right-side twin of a left part: positions reflected across the sagittal plane, attach joints
// swapped for their right twins (central joints stay).
MusclePart mirrorPart(const MusclePart& left, const Skeleton& skeleton, const LandmarkSet& landmarks,
                      const std::string& origin_landmark, const std::string& insertion_landmark);

// Re-expresses a world position in a joint's bind frame.
MuscleLocator locatorOn(const Skeleton& skeleton, int joint, const Eigen::Vector3d& world);

// A part of `spec` on `side` ("Left", "Right") with its locators at these world positions (origin and
// driver riding `origin_joint`, the insertion `insertion_joint`), the preset's bulge and radius scaled
// by `scale` (body height / reference height), and the response it starts with. A corrective's carrier
// is not set here.
MusclePart partFromPreset(const Skeleton& skeleton, const PresetPart& spec, const std::string& side, int origin_joint,
                          int insertion_joint, const Eigen::Vector3d& origin, const Eigen::Vector3d& insertion,
                          const Eigen::Vector3d& driver, double scale);

}  // namespace rigbake
