// rigbake runtime: the muscle rig an engine evaluates every frame from its skeleton's joint matrices
// (the God of War Ragnarök talk's "+0 animation sampled joints": muscle joints are driven at run time,
// not played from clips). No dependency beyond the C++17 standard library, no allocation and no
// exception in Run(), no I/O. docs/runtime.md gives the equations and docs/muscle-model.md the anatomy.
//
// Data layout follows ozz-animation's runtime: a rig built once offline (rigbake writes it into the
// glTF as the RIGBAKE_muscle_rig extension; formats/ reads it back) holds flat arrays; a job struct
// takes spans the caller owns, says in Validate() whether they fit, and does the work in Run().
//
// Matrices are 4x4 affine transforms stored column-major, 16 numbers each, as glTF stores them:
// m[12], m[13], m[14] is the translation. "Model space" is whatever space the caller's joint matrices
// are in (an engine's model space, or rigbake's scene world space): every output is in that space.
//
// Real is float for engines and double for rigbake's own bake, which samples its channels through this
// very code so that a bake and a game cannot disagree about the equations.
#pragma once

#include <cstddef>
#include <vector>

namespace rigbake::runtime {

template <typename T>
struct Span {
  T* data = nullptr;
  std::size_t size = 0;
  Span() = default;
  Span(T* d, std::size_t n) : data(d), size(n) {}
  template <typename Container>
  Span(Container& c) : data(c.data()), size(c.size()) {}  // NOLINT: a span of a vector or array
  T& operator[](std::size_t i) const { return data[i]; }
  bool empty() const { return size == 0; }
};

// One key of a set-driven key curve: at driver value `at`, the skinned joint is offset by `up` and
// `side` (model-space units, along the muscle's rest up and side axes) and scaled across its fibre by
// `scale` (1 = unchanged). Between keys the response is linear; outside them the nearest key holds.
template <typename Real>
struct ResponseKey {
  Real at = 0;
  Real up = 0;
  Real side = 0;
  Real scale = 1;
};

// One muscle part, everything in the bind frames of the joints it rides on.
template <typename Real>
struct RigMuscle {
  int origin_joint = -1;     // joints are indices into the caller's joint matrix array
  int insertion_joint = -1;
  int carrier_joint = -1;    // the joint the skinned joint rides and takes its skin weight from
  Real origin_local[3] = {0, 0, 0};     // muscle origin locator in the origin joint's frame
  Real insertion_local[3] = {0, 0, 0};  // muscle insertion locator in the insertion joint's frame
  Real rest_length = 1;                 // |insertion - origin| at the bind pose, model-space units
  Real compression = Real(0.5);         // the length ratio is clamped to [compression, stretch]
  Real stretch = Real(1.5);
  // The rest fibre and up axis in the origin joint's frame (directions through its bind matrix, so the
  // carried directions are exact at the bind pose whatever scale the matrix has); the helpers carry them.
  Real fibre_local[3] = {1, 0, 0};
  Real up_local[3] = {0, 1, 0};
  // The twist driver: the insertion joint's turn about the rest fibre since the bind pose, relative to
  // the origin joint, both read as orthonormal frames: the fibre in the origin joint's orthonormal
  // frame, and the insertion joint's bind rotation relative to the origin joint's (x, y, z, w).
  Real twist_axis_local[3] = {1, 0, 0};
  Real insertion_bind_in_origin[4] = {0, 0, 0, 1};
  // The helper driver: origin + fraction * L * fibre + offset_up * up + offset_side * side.
  Real driver_fraction = Real(0.5);
  Real driver_offset[2] = {0, 0};
  // The skinned joint's bind transform relative to the carrier joint's frame (column-major 4x4).
  Real skinned_in_carrier[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  // Response keys: ratio keys (driver: clamped length ratio) then twist keys (driver: radians),
  // each run ascending in `at`, in MuscleRig::keys.
  int ratio_key_begin = 0;
  int ratio_key_count = 0;
  int twist_key_begin = 0;
  int twist_key_count = 0;
};

// How many muscles Run() evaluates side by side. Its lane loops run over this many muscles' numbers
// in plain arrays, which compilers turn into SIMD instructions (SSE2: 4 floats or 2 doubles at a time).
constexpr int kMuscleLanes = 4;

// The rig as Run() reads it, built by prepareMuscleRig() from the muscles and keys alone, so that Run()
// need not derive it every frame: kMuscleLanes muscles per block, each quantity an array over the
// lanes. Lanes past a block's count repeat its last muscle (evaluated, not written). Muscles whose
// twist moves the response come first, so that the blocks after them skip the twist, and within each
// group those carried by their origin, then by their insertion, then by another joint.
template <typename Real>
struct MuscleCurveLanes {  // one response curve (ratio or twist) per lane
  // The first key's values (rest 0, 0, 1 for a curve without keys).
  Real up[kMuscleLanes], side[kMuscleLanes], scale[kMuscleLanes];
};
template <typename Real>
struct MuscleSegmentLanes {  // the segment from key k to key k + 1 of one curve, per lane
  // 1 / (k+1.at - k.at) and the values' changes; a lane whose curve has no such segment has
  // from = +infinity and no change.
  Real from[kMuscleLanes], inverse_span[kMuscleLanes];
  Real up_change[kMuscleLanes], side_change[kMuscleLanes], scale_change[kMuscleLanes];
};
enum class MuscleCarriers {
  kOrigins,     // every lane's carrier is its origin joint
  kInsertions,  // every lane's carrier is its insertion joint
  kPicked,      // each lane's is its origin or its insertion joint (carrier_is_origin)
  kRead,        // some lane's is another joint: the carriers' matrices are read
};
template <typename Real>
struct MuscleLanes {
  int count = 0;             // muscles in this block, 1 to kMuscleLanes
  int muscle[kMuscleLanes];  // each lane's index in MuscleRig::muscles (and in the job's outputs)
  int origin_joint[kMuscleLanes], insertion_joint[kMuscleLanes], carrier_joint[kMuscleLanes];
  // Most carriers are the origin or the insertion joint, whose matrices a block reads anyway: where
  // the lane's carrier is the origin joint (1) or not (0), and where the block takes its carriers'.
  Real carrier_is_origin[kMuscleLanes];
  MuscleCarriers carriers = MuscleCarriers::kRead;
  Real origin_local[3][kMuscleLanes], insertion_local[3][kMuscleLanes];
  Real rest_length[kMuscleLanes], compression[kMuscleLanes], stretch[kMuscleLanes];
  // The twist driver's reference pair: two unit directions across the rest fibre a, u1 and
  // u2 = a x u1, in the origin joint's orthonormal frame, and the same two taken into the insertion
  // joint's orthonormal frame by the bind rotation, Q0^-1 u1 and Q0^-1 u2 (docs/runtime.md).
  Real origin_across[2][3][kMuscleLanes], insertion_across[2][3][kMuscleLanes];
  MuscleCurveLanes<Real> ratio_curve, twist_curve;
  // The skinned joint's bind transform in the carrier's frame: columns 0-3, rows 0-2.
  Real skinned_in_carrier[12][kMuscleLanes];
  // This block's segments in MuscleRig::segments: its ratio curves' (as many as the most keys of a
  // lane have, less one), then its twist curves'.
  int segment_begin = 0, ratio_segment_count = 0, twist_segment_count = 0;
  // Whether a lane's twist keys leave the rest response (up 0, side 0, scale 1): without, and without
  // drivers asked for, Run() does not read the block's twist, which could not change the response.
  bool twist_moves = false;
  // For the helpers.
  Real fibre_local[3][kMuscleLanes], up_local[3][kMuscleLanes];
  Real driver_fraction[kMuscleLanes], driver_offset[2][kMuscleLanes];
};

template <typename Real>
struct MuscleRig {
  int joint_count = 0;  // how many joint matrices a job must be given
  std::vector<RigMuscle<Real>> muscles;
  std::vector<ResponseKey<Real>> keys;
  // Filled by prepareMuscleRig() from the above; call it once they are in, and again after any change.
  // A job refuses a rig whose prepared muscle count is not its muscle count.
  std::vector<MuscleLanes<Real>> blocks;
  std::vector<MuscleSegmentLanes<Real>> segments;
  std::size_t prepared_muscles = 0;
};

// Fills rig->blocks and rig->segments from rig->muscles and rig->keys (allocates: once, not per
// frame). The rig must pass rigProblem().
template <typename Real>
void prepareMuscleRig(MuscleRig<Real>* rig);

// What a muscle's drivers read this frame.
template <typename Real>
struct MuscleDrivers {
  Real ratio = 1;          // length / rest length, unclamped
  Real clamped_ratio = 1;  // clamped to [compression, stretch]: what the ratio keys are read at
  Real twist = 0;          // radians, insertion joint about the fibre relative to the origin joint
};

// "" when the rig's indices, lengths and keys can be evaluated, else what is wrong (for loaders).
template <typename Real>
const char* rigProblem(const MuscleRig<Real>& rig);

// Evaluates every muscle of `rig` for one pose.
template <typename Real>
struct MuscleRigJob {
  const MuscleRig<Real>* rig = nullptr;
  // Input: rig->joint_count model-space joint matrices, 16 numbers each.
  Span<const Real> joint_matrices;
  // Output: one model-space matrix per muscle for its skinned joint (the joint the mesh is weighted
  // to), 16 numbers each. The skinning matrix is this times the joint's inverse bind matrix.
  Span<Real> skinned_matrices;
  // Optional output (leave empty to skip): per muscle the talk's helper joints base, tip and driver,
  // 3 x 16 numbers, in that order. Base sits at the origin with X aimed at the insertion, tip at the
  // insertion aimed back, driver point-constrained between them; all share the up axis carried by the
  // origin joint and swung with the fibre, so they never flip.
  Span<Real> helper_matrices;
  // Optional output (leave empty to skip): per muscle its drivers.
  Span<MuscleDrivers<Real>> drivers;

  bool Validate() const;
  // False (and nothing written) when Validate() fails.
  bool Run() const;
};

// The response of one muscle at its drivers: offsets along up and side and the across-fibre scale,
// the sum of its ratio curve and its twist curve (each an offset from the rest response).
template <typename Real>
ResponseKey<Real> evaluateResponse(const MuscleRig<Real>& rig, const RigMuscle<Real>& muscle,
                                   const MuscleDrivers<Real>& drivers);

extern template struct MuscleRigJob<float>;
extern template struct MuscleRigJob<double>;

}  // namespace rigbake::runtime
