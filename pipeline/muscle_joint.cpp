// Muscle joint group evaluation.
// Sources: God of War Ragnarök rigging talk, "Muscle Joint Group" and "Muscle Properties" (aim
// constraints for the attachments, a point constraint for the muscle movement, set driven keys for
// the bulge; fibre structure from start to end; volume preservation), and
// createFromAttachObjs(name, originAttach, insertionAttach, compressionFactor, stretchFactor,
// bulgeVector). The aim matrix is the one of "Rigging with Triangles" (GDC 2018): X aims at the
// target, the up vector is made orthogonal to it, Z = X x Y. The up vector is carried by the origin
// attach joint and swung with the minimal rotation (Rodrigues) that takes the carried rest fibre to
// the current fibre, so it never flips as a limb passes overhead. docs/muscle-model.md has the model.
#include "pipeline/muscle_joint.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace rigbake {

namespace {

// The rest up vector points from the origin attach joint towards the muscle belly, unless the belly
// lies within this fraction of L_rest of the fibre line through that joint (then a joint axis is used).
constexpr double kOutwardMinFraction = 0.01;
// Below this fraction of L_rest the posed fibre has no direction; the carried rest fibre stands in.
constexpr double kMinLengthFraction = 1e-9;
// 1 + cos(angle) below which the fibre has reversed relative to its origin joint: the minimal
// rotation is undefined there (any half turn about an axis across the fibre qualifies).
constexpr double kReversedFibre = 1e-12;

Eigen::Vector3d acrossFibre(const Eigen::Vector3d& v, const Eigen::Vector3d& fibre) {
  return v - v.dot(fibre) * fibre;
}

// Rotates v by the smallest rotation that takes unit vector `from` to unit vector `to`
// (Rodrigues' formula with k = from x to, |k| = sin, from . to = cos).
Eigen::Vector3d swing(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& v) {
  const double cosine = from.dot(to);
  if (1.0 + cosine < kReversedFibre) {
    // Half turn about v's own direction across `from`: v (already across `from`) stays put.
    return v;
  }
  const Eigen::Vector3d k = from.cross(to);
  return cosine * v + k.cross(v) + (k.dot(v) / (1.0 + cosine)) * k;
}

Eigen::Matrix3d frameColumns(const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
  Eigen::Matrix3d m;
  m.col(0) = x;
  m.col(1) = y;
  m.col(2) = z;
  return m;
}

Eigen::Affine3d placedFrame(const Eigen::Vector3d& position, const Eigen::Matrix3d& rotation) {
  Eigen::Affine3d frame = Eigen::Affine3d::Identity();
  frame.linear() = rotation;
  frame.translation() = position;
  return frame;
}

}  // namespace

std::string musclePartProblem(const MusclePart& part, const Skeleton& skeleton) {
  const std::string joints = " is not a joint of the " + std::to_string(skeleton.size()) + "-joint skeleton";
  if (part.origin.joint < 0 || part.origin.joint >= skeleton.size())
    return "origin.joint " + std::to_string(part.origin.joint) + joints;
  if (part.insertion.joint < 0 || part.insertion.joint >= skeleton.size())
    return "insertion.joint " + std::to_string(part.insertion.joint) + joints;
  if (!part.origin.world.allFinite() || !part.insertion.world.allFinite() || !part.driver.world.allFinite())
    return "a locator position is not finite";
  const double length = (part.insertion.world - part.origin.world).norm();
  if (!(length >= kMinMuscleRestLength))
    return "origin and insertion are " + std::to_string(length) + " m apart (at least " +
           std::to_string(kMinMuscleRestLength) + " m needed)";
  if (!(part.compression > 0.0 && part.compression <= 1.0))
    return "compression " + std::to_string(part.compression) + " is not in (0, 1]";
  if (!(part.stretch >= 1.0 && std::isfinite(part.stretch)))
    return "stretch " + std::to_string(part.stretch) + " is not a finite number >= 1";
  if (!part.bulge.allFinite()) return "bulge is not finite";
  return "";
}

MuscleRestFrame muscleRestFrame(const MusclePart& part, const Skeleton& skeleton) {
  assert(musclePartProblem(part, skeleton).empty());
  MuscleRestFrame rest;
  rest.origin = part.origin.world;
  rest.insertion = part.insertion.world;
  const Eigen::Vector3d segment = rest.insertion - rest.origin;
  rest.length = segment.norm();
  rest.fibre = segment / rest.length;

  // Muscles bulge away from the bone they start on, so "up" is the belly's direction seen from the
  // origin attach joint, taken across the fibre.
  const Eigen::Affine3d& attach = skeleton.bind_world[part.origin.joint];
  Eigen::Vector3d up = acrossFibre(part.driver.world - attach.translation(), rest.fibre);
  if (up.norm() < kOutwardMinFraction * rest.length) {
    // The belly sits on the fibre line through the joint: use the attach joint's bind axis that is
    // most nearly across the fibre (lowest axis index on a tie), which exists for any fibre.
    int best_axis = 0;
    double best_alignment = 2.0;
    for (int axis = 0; axis < 3; ++axis) {
      const double alignment = std::abs(attach.linear().col(axis).normalized().dot(rest.fibre));
      if (alignment < best_alignment) {
        best_alignment = alignment;
        best_axis = axis;
      }
    }
    up = acrossFibre(attach.linear().col(best_axis).normalized(), rest.fibre);
  }
  rest.up = up.normalized();
  rest.side = rest.fibre.cross(rest.up);

  const Eigen::Vector3d driver = part.driver.world - rest.origin;
  rest.driver_fraction = driver.dot(rest.fibre) / rest.length;
  rest.driver_offset = {driver.dot(rest.up), driver.dot(rest.side)};
  rest.bulge_side_sign = part.side == "Right" ? -1.0 : 1.0;
  return rest;
}

