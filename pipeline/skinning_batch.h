// Skinning every vertex of a mesh part at every sampled frame, for the figures the bake measures
// (volumes, deformation error), in single-precision SIMD: SSE2, which every x86-64 processor has, so
// the results are the same bits on any machine that runs the bake (no wider or fused instructions are
// chosen at run time).
//
// Vertices that are weighted to the same joints, in the same order, are skinned four at a time, one per
// SSE lane: their joints' matrices are the same, so each matrix entry is loaded once, already in all
// four lanes, and nothing has to be gathered or shuffled. Each joint's d_k = (M_k - I) p is blended with
// up to four weight sets: sum_k w_set,k d_k is the offset of linear blend skinning
// p' = p + sum_k w_k (M_k p - p) (pipeline/skinning.h), or, for a set that is the difference of two
// weight sets, how far one set's skin is from the other's. The first set is also skinned by dual
// quaternions (Kavan, Collins, Zara, O'Sullivan, "Geometric Skinning with Approximate Dual Quaternion
// Blending", ACM TOG 27(4), 2008), as pipeline/skinning.cpp skinDualQuaternion() does in double.
//
// Single precision is enough for what is measured: positions are relative to a centre near the mesh
// (so their rounding is relative to the body's size, not to its distance from the scene origin) and
// within about 1e-7 of that size of the double result; volumes are summed in double; and an offset from
// a difference of weights is blended from the weight differences themselves (not as the difference of
// two positions), so it keeps seven significant digits however small it is. Callers that report an
// extreme to more digits recompute it in double (pipeline/bake.cpp).
#pragma once

#if !defined(__SSE2__)
#error "rigbake's measuring loops use SSE2 intrinsics (every x86-64 processor has them)"
#endif

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

// Four floats in one SSE register's layout.
struct alignas(16) Float4 {
  float v[4] = {0.0f, 0.0f, 0.0f, 0.0f};
};

constexpr int kSkinLanes = 4;  // vertices skinned together
constexpr int kSkinSets = 4;   // weight sets blended together

// The weights of one set: `plus` minus `minus` per joint (either may be null).
struct SetWeights {
  const InfluenceSet* plus = nullptr;
  const InfluenceSet* minus = nullptr;
};

// The rows of a frame's sign table, one per joint that is some vertex's first dual-quaternion joint:
// shared by every batch skinned with one FloatSkinFrame.
struct DualQuaternionPivots {
  std::vector<int> joints;        // pivot joints, in the order their rows are laid out
  std::vector<int> row_of_joint;  // joint -> row, -1 when no vertex starts with it
  int rowOf(int joint);           // adds a row when the joint has none
};

// A mesh part's vertices in groups of four that share their joints (padded with empty lanes): group
// g's slots [first_slot[g], first_slot[g + 1]) are joints[s], ascending, each with
// weights[kSkinSets * s + set] holding that set's weight in each lane. Positions are relative to
// `centre`, which must be the FloatSkinFrame's.
struct SkinningBatch {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<std::int32_t> vertex;       // kSkinLanes per group: the part's vertex, -1 for an empty lane
  std::vector<Float4> positions;          // 3 per group: x, y and z of the bind positions minus centre
  std::vector<std::uint32_t> first_slot;  // groups + 1
  std::vector<std::uint16_t> joints;
  std::vector<Float4> weights;
  // Dual quaternions of set 0: its joints are among the group's first dual_quaternion_slots[g] slots
  // (those below dual_quaternion_joints; 0 skips them), each flipped into the hemisphere of the joint
  // that comes first in set 0's own slot order, the pivot.
  std::vector<std::uint8_t> dual_quaternion_slots;
  std::vector<std::int32_t> pivot_row;  // DualQuaternionPivots row of the pivot
  std::vector<Float4> inverse_total;    // 1 / the sum of set 0's weights (the stretch blend divides by it)
  size_t groups() const { return first_slot.empty() ? 0 : first_slot.size() - 1; }
};

// Lays out `vertices` (indices into bind_positions and the sets) with the weights of each set, grouped
// by their joints (in the order of `vertices` within a group); where dual_quaternions[i] is set,
// vertices[i] is also skinned by dual quaternions of set 0, whose joints must then be below
// dual_quaternion_joints (FloatSkinFrame splits those). Joints that repeat in a vertex's slots are
// merged. A set's offset at a vertex is the same bits whatever the other sets are: its nonzero terms
// come in ascending joint order, and the others' joints add exact zeros. Throws INTERNAL for a joint
// beyond 65535 or without a dual quaternion. The same batch at any thread count.
SkinningBatch buildSkinningBatch(const std::vector<Eigen::Vector3d>& bind_positions, const std::vector<int>& vertices,
                                 const Eigen::Vector3d& centre, const std::array<SetWeights, kSkinSets>& sets,
                                 const std::vector<char>& dual_quaternions, int dual_quaternion_joints,
                                 DualQuaternionPivots* pivots, int threads);

