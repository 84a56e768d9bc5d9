// Linear blend skinning (Magnenat-Thalmann, Laperriere, Thalmann, "Joint-dependent local deformations
// for hand animation and object grasping", 1988; glTF 2.0 section 3.7.3.3) and dual-quaternion skinning
// (Kavan, Collins, Zara, O'Sullivan, "Geometric Skinning with Approximate Dual Quaternion Blending",
// ACM TOG 27(4), 2008, algorithm 1 and section 4.1 for scale).
#include "pipeline/skinning.h"

#include <Eigen/LU>
#include <cassert>

#include "pipeline/pose.h"

namespace rigbake {

namespace {

using Column = Eigen::Map<const Eigen::Array4d>;

// M p for the column-major 4x4 `a`, x, y and z side by side in one Array4d (the fourth lane is unused).
inline Eigen::Array4d movedPoint(const double* a, const Eigen::Vector3d& p) {
  return Column(a) * p.x() + Column(a + 4) * p.y() + Column(a + 8) * p.z() + Column(a + 12);
}

// p + sum_k w_k (M_k p - p) for one vertex, with exactly the roundings of transformPoint() and of Eigen's
// coefficient-wise sums, but x, y and z side by side in one Array4d (the fourth lane is unused), so
// the compiler uses packed instructions: faster, and the same bits as three scalar lanes.
inline Eigen::Vector3d blendVertex(const Eigen::Vector3d& p, const double* weights, const int* joints, int slots,
                                   const std::vector<Eigen::Affine3d>& frame) {
  const Eigen::Array4d point(p.x(), p.y(), p.z(), 0.0);
  Eigen::Array4d offset = Eigen::Array4d::Zero();
  for (int k = 0; k < slots; ++k) {
    const double weight = weights[k];
    if (weight == 0.0) continue;
    const Eigen::Array4d moved = movedPoint(frame[joints[k]].data(), p);
    offset += weight * (moved - point);
  }
  return p + offset.head<3>().matrix();
}

}  // namespace

std::vector<Eigen::Vector3d> skinLinearBlend(const std::vector<Eigen::Vector3d>& bind_positions,
                                             const InfluenceSet& influences,
                                             const std::vector<Eigen::Affine3d>& frame) {
  assert(influences.vertexCount() == static_cast<int>(bind_positions.size()));
  const int slots = influences.slots_per_vertex;
  std::vector<Eigen::Vector3d> posed(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v)
    posed[v] = blendVertex(bind_positions[v], &influences.weights[v * slots], &influences.joints[v * slots], slots, frame);
  return posed;
}

void skinLinearBlend(const std::vector<Eigen::Vector3d>& bind_positions, const InfluenceSet& influences,
                     const std::vector<Eigen::Affine3d>& frame, const std::vector<int>& vertices,
                     std::vector<Eigen::Vector3d>* posed) {
  assert(influences.vertexCount() == static_cast<int>(bind_positions.size()));
  const size_t slots = static_cast<size_t>(influences.slots_per_vertex);
  posed->resize(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const size_t v = static_cast<size_t>(vertices[i]);
    (*posed)[i] = blendVertex(bind_positions[v], &influences.weights[v * slots], &influences.joints[v * slots],
                              static_cast<int>(slots), frame);
  }
}

void splitDualQuaternion(const Eigen::Affine3d& matrix, Eigen::Quaterniond* real_out, Eigen::Quaterniond* dual_out,
                         Eigen::Matrix3d* stretch) {
  // Polar decomposition M = R S by Newton's iteration R <- (R + R^-T) / 2 (Higham, "Computing the
  // polar decomposition - with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986), which converges
  // quadratically; a mirrored joint keeps its mirror in S.
  const Eigen::Matrix3d linear = matrix.linear();
  const double sign = linear.determinant() < 0 ? -1.0 : 1.0;
  Eigen::Matrix3d rotation = sign * linear;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Eigen::Matrix3d next = 0.5 * (rotation + rotation.inverse().transpose());
    const double step = (next - rotation).cwiseAbs().maxCoeff();
    rotation = next;
    if (step < 1e-15) break;
  }
  *stretch = rotation.transpose() * linear;
  const Eigen::Quaterniond real(rotation);
  const Eigen::Vector3d t = matrix.translation();
  const Eigen::Quaterniond translation(0.0, t.x(), t.y(), t.z());
  Eigen::Quaterniond dual = translation * real;
  dual.coeffs() *= 0.5;
  *real_out = real.normalized();
  *dual_out = dual;
}

DualQuaternionFrame dualQuaternionFrame(const std::vector<Eigen::Affine3d>& frame) {
  DualQuaternionFrame split;
  split.real.resize(frame.size());
  split.dual.resize(frame.size());
  split.stretch.resize(frame.size());
  for (size_t j = 0; j < frame.size(); ++j) splitDualQuaternion(frame[j], &split.real[j], &split.dual[j], &split.stretch[j]);
  return split;
}

