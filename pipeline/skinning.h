// Skinning a mesh part for measurement: linear blend skinning (what glTF specifies and every engine
// does) and dual-quaternion skinning (the reference riggers compare volume with). Both take the same
// skin matrices as the rest of the pipeline: frame[j] maps a bind-pose world position to its posed
// world position through joint j (pipeline/pose.h skinMatrix()).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

// p' = sum_k w_k M_{j_k} p, written as p + sum_k w_k (M_{j_k} p - p) so that the bind pose gives p
// exactly. Weights are used as given (normalize them first if they do not sum to 1).
std::vector<Eigen::Vector3d> skinLinearBlend(const std::vector<Eigen::Vector3d>& bind_positions,
                                             const InfluenceSet& influences,
                                             const std::vector<Eigen::Affine3d>& frame);

// The same for the listed vertices only, into (*posed)[i] for vertices[i] (resized to fit, so a caller
// can reuse it): skinLinearBlend(...)[vertices[i]] to the bit, e.g. a VolumeSurface's welded vertices.
void skinLinearBlend(const std::vector<Eigen::Vector3d>& bind_positions, const InfluenceSet& influences,
                     const std::vector<Eigen::Affine3d>& frame, const std::vector<int>& vertices,
                     std::vector<Eigen::Vector3d>* posed);

// Each skin matrix split once per frame into what dual quaternions blend (rotation and translation)
// and what they cannot (the symmetric stretch of the polar decomposition, M = T R S).
struct DualQuaternionFrame {
  std::vector<Eigen::Quaterniond> real;  // rotation R, hemisphere of the first joint's is chosen per vertex
  std::vector<Eigen::Quaterniond> dual;  // 0.5 t R as a pure quaternion product
  std::vector<Eigen::Matrix3d> stretch;  // S; the identity for rigid joints
};
DualQuaternionFrame dualQuaternionFrame(const std::vector<Eigen::Affine3d>& frame);

// One skin matrix split as dualQuaternionFrame() splits each of its joints, to the bit: the unit
// rotation quaternion, the dual part and the stretch.
void splitDualQuaternion(const Eigen::Affine3d& matrix, Eigen::Quaterniond* real, Eigen::Quaterniond* dual,
                         Eigen::Matrix3d* stretch);

// Dual-quaternion linear blending (Kavan, Collins, Zara, O'Sullivan, "Geometric Skinning with
// Approximate Dual Quaternion Blending", ACM TOG 27(4), 2008): blend the unit dual quaternions with the
// vertex's weights, flipping each into the hemisphere of the vertex's strongest joint, normalize, and
// apply. Non-rigid joints follow the paper's section 4.1: their stretch S is blended linearly and
// applied first, in bind space.
std::vector<Eigen::Vector3d> skinDualQuaternion(const std::vector<Eigen::Vector3d>& bind_positions,
                                                const InfluenceSet& influences, const DualQuaternionFrame& frame);

// The three skinnings the deformation-quality figures compare, of the listed vertices in one pass:
// linear blend and dual quaternions of `input` and linear blend of `rig` (joints of the skeleton and
// beyond, in `frame`; `dual_quaternions` splits the skeleton's joints). The same bits as
// skinLinearBlend() and skinDualQuaternion() each; a joint both weight sets use at a vertex is
// transformed once.
void skinInputAndRig(const std::vector<Eigen::Vector3d>& bind_positions, const InfluenceSet& input,
                     const InfluenceSet& rig, const std::vector<Eigen::Affine3d>& frame,
                     const DualQuaternionFrame& dual_quaternions, const std::vector<int>& vertices,
                     std::vector<Eigen::Vector3d>* input_linear, std::vector<Eigen::Vector3d>* input_dual_quaternion,
                     std::vector<Eigen::Vector3d>* rig_linear);

}  // namespace rigbake