Eigen::Vector3d muscleScale(double clamped_ratio) {
  assert(clamped_ratio > 0.0);
  const double across = 1.0 / std::sqrt(clamped_ratio);
  return {clamped_ratio, across, across};
}

double muscleBulgeWeight(double clamped_ratio, double compression) {
  if (clamped_ratio >= 1.0 || compression >= 1.0) return 0.0;
  return (1.0 - clamped_ratio) / (1.0 - compression);
}

MuscleJointState evaluateMuscle(const MusclePart& part, const Skeleton& skeleton, const Pose& pose) {
  assert(static_cast<int>(pose.world.size()) == skeleton.size());
  const MuscleRestFrame rest = muscleRestFrame(part, skeleton);
  // Locators ride rigidly on their attach joints: bind world -> posed world through the joint's
  // skinning matrix, as a vertex bound only to that joint would.
  const Eigen::Affine3d origin_carry = skinMatrix(pose, skeleton, part.origin.joint);
  const Eigen::Affine3d insertion_carry = skinMatrix(pose, skeleton, part.insertion.joint);

  MuscleJointState state;
  state.origin = origin_carry * rest.origin;
  state.insertion = insertion_carry * rest.insertion;
  state.rest_length = rest.length;

  // The rest fibre and up vector as the origin joint carries them; the up vector is then swung with
  // the fibre's own motion relative to that joint.
  const Eigen::Vector3d carried_fibre = (origin_carry.linear() * rest.fibre).normalized();
  const Eigen::Vector3d carried_up =
      acrossFibre((origin_carry.linear() * rest.up).normalized(), carried_fibre).normalized();

  const Eigen::Vector3d segment = state.insertion - state.origin;
  state.length = segment.norm();
  const Eigen::Vector3d fibre =
      state.length > kMinLengthFraction * rest.length ? Eigen::Vector3d(segment / state.length) : carried_fibre;
  // Gram-Schmidt removes the rounding the swing leaves (and any shear the carry had).
  const Eigen::Vector3d up = acrossFibre(swing(carried_fibre, fibre, carried_up), fibre).normalized();
  const Eigen::Vector3d side = fibre.cross(up);

  const Eigen::Matrix3d base_rotation = frameColumns(fibre, up, side);
  state.base = placedFrame(state.origin, base_rotation);
  // The tip aims back at the origin with the same up vector; Z follows from the right-hand rule.
  state.tip = placedFrame(state.insertion, frameColumns(-fibre, up, -side));

  // Point constraint between base and tip at the rest fraction, with the rest offset across the fibre.
  state.driver = state.origin + rest.driver_fraction * state.length * fibre + rest.driver_offset.x() * up +
                 rest.driver_offset.y() * side;

  state.ratio = state.length / rest.length;
  state.clamped_ratio = std::clamp(state.ratio, part.compression, part.stretch);
  state.scale = muscleScale(state.clamped_ratio);
  const double bulge_weight = muscleBulgeWeight(state.clamped_ratio, part.compression);
  state.bulge_offset = bulge_weight * (part.bulge.x() * up + rest.bulge_side_sign * part.bulge.y() * side);

  state.skinned = placedFrame(state.driver + state.bulge_offset, base_rotation);
  state.skinned.scale(state.scale);
  return state;
}

Eigen::Affine3d muscleBindTransform(const MusclePart& part, const Skeleton& skeleton) {
  const MuscleRestFrame rest = muscleRestFrame(part, skeleton);
  return placedFrame(part.driver.world, frameColumns(rest.fibre, rest.up, rest.side));
}

Eigen::Affine3d skinnedLocalTransform(const MuscleJointState& state, const Pose& pose, int parent_joint) {
  assert(parent_joint >= 0 && parent_joint < static_cast<int>(pose.world.size()));
  return pose.world[parent_joint].inverse() * state.skinned;
}

Trs skinnedLocalTrs(const MuscleJointState& state, const Pose& pose, int parent_joint) {
  return decomposeTrs(skinnedLocalTransform(state, pose, parent_joint));
}

}  // namespace rigbake
