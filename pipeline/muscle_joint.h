// The God of War Ragnarök talk's muscle joint group, evaluated for one pose: the muscle origin and
// insertion ride their attach joints, the muscle base and tip aim at each other, the muscle driver is
// point-constrained between them, and the muscle skinned joint follows the driver with a
// volume-preserving scale and a bulge. docs/muscle-model.md gives every equation.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/pose.h"

namespace rigbake {

// A muscle part is evaluable when it has a non-degenerate rest length and factors with
// 0 < compression <= 1 <= stretch (so that the rest pose is never clamped).
constexpr double kMinMuscleRestLength = 1e-6;  // metres

// The bind-pose frame of a muscle part, from which every pose is evaluated.
struct MuscleRestFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();     // bind world position of the muscle origin
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero();  // bind world position of the muscle insertion
  Eigen::Vector3d fibre = Eigen::Vector3d::UnitX();     // unit, origin -> insertion
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();        // unit, across the fibre, outward (see the doc)
  Eigen::Vector3d side = Eigen::Vector3d::UnitZ();      // fibre x up
  double length = 0.0;                                  // L_rest
  // The driver's rest position as origin + fraction * L_rest * fibre + offset.x() * up + offset.y() * side.
  double driver_fraction = 0.5;
  Eigen::Vector2d driver_offset = Eigen::Vector2d::Zero();
  // Sign applied to the bulge's side component: -1 on "Right" parts, so that one preset bulge means
  // the mirror-image displacement on both sides even though both frames are right-handed.
  double bulge_side_sign = 1.0;
};

// Everything a pose gives one muscle part, in scene world space.
struct MuscleJointState {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();     // muscle origin
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero();  // muscle insertion
  Eigen::Affine3d base = Eigen::Affine3d::Identity();   // muscle base: at the origin, X aimed at the insertion
  Eigen::Affine3d tip = Eigen::Affine3d::Identity();    // muscle tip: at the insertion, X aimed at the origin
  Eigen::Vector3d driver = Eigen::Vector3d::Zero();     // muscle driver
  Eigen::Vector3d bulge_offset = Eigen::Vector3d::Zero();  // added to the driver
  double length = 0.0;         // L
  double rest_length = 0.0;    // L_rest
  double ratio = 1.0;          // r = L / L_rest
  double clamped_ratio = 1.0;  // r_c = clamp(r, compression, stretch)
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();     // (r_c, r_c^-1/2, r_c^-1/2) on the skinned joint's axes
  Eigen::Affine3d skinned = Eigen::Affine3d::Identity();  // muscle skinned joint
};

// "" when `part` can be evaluated on `skeleton`, otherwise what is wrong, naming the field
// (e.g. "insertion.joint 40 is not a joint of the 21-joint skeleton"). The caller turns it into an
// issue with its own code; evaluateMuscle() asserts it.
std::string musclePartProblem(const MusclePart& part, const Skeleton& skeleton);

MuscleRestFrame muscleRestFrame(const MusclePart& part, const Skeleton& skeleton);

MuscleJointState evaluateMuscle(const MusclePart& part, const Skeleton& skeleton, const Pose& pose);

// The skinned joint's world transform at the bind pose: T(driver) * R(rest base frame), unit scale.
// evaluateMuscle() returns it (to rounding) for any pose whose world equals bind_world; its inverse is
// the skinned joint's inverse bind matrix in scene space.
Eigen::Affine3d muscleBindTransform(const MusclePart& part, const Skeleton& skeleton);

// Volume-preserving scale for a clamped length ratio: along the fibre r_c, across it r_c^-1/2.
Eigen::Vector3d muscleScale(double clamped_ratio);

// How much of the bulge vector is applied: (1 - r_c) / (1 - compression) while shortening, 0 at rest
// and when stretched, 1 at full compression.
double muscleBulgeWeight(double clamped_ratio, double compression);

// The joint the skinned joint is parented to when written out: the origin attach joint.
inline int muscleParentJoint(const MusclePart& part) { return part.origin.joint; }

// The skinned joint relative to a parent joint's posed world transform (normally
// muscleParentJoint(part)), and the same split into T, R, S for an animation channel. The scale is
// along the skinned joint's own axes (X is the fibre), so the split is exact whenever the parent's
// world transform has no non-uniform scale.
Eigen::Affine3d skinnedLocalTransform(const MuscleJointState& state, const Pose& pose, int parent_joint);
Trs skinnedLocalTrs(const MuscleJointState& state, const Pose& pose, int parent_joint);

}  // namespace rigbake
