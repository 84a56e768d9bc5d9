// Point formulas: the small language presets use to place landmarks and muscle locators from the
// skeleton, so that anatomy lives in data. Every formula is evaluated in the scene's world space.
//
//   {"at": "neck"}                          a landmark's position ("clavicle" means this side's)
//   {"mean": [F, F, ...]}                   average of points
//   {"lerp": [A, B], "t": 0.25}             A + (B - A) * t
//   {"sum": [F, V, ...]}                    a point plus offset vectors
//   {"dir": "back", "ref_m": 0.05}          a body-axis vector of 0.05 reference metres
//   {"joint_axis": "neck", "axis": "z", "ref_m": 0.02}
//                                           the landmark joint's own bind-pose axis (unit length)
//   {"mix": {"lateral": F, "up": F, "forward": F}}
//                                           per body-axis components taken from different points
//   {"locator": "TrapeziusB.origin"}        a locator placed earlier in the same preset
//
// Reference metres scale with the body: an offset of r reference metres is r * height / 1.8 in the
// scene, so the talk's literal offsets apply unchanged to a 1.8 m character (see docs/presets.md).
#pragma once

#include <string>
#include <vector>

namespace rigbake {

struct PointFormula {
  enum class Kind { kAt, kMean, kLerp, kSum, kDir, kJointAxis, kMix, kLocator };
  Kind kind = Kind::kAt;
  std::string name;     // landmark (kAt, kJointAxis), direction (kDir) or locator (kLocator)
  std::string axis;     // kJointAxis: "x", "y" or "z"
  double t = 0.0;       // kLerp
  double ref_m = 0.0;   // kDir, kJointAxis
  std::vector<PointFormula> args;  // kMean, kLerp (2), kSum, kMix (lateral, up, forward)
  std::string pointer;  // JSON pointer in its file, for messages

  // A readable one-line rendering, e.g. "lerp(acromion_l, clavicle_l, 0.1667)", used in reports.
  std::string describe(const std::string& side_suffix) const;
};

// Landmark names every skeleton is resolved to (docs/output-contract.md).
const std::vector<std::string>& centralLandmarks();  // head, neck, chest, spine_t12, spine_l5, pelvis
const std::vector<std::string>& sidedLandmarks();    // clavicle, acromion, ..., upper_leg, ... without _l/_r
bool isOptionalLandmark(const std::string& base_name);  // the twist joints and the legs
bool isLegLandmark(const std::string& base_name);       // upper_leg, lower_leg, foot, toe
// "clavicle" + side "l" -> "clavicle_l"; central names and names already suffixed are unchanged.
std::string sidedName(const std::string& name, const std::string& side);
bool isCanonicalLandmark(const std::string& name);  // accepts both "clavicle" and "clavicle_l"

}  // namespace rigbake
