// Linear blend skinning (Magnenat-Thalmann, Laperriere, Thalmann, "Joint-dependent local deformations
// for hand animation and object grasping", 1988; glTF 2.0 section 3.7.3.3) and dual-quaternion skinning
// (Kavan, Collins, Zara, O'Sullivan, "Geometric Skinning with Approximate Dual Quaternion Blending",
// ACM TOG 27(4), 2008, algorithm 1 and section 4.1 for scale).
#include "pipeline/skinning.h"

#include <Eigen/LU>
#include <cassert>

#include "pipeline/pose.h"

namespace rigbake {

std::vector<Eigen::Vector3d> skinLinearBlend(const std::vector<Eigen::Vector3d>& bind_positions,
                                             const InfluenceSet& influences,
                                             const std::vector<Eigen::Affine3d>& frame) {
  assert(influences.vertexCount() == static_cast<int>(bind_positions.size()));
  const int slots = influences.slots_per_vertex;
  std::vector<Eigen::Vector3d> posed(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v) {
    const Eigen::Vector3d& p = bind_positions[v];
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    for (int k = 0; k < slots; ++k) {
      const double weight = influences.weights[v * slots + k];
      if (weight == 0.0) continue;
      offset += weight * (transformPoint(frame[influences.joints[v * slots + k]], p) - p);
    }
    posed[v] = p + offset;
  }
  return posed;
}

DualQuaternionFrame dualQuaternionFrame(const std::vector<Eigen::Affine3d>& frame) {
  DualQuaternionFrame split;
  split.real.resize(frame.size());
  split.dual.resize(frame.size());
  split.stretch.resize(frame.size());
  for (size_t j = 0; j < frame.size(); ++j) {
    // Polar decomposition M = R S by Newton's iteration R <- (R + R^-T) / 2 (Higham, "Computing the
    // polar decomposition - with applications", SIAM J. Sci. Stat. Comput. 7(4), 1986), which converges
    // quadratically; a mirrored joint keeps its mirror in S.
    const Eigen::Matrix3d linear = frame[j].linear();
    const double sign = linear.determinant() < 0 ? -1.0 : 1.0;
    Eigen::Matrix3d rotation = sign * linear;
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Eigen::Matrix3d next = 0.5 * (rotation + rotation.inverse().transpose());
      const double step = (next - rotation).cwiseAbs().maxCoeff();
      rotation = next;
      if (step < 1e-15) break;
    }
    split.stretch[j] = rotation.transpose() * linear;
    const Eigen::Quaterniond real(rotation);
    const Eigen::Vector3d t = frame[j].translation();
    const Eigen::Quaterniond translation(0.0, t.x(), t.y(), t.z());
    Eigen::Quaterniond dual = translation * real;
    dual.coeffs() *= 0.5;
    split.real[j] = real.normalized();
    split.dual[j] = dual;
  }
  return split;
}

std::vector<Eigen::Vector3d> skinDualQuaternion(const std::vector<Eigen::Vector3d>& bind_positions,
                                                const InfluenceSet& influences, const DualQuaternionFrame& frame) {
  assert(influences.vertexCount() == static_cast<int>(bind_positions.size()));
  const int slots = influences.slots_per_vertex;
  std::vector<Eigen::Vector3d> posed(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v) {
    const Eigen::Vector3d& p = bind_positions[v];
    Eigen::Vector4d real = Eigen::Vector4d::Zero(), dual = Eigen::Vector4d::Zero();
    Eigen::Matrix3d stretch = Eigen::Matrix3d::Zero();
    Eigen::Vector4d pivot = Eigen::Vector4d::Zero();
    double total = 0.0;
    for (int k = 0; k < slots; ++k) {
      const double weight = influences.weights[v * slots + k];
      if (weight == 0.0) continue;
      const int joint = influences.joints[v * slots + k];
      const Eigen::Vector4d q = frame.real[joint].coeffs();
      if (pivot.isZero()) pivot = q;  // canonical order: the strongest influence comes first
      const double sign = q.dot(pivot) < 0.0 ? -1.0 : 1.0;
      real += sign * weight * q;
      dual += sign * weight * frame.dual[joint].coeffs();
      stretch += weight * frame.stretch[joint];
      total += weight;
    }
    if (total == 0.0) {
      posed[v] = p;
      continue;
    }
    const Eigen::Vector3d stretched = stretch / total * p;
    const double norm = real.norm();
    const Eigen::Quaterniond r(real(3) / norm, real(0) / norm, real(1) / norm, real(2) / norm);
    const Eigen::Quaterniond e(dual(3) / norm, dual(0) / norm, dual(1) / norm, dual(2) / norm);
    // Translation of the normalized dual quaternion: the vector part of 2 e r*. (Its scalar part,
    // r . e, is what the blend left of non-unit length; Kavan et al. drop it the same way.)
    const Eigen::Vector3d translation = 2.0 * (e * r.conjugate()).vec();
    posed[v] = r * stretched + translation;
  }
  return posed;
}

}  // namespace rigbake
