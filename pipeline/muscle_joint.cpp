// Muscle joint groups: the builder from placed muscles to the runtime rig (runtime/muscle_rig.h, which
// holds the equations and cites their sources), and one-part evaluation for tests and reports. The
// rest frame follows the talk's createFromAttachObjs: the fibre runs from origin to insertion, the up
// axis points from the origin attach joint towards the belly (muscles bulge away from the bone they
// start on). docs/muscle-model.md.
#include "pipeline/muscle_joint.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace rigbake {

namespace {

// The rest up vector points from the origin attach joint towards the muscle belly, unless the belly
// lies within this fraction of L_rest of the fibre line through that joint (then a joint axis is used).
constexpr double kOutwardMinFraction = 0.01;

Eigen::Vector3d acrossFibre(const Eigen::Vector3d& v, const Eigen::Vector3d& fibre) {
  return v - v.dot(fibre) * fibre;
}

Eigen::Affine3d placedFrame(const Eigen::Vector3d& position, const Eigen::Vector3d& x, const Eigen::Vector3d& y,
                            const Eigen::Vector3d& z) {
  Eigen::Affine3d frame = Eigen::Affine3d::Identity();
  frame.linear().col(0) = x;
  frame.linear().col(1) = y;
  frame.linear().col(2) = z;
  frame.translation() = position;
  return frame;
}

void copy3(const Eigen::Vector3d& v, double* out) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

// A joint's bind rotation (its frame with any uniform scale divided out).
Eigen::Matrix3d bindRotation(const Skeleton& skeleton, int joint) {
  Eigen::Matrix3d r = skeleton.bind_world[joint].linear();
  const Eigen::Vector3d x = r.col(0).normalized();
  const Eigen::Vector3d y = acrossFibre(r.col(1), x).normalized();
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = x.cross(y);
  return r;
}

void appendCurve(const std::vector<ResponseKey>& curve, double side_sign, std::vector<runtime::ResponseKey<double>>* keys,
                 int* begin, int* count) {
  *begin = static_cast<int>(keys->size());
  *count = static_cast<int>(curve.size());
  for (const ResponseKey& key : curve) keys->push_back({key.at, key.up, side_sign * key.side, key.scale});
}

}  // namespace

std::string musclePartProblem(const MusclePart& part, const Skeleton& skeleton) {
  const std::string joints = " is not a joint of the " + std::to_string(skeleton.size()) + "-joint skeleton";
  if (part.origin.joint < 0 || part.origin.joint >= skeleton.size())
    return "origin.joint " + std::to_string(part.origin.joint) + joints;
  if (part.insertion.joint < 0 || part.insertion.joint >= skeleton.size())
    return "insertion.joint " + std::to_string(part.insertion.joint) + joints;
  if (part.carrier >= skeleton.size()) return "carrier joint " + std::to_string(part.carrier) + joints;
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
  const std::string response = muscleResponseProblem(part.response);
  if (!response.empty()) return "response: " + response;
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
  rest.side_sign = part.side == "Right" ? -1.0 : 1.0;
  return rest;
}

Eigen::Affine3d muscleBindTransform(const MusclePart& part, const Skeleton& skeleton) {
  const MuscleRestFrame rest = muscleRestFrame(part, skeleton);
  return placedFrame(part.driver.world, rest.fibre, rest.up, rest.side);
}

runtime::MuscleRig<double> buildMuscleRig(const MuscleSet& muscles, const Skeleton& skeleton) {
  runtime::MuscleRig<double> rig;
  rig.joint_count = skeleton.size();
  for (const MusclePart& part : muscles.parts) {
    const MuscleRestFrame rest = muscleRestFrame(part, skeleton);
    runtime::RigMuscle<double> muscle;
    muscle.origin_joint = part.origin.joint;
    muscle.insertion_joint = part.insertion.joint;
    muscle.carrier_joint = muscleCarrierJoint(part);
    const Eigen::Affine3d& origin_bind = skeleton.bind_world[part.origin.joint];
    const Eigen::Affine3d& insertion_bind = skeleton.bind_world[part.insertion.joint];
    copy3(origin_bind.inverse() * rest.origin, muscle.origin_local);
    copy3(insertion_bind.inverse() * rest.insertion, muscle.insertion_local);
    muscle.rest_length = rest.length;
    muscle.compression = part.compression;
    muscle.stretch = part.stretch;
    // Helper directions through the bind matrix (exact at the bind pose); the twist axis in the
    // orthonormal frame the runtime reads the twist in (rotationOf()).
    const Eigen::Matrix3d origin_inverse_linear = origin_bind.linear().inverse();
    copy3(origin_inverse_linear * rest.fibre, muscle.fibre_local);
    copy3(origin_inverse_linear * rest.up, muscle.up_local);
    const Eigen::Matrix3d origin_rotation = bindRotation(skeleton, part.origin.joint);
    copy3(origin_rotation.transpose() * rest.fibre, muscle.twist_axis_local);
    const Eigen::Quaterniond relative(Eigen::Matrix3d(origin_rotation.transpose() *
                                                      bindRotation(skeleton, part.insertion.joint)));
    const Eigen::Quaterniond q = relative.normalized();
    muscle.insertion_bind_in_origin[0] = q.x();
    muscle.insertion_bind_in_origin[1] = q.y();
    muscle.insertion_bind_in_origin[2] = q.z();
    muscle.insertion_bind_in_origin[3] = q.w();
    muscle.driver_fraction = rest.driver_fraction;
    muscle.driver_offset[0] = rest.driver_offset.x();
    muscle.driver_offset[1] = rest.driver_offset.y();
    const Eigen::Matrix4d in_carrier =
        (skeleton.bind_world[muscle.carrier_joint].inverse() * muscleBindTransform(part, skeleton)).matrix();
    for (int k = 0; k < 16; ++k) muscle.skinned_in_carrier[k] = in_carrier.data()[k];
    appendCurve(part.response.ratio, rest.side_sign, &rig.keys, &muscle.ratio_key_begin, &muscle.ratio_key_count);
    appendCurve(part.response.twist, rest.side_sign, &rig.keys, &muscle.twist_key_begin, &muscle.twist_key_count);
    rig.muscles.push_back(muscle);
  }
  assert(std::string(runtime::rigProblem(rig)).empty() || muscles.parts.empty());
  runtime::prepareMuscleRig(&rig);
  return rig;
}