// One sampled frame in single precision, about `centre` c: each skin matrix as the map of p - c to
// M p - c, every entry already in all four lanes. linear: 12 per joint, row r column k at 4 r + k, of
// M - I with the centred translation t + (M - I) c as column 3. The first dual_quaternion_joints joints
// are also split for dual quaternions (pipeline/skinning.h splitDualQuaternion()): dual_quaternion, 8
// per joint, the real part's x, y, z, w then the dual part's, and per pivot row the sign bit that flips
// each joint's quaternion into the pivot's hemisphere (decided in double, as the double skinning
// decides). When every joint is rigid the split is of the centred map (dual-quaternion blending of
// rigid transforms commutes with the change of centre); otherwise of M itself, with the stretch's rows
// (12 per joint: S and S c as column 3), and the skinning goes through scene coordinates, as the
// stretch is applied in bind space.
struct FloatSkinFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<Float4> linear;
  int dual_quaternion_joints = 0;
  std::vector<Float4> dual_quaternion;
  bool rigid = true;            // every stretch is the identity to 1e-12: skinning skips it
  std::vector<Float4> stretch;  // when not rigid
  std::array<Float4, 3> centre_lanes;  // c's x, y and z, each in all lanes
  std::vector<std::uint32_t> signs;    // [row * dual_quaternion_joints + joint]
  // max_j (|L_j - I|_F + |t'_j|) over the joints: |d_k| <= reach (|p - c| + 1), for bounding rounding.
  double reach = 0.0;
  // The split in double, kept from frame to frame.
  std::vector<std::array<double, 4>> real_double;
  std::vector<Eigen::Matrix3d> stretch_double;
};

// Fills `out` (reusing its storage) from one frame's skin matrices.
void prepareFloatSkinFrame(const std::vector<Eigen::Affine3d>& frame, const Eigen::Vector3d& centre,
                           int dual_quaternion_joints, const DualQuaternionPivots& pivots, FloatSkinFrame* out);

// One group skinned: lanes are the group's vertices.
struct SkinnedGroup {
  __m128 x, y, z;                                  // bind position minus centre
  __m128 offset[kSkinSets][3];                     // sum_k w_set,k d_k: x, y, z
  __m128 dual_quaternion[3];                       // dual-quaternion position minus centre (x, y, z)
};

namespace skinning_batch_detail {

inline __m128 splat(const Float4& value) { return _mm_load_ps(value.v); }

// Dual-quaternion positions of group g (the algorithm of skinning.cpp's dualQuaternionVertex(), in
// four lanes).
inline void dualQuaternionGroup(const SkinningBatch& batch, size_t g, const FloatSkinFrame& frame, SkinnedGroup* out) {
  const std::uint32_t first = batch.first_slot[g];
  const std::uint32_t last = first + batch.dual_quaternion_slots[g];
  const std::uint32_t* signs =
      frame.signs.data() + static_cast<size_t>(batch.pivot_row[g]) * static_cast<size_t>(frame.dual_quaternion_joints);
  __m128 real[4], dual[4];
  for (int k = 0; k < 4; ++k) real[k] = dual[k] = _mm_setzero_ps();
  __m128 stretch[12];
  if (!frame.rigid)
    for (__m128& s : stretch) s = _mm_setzero_ps();
  for (std::uint32_t s = first; s < last; ++s) {
    const size_t joint = batch.joints[s];
    const __m128 weight = splat(batch.weights[kSkinSets * static_cast<size_t>(s)]);
    const __m128 flipped = _mm_xor_ps(weight, _mm_castsi128_ps(_mm_set1_epi32(static_cast<int>(signs[joint]))));
    const Float4* q = &frame.dual_quaternion[8 * joint];
    for (int k = 0; k < 4; ++k) {
      real[k] = _mm_add_ps(real[k], _mm_mul_ps(flipped, splat(q[k])));
      dual[k] = _mm_add_ps(dual[k], _mm_mul_ps(flipped, splat(q[4 + k])));
    }
    if (!frame.rigid) {
      const Float4* rows = &frame.stretch[12 * joint];
      for (int k = 0; k < 12; ++k) stretch[k] = _mm_add_ps(stretch[k], _mm_mul_ps(weight, splat(rows[k])));
    }
  }
  __m128 v[3] = {out->x, out->y, out->z};
  if (!frame.rigid) {
    // S (p - c) + S c: the stretched bind position in scene coordinates.
    const __m128 inverse_total = splat(batch.inverse_total[g]);
    for (int r = 0; r < 3; ++r) {
      const __m128* row = stretch + 4 * r;
      v[r] = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(row[0], out->x), _mm_mul_ps(row[1], out->y)),
                                   _mm_add_ps(_mm_mul_ps(row[2], out->z), row[3])),
                        inverse_total);
    }
  }
  // With q = (u, w) the blended real part and n = |q|^2, the normalized rotation of v is
  // v + (w t + u x t) / n with t = 2 u x v, and the translation, the vector part of 2 e r* for the
  // normalized parts, is 2 (w e_u - e_w u - e_u x u) / n: one division and no square root.
  const __m128 n = _mm_add_ps(_mm_add_ps(_mm_mul_ps(real[0], real[0]), _mm_mul_ps(real[1], real[1])),
                              _mm_add_ps(_mm_mul_ps(real[2], real[2]), _mm_mul_ps(real[3], real[3])));
  const __m128 inverse = _mm_div_ps(_mm_set1_ps(1.0f), n);
  auto cross = [](const __m128* a, const __m128* b, __m128* c) {
    c[0] = _mm_sub_ps(_mm_mul_ps(a[1], b[2]), _mm_mul_ps(a[2], b[1]));
    c[1] = _mm_sub_ps(_mm_mul_ps(a[2], b[0]), _mm_mul_ps(a[0], b[2]));
    c[2] = _mm_sub_ps(_mm_mul_ps(a[0], b[1]), _mm_mul_ps(a[1], b[0]));
  };
  const __m128 w = real[3], e_w = dual[3];
  __m128 t[3], u_t[3], e_u_u[3];
  cross(real, v, t);
  for (__m128& c : t) c = _mm_add_ps(c, c);
  cross(real, t, u_t);
  cross(dual, real, e_u_u);
  for (int r = 0; r < 3; ++r) {
    const __m128 half_translation = _mm_sub_ps(_mm_sub_ps(_mm_mul_ps(w, dual[r]), _mm_mul_ps(e_w, real[r])), e_u_u[r]);
    const __m128 turned = _mm_add_ps(_mm_add_ps(_mm_mul_ps(w, t[r]), u_t[r]), _mm_add_ps(half_translation, half_translation));
    out->dual_quaternion[r] = _mm_add_ps(v[r], _mm_mul_ps(turned, inverse));
    if (!frame.rigid) out->dual_quaternion[r] = _mm_sub_ps(out->dual_quaternion[r], splat(frame.centre_lanes[r]));
  }
}

}  // namespace skinning_batch_detail

