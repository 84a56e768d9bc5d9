// Deformation error of approximated skin weights under linear-blend skinning (Magnenat-Thalmann et al.,
// "Joint-dependent local deformations for hand animation and object grasping", 1988; in glTF terms the
// vertex skinning of glTF 2.0 3.7.3.3): p' = sum_k w_k M_{j_k} p.
#include "pipeline/deformation_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.h"
#include "pipeline/parallel.h"
#include "pipeline/pose.h"

namespace rigbake {

namespace {

void requireVertices(const InfluenceSet& set, size_t vertices, const char* name) {
  if (set.slots_per_vertex <= 0 || set.joints.size() != set.weights.size() ||
      set.joints.size() != vertices * static_cast<size_t>(set.slots_per_vertex))
    fail(errc::INTERNAL, "", std::string("skinningDeformationError: ") + name + " influences do not match the " +
                             std::to_string(vertices) + " positions");
}

// The first weighted slot, reference before approximation and vertex by vertex (the order skinning
// meets them), that names a joint without a matrix: checked once, before the frames are skinned.
void requireJoints(const InfluenceSet& reference, const InfluenceSet& approximation, size_t joints) {
  const int vertices = reference.vertexCount();
  for (int v = 0; v < vertices; ++v) {
    for (const InfluenceSet* set : {&reference, &approximation}) {
      for (int k = 0; k < set->slots_per_vertex; ++k) {
        const size_t index = static_cast<size_t>(v) * set->slots_per_vertex + k;
        const int joint = set->joints[index];
        if (set->weights[index] == 0.0 || (joint >= 0 && joint < static_cast<int>(joints))) continue;
        fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " names joint " + std::to_string(joint) + " but there are " +
                                 std::to_string(joints) + " skin matrices");
      }
    }
  }
}

// Both skinned positions of one vertex, p + sum_k w_k (M_k p - p), each M_k p - p computed once for a
// joint the two sets share. The arithmetic per coordinate is transformPoint()'s and Eigen's
// coefficient-wise sums', in the same order (x, y and z side by side in an Array4d, the fourth lane
// unused), so the displacement is the same to the bit as skinning the two sets apart.
double vertexDisplacement(const Eigen::Vector3d& p, const InfluenceSet& reference, const InfluenceSet& approximation,
                          size_t vertex, const std::vector<Eigen::Affine3d>& skin_matrices) {
  using Column = Eigen::Map<const Eigen::Array4d>;
  constexpr int kShared = 32;
  const Eigen::Array4d point(p.x(), p.y(), p.z(), 0.0);
  auto moved = [&](int joint) {
    const double* a = skin_matrices[joint].data();  // column-major 4x4
    return Eigen::Array4d(Column(a) * p.x() + Column(a + 4) * p.y() + Column(a + 8) * p.z() + Column(a + 12) - point);
  };
  int shared_joint[kShared];
  Eigen::Array4d shared_move[kShared];
  int shared = 0;
  Eigen::Array4d offset = Eigen::Array4d::Zero();
  const int reference_slots = reference.slots_per_vertex;
  for (int k = 0; k < reference_slots; ++k) {
    const size_t index = vertex * reference_slots + k;
    const double weight = reference.weights[index];
    if (weight == 0.0) continue;
    const int joint = reference.joints[index];
    const Eigen::Array4d move = moved(joint);
    if (shared < kShared) {
      shared_joint[shared] = joint;
      shared_move[shared++] = move;
    }
    offset += weight * move;
  }
  Eigen::Array4d approximate_offset = Eigen::Array4d::Zero();
  const int approximation_slots = approximation.slots_per_vertex;
  for (int k = 0; k < approximation_slots; ++k) {
    const size_t index = vertex * approximation_slots + k;
    const double weight = approximation.weights[index];
    if (weight == 0.0) continue;
    const int joint = approximation.joints[index];
    int at = 0;
    while (at < shared && shared_joint[at] != joint) ++at;
    approximate_offset += weight * (at < shared ? shared_move[at] : moved(joint));
  }
  const Eigen::Vector3d skinned = p + offset.head<3>().matrix();
  const Eigen::Vector3d approximated = p + approximate_offset.head<3>().matrix();
  return (skinned - approximated).norm();
}

// One frame's figures, the vertices in order (the same sums as skinningDeformationError()).
DeformationError frameDeformationError(const std::vector<Eigen::Vector3d>& bind_positions, const InfluenceSet& reference,
                                       const InfluenceSet& approximation, const std::vector<Eigen::Affine3d>& skin_matrices) {
  DeformationError error;
  error.vertex_count = static_cast<int>(bind_positions.size());
  double sum_squared = 0.0;
  for (int v = 0; v < error.vertex_count; ++v) {
    const double distance = vertexDisplacement(bind_positions[v], reference, approximation, static_cast<size_t>(v), skin_matrices);
    sum_squared += distance * distance;
    if (distance > error.max_displacement) {
      error.max_displacement = distance;
      error.max_vertex = v;
    }
  }
  if (error.vertex_count > 0) error.rms_displacement = std::sqrt(sum_squared / error.vertex_count);
  return error;
}

}  // namespace