std::vector<double> jointMatrices(const Pose& pose) {
  std::vector<double> matrices(16 * pose.world.size());
  for (size_t j = 0; j < pose.world.size(); ++j) {
    const Eigen::Matrix4d m = pose.world[j].matrix();
    std::copy(m.data(), m.data() + 16, matrices.begin() + 16 * j);
  }
  return matrices;
}

RigEvaluation evaluateRig(const runtime::MuscleRig<double>& rig, const Pose& pose, bool with_helpers) {
  RigEvaluation out;
  const std::vector<double> joints = jointMatrices(pose);
  out.skinned.assign(16 * rig.muscles.size(), 0.0);
  if (with_helpers) out.helpers.assign(48 * rig.muscles.size(), 0.0);
  out.drivers.resize(rig.muscles.size());
  runtime::MuscleRigJob<double> job;
  job.rig = &rig;
  job.joint_matrices = runtime::Span<const double>(joints.data(), joints.size());
  job.skinned_matrices = runtime::Span<double>(out.skinned);
  job.helper_matrices = runtime::Span<double>(out.helpers);
  job.drivers = runtime::Span<runtime::MuscleDrivers<double>>(out.drivers);
  const bool ran = job.Run();
  assert(ran);
  (void)ran;
  return out;
}

Eigen::Affine3d matrixAt(const std::vector<double>& matrices, size_t index) {
  Eigen::Affine3d m;
  m.matrix() = Eigen::Map<const Eigen::Matrix4d>(matrices.data() + 16 * index);
  return m;
}

MuscleJointState evaluateMuscle(const MusclePart& part, const Skeleton& skeleton, const Pose& pose) {
  assert(static_cast<int>(pose.world.size()) == skeleton.size());
  MuscleSet one;
  one.parts.push_back(part);
  const runtime::MuscleRig<double> rig = buildMuscleRig(one, skeleton);
  const RigEvaluation evaluation = evaluateRig(rig, pose, true);
  const runtime::MuscleDrivers<double>& drivers = evaluation.drivers[0];
  const runtime::ResponseKey<double> response = runtime::evaluateResponse(rig, rig.muscles[0], drivers);
  MuscleJointState state;
  state.base = matrixAt(evaluation.helpers, 0);
  state.tip = matrixAt(evaluation.helpers, 1);
  state.driver = matrixAt(evaluation.helpers, 2);
  state.origin = state.base.translation();
  state.insertion = state.tip.translation();
  state.rest_length = rig.muscles[0].rest_length;
  state.length = (state.insertion - state.origin).norm();
  state.ratio = drivers.ratio;
  state.clamped_ratio = drivers.clamped_ratio;
  state.twist = drivers.twist;
  state.offset_up = response.up;
  state.offset_side = response.side;
  state.scale = response.scale;
  state.skinned = matrixAt(evaluation.skinned, 0);
  return state;
}

Eigen::Affine3d skinnedLocalTransform(const MuscleJointState& state, const Pose& pose, int parent_joint) {
  assert(parent_joint >= 0 && parent_joint < static_cast<int>(pose.world.size()));
  return pose.world[parent_joint].inverse() * state.skinned;
}

Trs skinnedLocalTrs(const MuscleJointState& state, const Pose& pose, int parent_joint) {
  return decomposeTrs(skinnedLocalTransform(state, pose, parent_joint));
}

}  // namespace rigbake
