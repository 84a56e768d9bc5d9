// The God of War Ragnarök talk's muscle joint group for one pose, evaluated by the runtime rig that
// engines link (runtime/muscle_rig.h): the muscle origin and insertion ride their attach joints, the
// muscle base and tip aim at each other, the muscle driver is point-constrained between them, and the
// muscle skinned joint rides its carrier joint and moves by the set-driven response to the muscle's
// length and twist. This file is the builder from anatomy's data to the runtime's flat arrays, and a
// convenience evaluation for one part. docs/muscle-model.md gives every equation.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/pose.h"
#include "runtime/muscle_rig.h"

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
  // Sign applied to the response's side component: -1 on "Right" parts, so that one preset bulge means
  // the mirror-image displacement on both sides even though both frames are right-handed.
  double side_sign = 1.0;
};

// Everything a pose gives one muscle part, in scene world space.
struct MuscleJointState {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();     // muscle origin
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero();  // muscle insertion
  Eigen::Affine3d base = Eigen::Affine3d::Identity();   // muscle base: at the origin, X aimed at the insertion
  Eigen::Affine3d tip = Eigen::Affine3d::Identity();    // muscle tip: at the insertion, X aimed at the origin
  Eigen::Affine3d driver = Eigen::Affine3d::Identity(); // muscle driver, oriented like the base
  double length = 0.0;         // L
  double rest_length = 0.0;    // L_rest
  double ratio = 1.0;          // r = L / L_rest
  double clamped_ratio = 1.0;  // r_c = clamp(r, compression, stretch)
  double twist = 0.0;          // radians: the insertion joint's turn about the fibre, relative to the origin joint
  double offset_up = 0.0;      // the response: metres along the rest up axis
  double offset_side = 0.0;    //   ... along the rest side axis (already signed for the part's side)
  double scale = 1.0;          //   ... and the scale across the fibre
  Eigen::Affine3d skinned = Eigen::Affine3d::Identity();  // muscle skinned joint
};

// "" when `part` can be evaluated on `skeleton`, otherwise what is wrong, naming the field
// (e.g. "insertion.joint 40 is not a joint of the 21-joint skeleton"). The caller turns it into an
// issue with its own code; evaluateMuscle() asserts it.
std::string musclePartProblem(const MusclePart& part, const Skeleton& skeleton);

MuscleRestFrame muscleRestFrame(const MusclePart& part, const Skeleton& skeleton);

// The skinned joint's world transform at the bind pose: T(driver) * R(rest base frame), unit scale.
// Its inverse is the skinned joint's inverse bind matrix in scene space.
Eigen::Affine3d muscleBindTransform(const MusclePart& part, const Skeleton& skeleton);

// The joint a part's skinned joint rides: its carrier, or the origin attach joint while none is chosen.
inline int muscleCarrierJoint(const MusclePart& part) { return part.carrier >= 0 ? part.carrier : part.origin.joint; }

// The runtime rig of every part, on the skeleton's joint indices (scene world space, metres). Every part
// must pass musclePartProblem().
runtime::MuscleRig<double> buildMuscleRig(const MuscleSet& muscles, const Skeleton& skeleton);

// The pose's world transforms as the flat column-major matrices a runtime job takes.
std::vector<double> jointMatrices(const Pose& pose);

// One evaluation of the whole rig for a pose: the skinned joints' world transforms, every helper
// (base, tip, driver) and every part's drivers.
struct RigEvaluation {
  std::vector<double> skinned;  // 16 per part
  std::vector<double> helpers;  // 48 per part: base, tip, driver
  std::vector<runtime::MuscleDrivers<double>> drivers;
};
RigEvaluation evaluateRig(const runtime::MuscleRig<double>& rig, const Pose& pose, bool with_helpers);

Eigen::Affine3d matrixAt(const std::vector<double>& matrices, size_t index);

// One part, evaluated alone (tests, reports). For whole rigs use buildMuscleRig() once and evaluateRig().
MuscleJointState evaluateMuscle(const MusclePart& part, const Skeleton& skeleton, const Pose& pose);

// The skinned joint relative to a parent joint's posed world transform, and the same split into T, R,
// S for an animation channel. The scale is along the skinned joint's own axes (X is the fibre), so the
// split is exact whenever the parent's world transform has no non-uniform scale.
Eigen::Affine3d skinnedLocalTransform(const MuscleJointState& state, const Pose& pose, int parent_joint);
Trs skinnedLocalTrs(const MuscleJointState& state, const Pose& pose, int parent_joint);

}  // namespace rigbake
