// How far pruning and quantizing influences move skinned vertices: linear-blend skinning with the
// reference weights against the same skinning with the approximated ones, for one pose.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

struct DeformationError {
  double max_displacement = 0.0;  // in the positions' units
  double rms_displacement = 0.0;
  int max_vertex = -1;  // the vertex with the largest displacement, -1 when nothing moved
  int vertex_count = 0;
};

// Skins every bind position with both weight sets and measures |p_reference - p_approximation|.
// skin_matrices[j] maps a bind position to its posed position through joint j (jointWorld *
// inverseBindWorld, pipeline/pose.h skinMatrix()). Skinning is evaluated as p + sum_k w_k (M_k p - p),
// which equals sum_k w_k M_k p for weights summing to 1 (both sets must) but is exactly p at the bind
// pose, so quantization errors are not drowned in rounding of large coordinates.
// Throws INTERNAL when the sets do not match the positions or name a joint without a matrix.
DeformationError skinningDeformationError(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices);

// skinningDeformationError() at every frame of `frames` (each one skin matrix per joint), frames on
// `threads` threads (pipeline/parallel.h): the same figures to the bit, whatever the count.
std::vector<DeformationError> skinningDeformationErrors(const std::vector<Eigen::Vector3d>& bind_positions,
                                                        const InfluenceSet& reference, const InfluenceSet& approximation,
                                                        const std::vector<std::vector<Eigen::Affine3d>>& frames,
                                                        int threads);

// |p_reference - p_approximation| for each vertex, skinned as above (what skinningDeformationError
// summarizes; a report can map it onto the mesh).
std::vector<double> skinningDisplacements(const std::vector<Eigen::Vector3d>& bind_positions,
                                          const InfluenceSet& reference, const InfluenceSet& approximation,
                                          const std::vector<Eigen::Affine3d>& skin_matrices);

// The error over two vertex sets together (several mesh parts of one character); max_vertex numbers
// a's vertices first, then b's.
DeformationError combineDeformationErrors(const DeformationError& a, const DeformationError& b);

// The largest |w_a(v, j) - w_b(v, j)| over every vertex v and joint j either set names (a joint
// missing from a vertex weighs 0), e.g. what requantizing 0.001 weights to 1/65535 adds.
double maxWeightDifference(const InfluenceSet& a, const InfluenceSet& b);

}  // namespace rigbake
