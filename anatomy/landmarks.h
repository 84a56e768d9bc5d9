// Canonical skeleton landmarks (the talk's "Spinal Column" mapping: head C1, neck C7, chest T8,
// spine_t12 T12, spine_l5 L5, pelvis S5; and per side clavicle, acromion, scapula, upper arm, twist
// joints, forearm, hand, and the optional legs: upper leg, lower leg, foot, toe) resolved from any
// naming convention, from structure, or derived.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/presets.h"

namespace rigbake {

// The body's own axes, computed from the skeleton so that any facing, up axis and unit works:
// lateral = left minus right upper arm, up = neck minus pelvis (made orthogonal to lateral... see
// docs/landmarks.md), forward = lateral x up.
struct BodyFrame {
  Eigen::Vector3d lateral = Eigen::Vector3d::UnitX();  // towards the character's left
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d midline = Eigen::Vector3d::Zero();  // a point on the sagittal plane
  double height = 0.0;                                // extent of the body mesh along `up`, scene units

  // "up", "down", "forward", "back", and "lateral"/"medial", which depend on the side ("l" or "r").
  Eigen::Vector3d direction(const std::string& name, const std::string& side) const;
  // Reflection across the sagittal plane.
  Eigen::Vector3d mirror(const Eigen::Vector3d& point) const;
  // Signed distance to the character's left of the sagittal plane.
  double lateralOffset(const Eigen::Vector3d& point) const { return (point - midline).dot(lateral); }
};

struct Landmark {
  bool resolved = false;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int joint = -1;          // the joint the landmark rides on
  std::string from_joint;  // joint name when the landmark is a joint, empty when derived
  std::string derived;     // the formula, when derived
  std::string source;      // "map:<name>", "vrm", "structure" or "derived"
};

struct LandmarkSet {
  std::string map_name;  // the naming map used, or "structure"
  BodyFrame body;
  std::map<std::string, Landmark> landmarks;  // every canonical name, resolved or not
  // Per skeleton joint, its parent as the body hangs it: the skeleton's own, except a limb root that the
  // rig hangs from the neck or the spine (LandmarkRules::limb_roots), which hangs from the joint above
  // those. What the muscles span is walked in this hierarchy, so that it does not depend on the rig's.
  std::vector<int> anatomical_parents;

  bool has(const std::string& name) const;
  const Landmark& get(const std::string& name) const;  // asserts has()
};

struct LandmarkInputs {
  const std::vector<NamingMap>* maps = nullptr;  // candidates for auto-detection
  const NamingMap* forced_map = nullptr;         // --map: use this one only
  const LandmarkRules* rules = nullptr;
};

// Throws LANDMARK_UNRESOLVED naming the landmark and the names tried when a required one is missing.
LandmarkSet resolveLandmarks(const Character& character, const LandmarkInputs& inputs);

// How many canonical landmarks a naming map finds in a skeleton (for detection and reports).
int countMapMatches(const NamingMap& map, const Character& character);

// Extent of the body mesh along `up` (skinned parts and rigid parts riding on joints).
double bodyHeight(const Character& character, const Eigen::Vector3d& up);

}  // namespace rigbake
