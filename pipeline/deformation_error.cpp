// Deformation error of approximated skin weights under linear-blend skinning (Magnenat-Thalmann et al.,
// "Joint-dependent local deformations for hand animation and object grasping", 1988; in glTF terms the
// vertex skinning of glTF 2.0 3.7.3.3): p' = sum_k w_k M_{j_k} p.
#include "pipeline/deformation_error.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "anatomy/error.h"
#include "pipeline/pose.h"

namespace rigbake {

namespace {

Eigen::Vector3d skinnedPosition(const Eigen::Vector3d& p, const InfluenceSet& set, int vertex,
                                const std::vector<Eigen::Affine3d>& skin_matrices) {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  const int slots = set.slots_per_vertex;
  for (int k = 0; k < slots; ++k) {
    size_t index = static_cast<size_t>(vertex) * slots + k;
    double weight = set.weights[index];
    if (weight == 0.0) continue;
    int joint = set.joints[index];
    if (joint < 0 || joint >= static_cast<int>(skin_matrices.size()))
      fail("INTERNAL", "", "vertex " + std::to_string(vertex) + " names joint " + std::to_string(joint) +
                               " but there are " + std::to_string(skin_matrices.size()) + " skin matrices");
    offset += weight * (transformPoint(skin_matrices[joint], p) - p);
  }
  return p + offset;
}

void requireVertices(const InfluenceSet& set, size_t vertices, const char* name) {
  if (set.slots_per_vertex <= 0 || set.joints.size() != set.weights.size() ||
      set.joints.size() != vertices * static_cast<size_t>(set.slots_per_vertex))
    fail("INTERNAL", "", std::string("skinningDeformationError: ") + name + " influences do not match the " +
                             std::to_string(vertices) + " positions");
}

}  // namespace

std::vector<double> skinningDisplacements(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices) {
  requireVertices(reference, bind_positions.size(), "reference");
  requireVertices(approximation, bind_positions.size(), "approximated");
  std::vector<double> displacements(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v) {
    const Eigen::Vector3d& p = bind_positions[v];
    const int vertex = static_cast<int>(v);
    displacements[v] = (skinnedPosition(p, reference, vertex, skin_matrices) -
                        skinnedPosition(p, approximation, vertex, skin_matrices)).norm();
  }
  return displacements;
}

DeformationError skinningDeformationError(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices) {
  std::vector<double> displacements = skinningDisplacements(bind_positions, reference, approximation, skin_matrices);
  DeformationError error;
  error.vertex_count = static_cast<int>(displacements.size());
  double sum_squared = 0.0;
  for (int v = 0; v < error.vertex_count; ++v) {
    double distance = displacements[v];
    sum_squared += distance * distance;
    if (distance > error.max_displacement) {
      error.max_displacement = distance;
      error.max_vertex = v;
    }
  }
  if (error.vertex_count > 0) error.rms_displacement = std::sqrt(sum_squared / error.vertex_count);
  return error;
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
    fail("INTERNAL", "", "maxWeightDifference: the sets have different vertex counts");
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
