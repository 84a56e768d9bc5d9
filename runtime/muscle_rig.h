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

template <typename Real>
struct MuscleRig {
  int joint_count = 0;  // how many joint matrices a job must be given
  std::vector<RigMuscle<Real>> muscles;
  std::vector<ResponseKey<Real>> keys;
};

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
