// Skinning with optimized centres of rotation: Binh Huy Le and Jessica K. Hodgins, "Real-time Skeletal
// Skinning with Optimized Centers of Rotation", ACM TOG 35(4) (SIGGRAPH 2016). Plain skinning's
// weights and cost, without its collapse at bent joints (it blends rotations as quaternions) and
// without dual quaternions' bulge (each vertex turns about a centre that skin of similar weights
// surrounds, not about the joints). rigbake uses it as a yardstick beside plain and dual-quaternion
// skinning (docs/deformation-quality.md); the figures compare the rig with all three.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "anatomy/character.h"
#include "pipeline/influences.h"
#include "pipeline/skinning.h"

namespace rigbake {

// The paper's weight similarity (its equation 3): sum over joint pairs j != k of
// w_pj w_pk w_vj w_vk exp(-(w_pj w_vk - w_pk w_vj)^2 / sigma^2), sigma = 0.1 (the paper's value).
// Zero unless both weight vectors have at least two joints in common.
constexpr double kCorSigma = 0.1;
struct SparseWeights {
  std::vector<std::pair<int, double>> entries;  // joint ascending, weights > 0
};
double weightSimilarity(const SparseWeights& p, const SparseWeights& v);

// Per vertex of `mesh` (weights `influences`, normalized), its centre of rotation (equation 4):
// p*_i = sum_t s(w_i, w_t) a_t c_t / sum_t s(w_i, w_t) a_t over the mesh's triangles t, with w_t the
// mean of the triangle's corner weights, a_t its area and c_t its centroid. Triangles whose mean
// weights agree to 1/64 are summed as one (area-weighted), as the paper clusters them. A vertex that no
// triangle resembles (one joint, or a blend found nowhere else) has no centre: has_centre[v] = 0, and it
// is skinned by linear blending, to which the method reduces for one joint. On `threads` threads; the
// same result at any count.
struct RotationCentres {
  std::vector<Eigen::Vector3d> centre;
  std::vector<char> has_centre;
};
RotationCentres optimizedRotationCentres(const MeshPart& mesh, const InfluenceSet& influences, int threads = 1);

// Equation 5: q = the weights' blend of the joints' rotations as quaternions (each in the hemisphere of
// the vertex's first joint), normalized, R its matrix; t = sum_j w_j M_j p* - R p*; v' = R v + t.
// `frame` holds the skin matrices, `rotations` their rotations as dualQuaternionFrame() splits them.
std::vector<Eigen::Vector3d> skinCentreOfRotation(const std::vector<Eigen::Vector3d>& bind_positions,
                                                  const InfluenceSet& influences, const RotationCentres& centres,
                                                  const std::vector<Eigen::Affine3d>& frame,
                                                  const DualQuaternionFrame& rotations);

}  // namespace rigbake