std::vector<double> skinningDisplacements(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices) {
  requireVertices(reference, bind_positions.size(), "reference");
  requireVertices(approximation, bind_positions.size(), "approximated");
  requireJoints(reference, approximation, skin_matrices.size());
  std::vector<double> displacements(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v)
    displacements[v] = vertexDisplacement(bind_positions[v], reference, approximation, v, skin_matrices);
  return displacements;
}

DeformationError skinningDeformationError(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices) {
  requireVertices(reference, bind_positions.size(), "reference");
  requireVertices(approximation, bind_positions.size(), "approximated");
  requireJoints(reference, approximation, skin_matrices.size());
  return frameDeformationError(bind_positions, reference, approximation, skin_matrices);
}

std::vector<DeformationError> skinningDeformationErrors(const std::vector<Eigen::Vector3d>& bind_positions,
                                                        const InfluenceSet& reference, const InfluenceSet& approximation,
                                                        const std::vector<std::vector<Eigen::Affine3d>>& frames,
                                                        int threads) {
  requireVertices(reference, bind_positions.size(), "reference");
  requireVertices(approximation, bind_positions.size(), "approximated");
  size_t joints = std::numeric_limits<size_t>::max();
  for (const std::vector<Eigen::Affine3d>& frame : frames) joints = std::min(joints, frame.size());
  if (!frames.empty()) requireJoints(reference, approximation, joints);
  std::vector<DeformationError> errors(frames.size());
  parallelForEach(threads, frames.size(), [&](size_t t) {
    errors[t] = frameDeformationError(bind_positions, reference, approximation, frames[t]);
  });
  return errors;
}

DeformationError combineDeformationErrors(const DeformationError& a, const DeformationError& b) {
  DeformationError out;
  out.vertex_count = a.vertex_count + b.vertex_count;
  if (b.max_displacement > a.max_displacement) {
    out.max_displacement = b.max_displacement;
    out.max_vertex = b.max_vertex < 0 ? -1 : a.vertex_count + b.max_vertex;
  } else {
    out.max_displacement = a.max_displacement;
    out.max_vertex = a.max_vertex;
  }
  if (out.vertex_count > 0) {
    double sum_squared = a.rms_displacement * a.rms_displacement * a.vertex_count +
                         b.rms_displacement * b.rms_displacement * b.vertex_count;
    out.rms_displacement = std::sqrt(sum_squared / out.vertex_count);
  }
  return out;
}

double maxWeightDifference(const InfluenceSet& a, const InfluenceSet& b) {
  if (a.vertexCount() != b.vertexCount())
    fail(errc::INTERNAL, "", "maxWeightDifference: the sets have different vertex counts");
  double largest = 0.0;
  for (int v = 0; v < a.vertexCount(); ++v) {
    // Slots may be ordered differently (requantizing can reorder equal weights), so compare by joint.
    std::map<int, double> difference;
    for (int k = 0; k < a.slots_per_vertex; ++k) {
      size_t index = static_cast<size_t>(v) * a.slots_per_vertex + k;
      if (a.weights[index] != 0.0) difference[a.joints[index]] += a.weights[index];
    }
    for (int k = 0; k < b.slots_per_vertex; ++k) {
      size_t index = static_cast<size_t>(v) * b.slots_per_vertex + k;
      if (b.weights[index] != 0.0) difference[b.joints[index]] -= b.weights[index];
    }
    for (const auto& entry : difference) largest = std::max(largest, std::abs(entry.second));
  }
  return largest;
}

}  // namespace rigbake
