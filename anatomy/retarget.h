// Moves muscle data (hand-tuned or placed) from one character to another whose skeleton has other
// joint names, proportions, scale, units or facing: the talk's "Import/Export Muscle Data", where
// Kratos' exported muscle joints are imported onto another character. See docs/retarget.md.
#pragma once

#include <string>
#include <vector>

#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "anatomy/presets.h"

namespace rigbake {

// How one locator was carried, for reports: the canonical frame it was expressed in and the joints
// it rode on before and after.
struct CarriedLocator {
  std::string part;        // e.g. LeftBicep
  std::string locator;     // "origin", "insertion" or "driver"
  std::string frame;       // e.g. "upper_arm_l->forearm_l", or "muscle" for a driver between its ends
  std::string src_joint;
  std::string dst_joint;
};

// `source` rides on `src` (joint indices into its skeleton, as readMuscleJson or placeMuscles give
// them). Each origin and insertion is expressed in the landmark frame of its attach joint's body
// segment on `src` and rebuilt from the same canonical landmarks on `dst`; each driver is carried
// between its muscle's ends. For the parts `preset` knows, its attach landmarks say which landmark a
// joint stands for (several can ride on one joint) and its placement rule says which landmark frame
// the locator was built in, so hand-tuned edits of a preset placement travel with the landmarks
// they were tuned against; parts it lacks are carried in their attach landmark's frame.
// Bulge and weight radius scale with body height; compression and stretch are unchanged. A corrective
// rides the joint of its carrier landmark on `dst`, and is left out where that landmark does not resolve
// or its joint already carries another corrective of the same group and side (as placeMuscles() does).
// Throws RETARGET_LOCATOR_UNANCHORED (a locator rides on a joint with no landmark on or above it) and
// RETARGET_SEGMENT_DEGENERATE (a frame's two landmarks coincide on either character), both before
// any locator is moved; `source_file` names the muscle file in their messages. `carried`, when given,
// receives one entry per locator, in part order.
MuscleSet retargetMuscles(const MuscleSet& source, const Character& src, const LandmarkSet& src_landmarks,
                          const Character& dst, const LandmarkSet& dst_landmarks, const MusclePreset& preset,
                          const std::string& source_file = "", std::vector<CarriedLocator>* carried = nullptr);

}  // namespace rigbake