// Skins groups [begin, end) of `batch` at `frame` and calls visit(g, group) for each, with the sets of
// kSetMask (bit s: set s) blended (the others' offsets are left unset). An entry without dual
// quaternions gets its bind position as dual_quaternion.
template <unsigned kSetMask, typename Visit>
void skinSkinningBatch(const SkinningBatch& batch, const FloatSkinFrame& frame, size_t begin, size_t end, Visit&& visit) {
  using skinning_batch_detail::splat;
  const Float4* linear = frame.linear.data();
  SkinnedGroup group{};  // value-initialized: GCC 12 may otherwise flag offset sets a mask leaves unset (-Wmaybe-uninitialized)
  for (size_t g = begin; g < end; ++g) {
    group.x = splat(batch.positions[3 * g]);
    group.y = splat(batch.positions[3 * g + 1]);
    group.z = splat(batch.positions[3 * g + 2]);
    for (int s = 0; s < kSkinSets; ++s)
      if (kSetMask & (1u << s))
        for (__m128& c : group.offset[s]) c = _mm_setzero_ps();
    const std::uint32_t last = batch.first_slot[g + 1];
    for (std::uint32_t slot = batch.first_slot[g]; slot < last; ++slot) {
      const Float4* m = linear + 12 * static_cast<size_t>(batch.joints[slot]);
      __m128 d[3];
      for (int r = 0; r < 3; ++r)
        d[r] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(splat(m[4 * r]), group.x), _mm_mul_ps(splat(m[4 * r + 1]), group.y)),
                          _mm_add_ps(_mm_mul_ps(splat(m[4 * r + 2]), group.z), splat(m[4 * r + 3])));
      const Float4* weights = &batch.weights[kSkinSets * static_cast<size_t>(slot)];
      for (int s = 0; s < kSkinSets; ++s) {
        if (!(kSetMask & (1u << s))) continue;
        const __m128 weight = splat(weights[s]);
        for (int r = 0; r < 3; ++r) group.offset[s][r] = _mm_add_ps(group.offset[s][r], _mm_mul_ps(weight, d[r]));
      }
    }
    if (batch.dual_quaternion_slots[g] > 0) {
      skinning_batch_detail::dualQuaternionGroup(batch, g, frame, &group);
    } else {
      group.dual_quaternion[0] = group.x;
      group.dual_quaternion[1] = group.y;
      group.dual_quaternion[2] = group.z;
    }
    visit(g, group);
  }
}

}  // namespace rigbake
