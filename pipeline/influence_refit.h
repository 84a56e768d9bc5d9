// The kept joints and weights refitted to the motion they stand for. Pruning a vertex to its n largest
// weights and rescaling them (pruneInfluences()) drops the rest of its blend: where the dropped joints
// move differently from the kept ones, the vertex leaves the full rig's path (Cowboy at 4 influences:
// 310 mm at worst, 20.6 mm root mean square; a lower back region of CesiumMan 6.35 points of volume
// beyond plain skinning). Here each pruned vertex takes the n of its joints, and the weights on them,
// non-negative and summing to 1, whose linear blend follows the full weights' blend closest over the
// character's frames, in the least-squares sense: the weight step of skinning decomposition (Le and
// Deng, "Smooth Skinning Decomposition with Rigid Bones", SIGGRAPH Asia 2012, section 4), with the
// joints chosen from the vertex's own full row. docs/muscle-weights.md, "Refitting the kept weights".
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "pipeline/influences.h"
#include "pipeline/quantize_for_motion.h"

namespace rigbake {

// At most this many frames, evenly strided over `frames`, enter each vertex's fit.
constexpr size_t kRefitFrames = 512;
// Rows with more kept weights than this are left as pruned (the bake keeps 4, 7 or 10).
constexpr int kRefitMaxKept = 10;

// For every vertex of `kept` (pruned from `full`, the same vertices) that lost a weight: chooses which m
// of its full row's joints to keep (m its kept count) and their weights u >= 0, sum u = 1, minimising
// sum_t |sum_k u_k M_k(t) x - sum_j w_j M_j(t) x|^2, with x its bind position (`bind`), w its full
// weights and M(t) the skinning matrices of frame t (every joint, muscle joints included). The search
// starts from the pruned joints and swaps one kept joint for a dropped one while that lowers the
// minimum, so no vertex follows the full blend worse than its pruned joints refitted. The rows come back
// in canonical order (weights descending, then joint index; a weight the fit sets to 0 leaves its slot).
// Without frames nothing changes. Each vertex is fitted on its own: the same at any thread count, and
// the same for two vertices with the same weights and bind position (a border between meshes keeps one
// row).
void refitKeptWeights(const InfluenceSet& full, const std::vector<Eigen::Vector3d>& bind, const std::vector<SkinFrame>& frames,
                      InfluenceSet* kept, int threads);

}  // namespace rigbake