namespace {

Eigen::Vector3d dualQuaternionVertex(const Eigen::Vector3d& p, const double* weights, const int* joints, int slots,
                                     const DualQuaternionFrame& frame) {
  Eigen::Vector4d real = Eigen::Vector4d::Zero(), dual = Eigen::Vector4d::Zero();
  Eigen::Matrix3d stretch = Eigen::Matrix3d::Zero();
  Eigen::Vector4d pivot = Eigen::Vector4d::Zero();
  double total = 0.0;
  for (int k = 0; k < slots; ++k) {
    const double weight = weights[k];
    if (weight == 0.0) continue;
    const int joint = joints[k];
    const Eigen::Vector4d q = frame.real[joint].coeffs();
    if (pivot.isZero()) pivot = q;  // canonical order: the strongest influence comes first
    const double sign = q.dot(pivot) < 0.0 ? -1.0 : 1.0;
    real += sign * weight * q;
    dual += sign * weight * frame.dual[joint].coeffs();
    stretch += weight * frame.stretch[joint];
    total += weight;
  }
  if (total == 0.0) return p;
  const Eigen::Vector3d stretched = stretch / total * p;
  const double norm = real.norm();
  const Eigen::Quaterniond r(real(3) / norm, real(0) / norm, real(1) / norm, real(2) / norm);
  const Eigen::Quaterniond e(dual(3) / norm, dual(0) / norm, dual(1) / norm, dual(2) / norm);
  // Translation of the normalized dual quaternion: the vector part of 2 e r*. (Its scalar part,
  // r . e, is what the blend left of non-unit length; Kavan et al. drop it the same way.)
  const Eigen::Vector3d translation = 2.0 * (e * r.conjugate()).vec();
  return r * stretched + translation;
}

}  // namespace

std::vector<Eigen::Vector3d> skinDualQuaternion(const std::vector<Eigen::Vector3d>& bind_positions,
                                                const InfluenceSet& influences, const DualQuaternionFrame& frame) {
  assert(influences.vertexCount() == static_cast<int>(bind_positions.size()));
  const int slots = influences.slots_per_vertex;
  std::vector<Eigen::Vector3d> posed(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v)
    posed[v] = dualQuaternionVertex(bind_positions[v], &influences.weights[v * slots], &influences.joints[v * slots],
                                    slots, frame);
  return posed;
}

void skinInputAndRig(const std::vector<Eigen::Vector3d>& bind_positions, const InfluenceSet& input,
                     const InfluenceSet& rig, const std::vector<Eigen::Affine3d>& frame,
                     const DualQuaternionFrame& dual_quaternions, const std::vector<int>& vertices,
                     std::vector<Eigen::Vector3d>* input_linear, std::vector<Eigen::Vector3d>* input_dual_quaternion,
                     std::vector<Eigen::Vector3d>* rig_linear) {
  assert(input.vertexCount() == static_cast<int>(bind_positions.size()));
  assert(rig.vertexCount() == static_cast<int>(bind_positions.size()));
  const size_t input_slots = static_cast<size_t>(input.slots_per_vertex), rig_slots = static_cast<size_t>(rig.slots_per_vertex);
  input_linear->resize(vertices.size());
  input_dual_quaternion->resize(vertices.size());
  rig_linear->resize(vertices.size());
  // The input's joints' M p at the vertex, for the rig's blend: the same expression, so the same bits.
  constexpr int kCached = 16;
  int cached_joint[kCached];
  Eigen::Array4d cached_moved[kCached];
  for (size_t i = 0; i < vertices.size(); ++i) {
    const size_t v = static_cast<size_t>(vertices[i]);
    const Eigen::Vector3d& p = bind_positions[v];
    const Eigen::Array4d point(p.x(), p.y(), p.z(), 0.0);
    const double* weights = &input.weights[v * input_slots];
    const int* joints = &input.joints[v * input_slots];
    int cached = 0;
    Eigen::Array4d offset = Eigen::Array4d::Zero();
    for (size_t k = 0; k < input_slots; ++k) {
      const double weight = weights[k];
      if (weight == 0.0) continue;
      const Eigen::Array4d moved = movedPoint(frame[joints[k]].data(), p);
      offset += weight * (moved - point);
      if (cached < kCached) {
        cached_joint[cached] = joints[k];
        cached_moved[cached] = moved;
        ++cached;
      }
    }
    (*input_linear)[i] = p + offset.head<3>().matrix();
    (*input_dual_quaternion)[i] = dualQuaternionVertex(p, weights, joints, static_cast<int>(input_slots), dual_quaternions);
    weights = &rig.weights[v * rig_slots];
    joints = &rig.joints[v * rig_slots];
    offset = Eigen::Array4d::Zero();
    for (size_t k = 0; k < rig_slots; ++k) {
      const double weight = weights[k];
      if (weight == 0.0) continue;
      int c = 0;
      while (c < cached && cached_joint[c] != joints[k]) ++c;
      if (c < cached) {
        offset += weight * (cached_moved[c] - point);
      } else {
        const Eigen::Array4d moved = movedPoint(frame[joints[k]].data(), p);
        offset += weight * (moved - point);
      }
    }
    (*rig_linear)[i] = p + offset.head<3>().matrix();
  }
}

}  // namespace rigbake
