// The runtime muscle rig. Sources:
// - God of War Ragnarök rigging talk (Tenghao Wang), "Muscle Joint Group": origin and insertion
//   locators ride their attach joints, base and tip aim at each other, the driver is point-constrained
//   between them, and set driven keys on the muscle's length give the bulge ("Constraints and SDK are
//   supported in-engine"). The length ratio is clamped to [compression, stretch] as createFromAttachObjs'
//   compressionFactor / stretchFactor do.
// - The aim matrix of "Rigging with Triangles" (GDC 2018): X aims, the up vector is made orthogonal,
//   Z = X x Y; the up vector is carried by the origin joint and swung by the minimal rotation
//   (Rodrigues) that takes the carried rest fibre to the current fibre, so it never flips.
// - Swing-twist decomposition of a rotation about an axis (the twist is the quaternion's projection
//   on that axis), for the twist driver; read here from the joints' frames (docs/runtime.md).
// - Data-oriented layout in the manner of ozz-animation's SoA jobs: what is computed per muscle across
//   the muscles (the drivers, the response curves, the helpers) runs kMuscleLanes muscles at a time,
//   each quantity an array over the lanes, so that the compiler's loop vectorizer puts a step of every
//   lane in one SIMD instruction; what works on one matrix at a time (the locators, the skinned
//   matrix) runs muscle by muscle on the matrices' four-number columns, which its straight-line
//   vectorizer packs the same way. Lane loops hold straight-line code (selects, no branches), which is
//   what the loop vectorizer needs.
// rigbake's skinned joint rides its carrier joint (the joint it takes its skin weight from), so that a
// muscle at rest response reproduces the input skinning exactly, and moves by the response alone:
// docs/muscle-model.md says why (measured: following the driver point costs the shoulder 30 % of its
// volume).
#include "runtime/muscle_rig.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace rigbake::runtime {
namespace {

constexpr int kLanes = kMuscleLanes;

// GCC unrolls a short loop completely before its loop vectorizer runs, which leaves scalar code with
// branches; told not to, it vectorizes the lane loop (GCC 12, SSE2). Other compilers decide alone.
#if defined(__GNUC__) && !defined(__clang__)
#define RIGBAKE_LANE_LOOP _Pragma("GCC unroll 1")
#else
#define RIGBAKE_LANE_LOOP
#endif

template <typename Real>
struct Vec3 {
  Real x, y, z;
};

template <typename Real>
inline Vec3<Real> operator+(Vec3<Real> a, Vec3<Real> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename Real>
inline Vec3<Real> operator-(Vec3<Real> a, Vec3<Real> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename Real>
inline Vec3<Real> operator*(Real s, Vec3<Real> a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename Real>
inline Real dot(Vec3<Real> a, Vec3<Real> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename Real>
inline Vec3<Real> cross(Vec3<Real> a, Vec3<Real> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Real>
inline Real select(bool condition, Real a, Real b) { return condition ? a : b; }
template <typename Real>
inline Vec3<Real> select(bool condition, Vec3<Real> a, Vec3<Real> b) {
  return {select(condition, a.x, b.x), select(condition, a.y, b.y), select(condition, a.z, b.z)};
}
// a / |a|, a zero vector staying zero. Both sides of the select are computed, so that a lane loop has
// no branch (the zero lane's unused quotient is inf).
template <typename Real>
inline Vec3<Real> normalized(Vec3<Real> a) {
  const Real n = std::sqrt(dot(a, a));
  return select(n > Real(0), Real(1) / n, Real(1)) * a;
}
template <typename Real>
inline Real clampValue(Real v, Real lo, Real hi) { return v < lo ? lo : (v > hi ? hi : v); }

// One lane of a quantity stored [component][lane].
template <typename Real>
inline Vec3<Real> lane(const Real (*v)[kLanes], int l) { return {v[0][l], v[1][l], v[2][l]}; }
template <typename Real>
inline void setLane(Real (*v)[kLanes], int l, Vec3<Real> value) {
  v[0][l] = value.x;
  v[1][l] = value.y;
  v[2][l] = value.z;
}

// Each lane's joint matrix as its 12 affine numbers, [column * 3 + row][lane].
template <typename Real>
struct JointLanes {
  Real m[12][kLanes];
  Vec3<Real> column(int c, int l) const { return {m[3 * c][l], m[3 * c + 1][l], m[3 * c + 2][l]}; }
  // The matrix applied to a direction and to a point, summed in the order of the matrix product
  // (column 0 first, the translation last).
  Vec3<Real> direction(int l, Vec3<Real> d) const {
    return {m[0][l] * d.x + m[3][l] * d.y + m[6][l] * d.z, m[1][l] * d.x + m[4][l] * d.y + m[7][l] * d.z,
            m[2][l] * d.x + m[5][l] * d.y + m[8][l] * d.z};
  }
  Vec3<Real> point(int l, Vec3<Real> p) const { return direction(l, p) + column(3, l); }
};

template <typename Real>
void gatherJoints(const Real* joints, const int* joint, JointLanes<Real>* out) {
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    const Real* m = joints + 16 * joint[l];
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 3; ++r) out->m[3 * c + r][l] = m[4 * c + r];
    }
  }
}

// The rotation of a joint matrix as an orthonormal frame: its first two columns made orthonormal
// (Gram-Schmidt; exact for a rotation times a uniform scale, the nearest frame for anything else).
template <typename Real>
struct Frame {
  Vec3<Real> x, y, z;
  Vec3<Real> apply(Vec3<Real> d) const {
    return {x.x * d.x + y.x * d.y + z.x * d.z, x.y * d.x + y.y * d.y + z.y * d.z, x.z * d.x + y.z * d.y + z.z * d.z};
  }
};
template <typename Real>
inline Frame<Real> orthonormalFrame(Vec3<Real> column0, Vec3<Real> column1) {
  const Vec3<Real> x = normalized(column0);
  const Vec3<Real> y = normalized(column1 - dot(column1, x) * x);
  return {x, y, cross(x, y)};
}

// atan(t) ~ t p(t^2) on |t| <= tan(pi/8): p is the Chebyshev fit to atan(sqrt(s)) / sqrt(s) on
// s in [0, tan^2(pi/8)] (mpmath.chebyfit), of degree 4 for float (error 1.8e-8) and 10 for double
// (3.5e-17). glibc's atan2f takes some 25 ns, a quarter of the float rig's 1 us budget, and no library
// atan2 runs in a SIMD lane.
template <typename Real>
struct ArcTangent;
template <>
struct ArcTangent<float> {
  static constexpr int kCount = 5;
  static constexpr float kCoefficients[kCount] = {0.07976291806794557910f, -0.1384849021226920766f, 0.1997408241550766711f,
                                                  -0.3333278577192484365f, 0.9999999812646111210f};
};
template <>
struct ArcTangent<double> {
  static constexpr int kCount = 11;
  static constexpr double kCoefficients[kCount] = {
      0.02113537315769324521,  -0.04348052215716462478, 0.05688349226809010479, -0.06640233930429408589,
      0.07689953496306857756,  -0.09090773074808413790, 0.1111110618045594522,  -0.1428571418097646683,
      0.1999999999885511013,   -0.3333333333332843857,  0.9999999999999999653};
};

constexpr double kPi = 3.14159265358979323846;

// atan2(y[l], x[l]) in [-pi, pi] for every lane: with t = min / max of |x|, |y|, atan(t) directly for
// t <= tan(pi/8), else pi/4 + atan((t - 1) / (t + 1)), then moved to its octant. One division: the
// reduced argument is (min - max) / (min + max). Against atan2l over 2e7 random pairs: 4.8e-16 rad in
// double, 2.7e-7 in float (glibc's atan2f: 2.5e-7), both about an ulp of pi.
template <typename Real>
void arcTangent2(const Real* y, const Real* x, Real* angle) {
  const Real tan_eighth = Real(0.41421356237309504880);
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    const Real ax = std::fabs(x[l]), ay = std::fabs(y[l]);
    const Real high = ax > ay ? ax : ay;
    const Real low = ax > ay ? ay : ax;
    const bool reduced = low > tan_eighth * high;
    const Real t = select(reduced, low - high, low) / select(reduced, low + high, select(high > Real(0), high, Real(1)));
    const Real s = t * t;
    Real p = ArcTangent<Real>::kCoefficients[0];
    for (int k = 1; k < ArcTangent<Real>::kCount; ++k) p = p * s + ArcTangent<Real>::kCoefficients[k];
    const Real octant = select(reduced, static_cast<Real>(kPi / 4), Real(0)) + t * p;
    const Real quadrant = select(ay > ax, static_cast<Real>(kPi / 2) - octant, octant);
    const Real half = select(x[l] < Real(0), static_cast<Real>(kPi) - quadrant, quadrant);
    angle[l] = std::copysign(half, y[l]);
  }
}

// Below this fraction of the rest length the fibre has no direction; the carried rest fibre stands in.
template <typename Real>
constexpr Real kMinLengthFraction = Real(1e-6);
// 1 + cos(angle) below which the fibre has reversed relative to its origin joint.
template <typename Real>
constexpr Real kReversedFibre = Real(1e-12);

// One response curve, as docs/extensions/RIGBAKE_muscle_rig.md states it: the nearest key outside the
// keys, linear between them.
template <typename Real>
void addCurve(const ResponseKey<Real>* keys, int count, Real at, ResponseKey<Real>* sum) {
  if (count <= 0) return;
  ResponseKey<Real> value = keys[0];
  if (at >= keys[count - 1].at) {
    value = keys[count - 1];
  } else if (at > keys[0].at) {
    int k = 1;
    while (keys[k].at < at) ++k;  // keys[k - 1].at < at <= keys[k].at
    const ResponseKey<Real>& a = keys[k - 1];
    const ResponseKey<Real>& b = keys[k];
    const Real span = b.at - a.at;
    const Real t = span > Real(0) ? (at - a.at) / span : Real(1);
    value.up = a.up + t * (b.up - a.up);
    value.side = a.side + t * (b.side - a.side);
    value.scale = a.scale + t * (b.scale - a.scale);
  }
  sum->up += value.up;
  sum->side += value.side;
  sum->scale += value.scale - Real(1);
}

// What a block's lanes compute, stage by stage.
template <typename Real>
struct BlockState {
  JointLanes<Real> origin_joint, insertion_joint, carrier_joint;
  Real origin[3][kLanes], insertion[3][kLanes], segment[3][kLanes];
  Real length[kLanes], ratio[kLanes], clamped_ratio[kLanes], twist[kLanes];
  Real up[kLanes], side[kLanes], scale[kLanes];  // the response
};

// Each lane's carrier matrix from its origin's or its insertion's (MuscleCarriers::kPicked).
template <typename Real>
void pickCarriers(const MuscleLanes<Real>& block, BlockState<Real>* s) {
  for (int e = 0; e < 12; ++e) {
    RIGBAKE_LANE_LOOP
    for (int l = 0; l < kLanes; ++l) {
      s->carrier_joint.m[e][l] = select(block.carrier_is_origin[l] > Real(0), s->origin_joint.m[e][l], s->insertion_joint.m[e][l]);
    }
  }
}

// The locators o = W_o (o_l, 1) and i = W_i (i_l, 1), the length ratio r = |i - o| / L_rest and
// r_c = clamp(r, compression, stretch).
template <typename Real>
void evaluateLocators(const MuscleLanes<Real>& block, BlockState<Real>* s) {
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    const Vec3<Real> origin = s->origin_joint.point(l, lane(block.origin_local, l));
    const Vec3<Real> insertion = s->insertion_joint.point(l, lane(block.insertion_local, l));
    const Vec3<Real> segment = insertion - origin;
    const Real length = std::sqrt(dot(segment, segment));
    const Real ratio = length / block.rest_length[l];
    setLane(s->origin, l, origin);
    setLane(s->insertion, l, insertion);
    setLane(s->segment, l, segment);
    s->length[l] = length;
    s->ratio[l] = ratio;
    s->clamped_ratio[l] = clampValue(ratio, block.compression[l], block.stretch[l]);
  }
}

// The twist driver: the angle about the rest fibre from the origin joint's reference pair (u1, u2) to
// the insertion joint's (v1, v2), each carried by its joint's orthonormal frame,
//   theta = atan2(u2.v1 - u1.v2, u1.v1 + u2.v2),
// which is the swing-twist twist 2 atan2(delta.xyz . a, delta.w) of delta = R_o^-1 R_i Q0^-1: with D its
// matrix, u_j.v_k = e_j^T D e_k in the frame (u1, u2, a), so the arguments are a . vee(D - D^T) =
// 4 w (v . a) and tr D - a^T D a = 2 (w^2 - (v . a)^2) for delta = (v, w), and atan2 of those is twice
// atan2(v . a, w). docs/runtime.md.
template <typename Real>
void evaluateTwist(const MuscleLanes<Real>& block, BlockState<Real>* s) {
  Real along[kLanes], across[kLanes];
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    const Frame<Real> origin = orthonormalFrame(s->origin_joint.column(0, l), s->origin_joint.column(1, l));
    const Vec3<Real> u1 = origin.apply(lane(block.origin_across[0], l));
    const Vec3<Real> u2 = origin.apply(lane(block.origin_across[1], l));
    const Frame<Real> insertion = orthonormalFrame(s->insertion_joint.column(0, l), s->insertion_joint.column(1, l));
    const Vec3<Real> v1 = insertion.apply(lane(block.insertion_across[0], l));
    const Vec3<Real> v2 = insertion.apply(lane(block.insertion_across[1], l));
    along[l] = dot(u2, v1) - dot(u1, v2);
    across[l] = dot(u1, v1) + dot(u2, v2);
  }
  arcTangent2(along, across, s->twist);
  // atan2 gives [-pi, pi]; the twist is in (-pi, pi].
  const Real pi = static_cast<Real>(kPi);
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) s->twist[l] = select(s->twist[l] <= -pi, s->twist[l] + Real(2) * pi, s->twist[l]);
}

// One curve per lane at `driver`, added to the response: the first key's value plus each segment's
// change times how far the driver has come through it, t = clamp((driver - from) / span, 0, 1). Below
// the first key every t is 0, from the last key on every t is 1, in between the segment holding the
// driver adds its share: addCurve()'s value, summed in another order.
template <typename Real>
void addCurve(const MuscleCurveLanes<Real>& curve, const MuscleSegmentLanes<Real>* segments, int segment_count,
              const Real* driver, BlockState<Real>* s) {
  Real up[kLanes], side[kLanes], scale[kLanes];
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    up[l] = curve.up[l];
    side[l] = curve.side[l];
    scale[l] = curve.scale[l];
  }
  for (int k = 0; k < segment_count; ++k) {
    const MuscleSegmentLanes<Real>& g = segments[k];
    RIGBAKE_LANE_LOOP
    for (int l = 0; l < kLanes; ++l) {
      const Real t = std::min(std::max((driver[l] - g.from[l]) * g.inverse_span[l], Real(0)), Real(1));
      up[l] += t * g.up_change[l];
      side[l] += t * g.side_change[l];
      scale[l] += t * g.scale_change[l];
    }
  }
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    s->up[l] += up[l];
    s->side[l] += side[l];
    s->scale[l] += scale[l] - Real(1);
  }
}

// The response (evaluateResponse()): the rest response plus each curve's offset from it.
template <typename Real>
void evaluateResponses(const MuscleLanes<Real>& block, const MuscleSegmentLanes<Real>* segments, BlockState<Real>* s) {
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    s->up[l] = 0;
    s->side[l] = 0;
    s->scale[l] = 1;
  }
  const MuscleSegmentLanes<Real>* ratio_segments = segments + block.segment_begin;
  addCurve(block.ratio_curve, ratio_segments, block.ratio_segment_count, s->clamped_ratio, s);
  // A block whose twist keys are all rest keys adds nothing for the twist (0, 0 and 1 - 1).
  if (block.twist_moves) {
    addCurve(block.twist_curve, ratio_segments + block.ratio_segment_count, block.twist_segment_count, s->twist, s);
  }
}

// M = W_carrier * K * T(0, up, side) * diag(1, scale, scale), K the bind transform in the carrier:
// K's columns 1 and 2 scaled, its translation moved along them, then the affine product, each entry
// summed in the order of the matrix product.
template <typename Real>
void evaluateSkinned(const MuscleLanes<Real>& block, const JointLanes<Real>& carrier, const BlockState<Real>& s,
                     Real (*skinned)[kLanes]) {
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    Real k[12];
    for (int e = 0; e < 12; ++e) k[e] = block.skinned_in_carrier[e][l];
    for (int r = 0; r < 3; ++r) k[9 + r] += k[3 + r] * s.up[l] + k[6 + r] * s.side[l];
    for (int r = 0; r < 3; ++r) {
      k[3 + r] *= s.scale[l];
      k[6 + r] *= s.scale[l];
    }
    for (int c = 0; c < 4; ++c) {
      const Vec3<Real> v = carrier.direction(l, {k[3 * c], k[3 * c + 1], k[3 * c + 2]});
      const Vec3<Real> column = c == 3 ? v + carrier.column(3, l) : v;
      skinned[3 * c][l] = column.x;
      skinned[3 * c + 1][l] = column.y;
      skinned[3 * c + 2][l] = column.z;
    }
  }
}

// The helper frames' columns per lane: fibre, up, side and the driver point (the base sits at the
// origin, the tip at the insertion, both already in the block's state).
template <typename Real>
struct HelperLanes {
  Real fibre[3][kLanes], up[3][kLanes], side[3][kLanes], driver[3][kLanes];
};

template <typename Real>
void evaluateHelpers(const MuscleLanes<Real>& block, const BlockState<Real>& s, HelperLanes<Real>* out) {
  RIGBAKE_LANE_LOOP
  for (int l = 0; l < kLanes; ++l) {
    const Vec3<Real> carried_fibre = normalized(s.origin_joint.direction(l, lane(block.fibre_local, l)));
    const Vec3<Real> carried_up_raw = normalized(s.origin_joint.direction(l, lane(block.up_local, l)));
    const Vec3<Real> carried_up = normalized(carried_up_raw - dot(carried_up_raw, carried_fibre) * carried_fibre);
    const Real current = s.length[l];
    const Vec3<Real> fibre = select(current > kMinLengthFraction<Real> * block.rest_length[l],
                                    (Real(1) / current) * lane(s.segment, l), carried_fibre);
    // Swing the carried up vector with the fibre's own motion (Rodrigues, k = from x to).
    const Real cosine = dot(carried_fibre, fibre);
    const Vec3<Real> k = cross(carried_fibre, fibre);
    const Vec3<Real> rodrigues = cosine * carried_up + cross(k, carried_up) + (dot(k, carried_up) / (Real(1) + cosine)) * k;
    const Vec3<Real> swung = select(Real(1) + cosine >= kReversedFibre<Real>, rodrigues, carried_up);
    const Vec3<Real> up = normalized(swung - dot(swung, fibre) * fibre);
    const Vec3<Real> side = cross(fibre, up);
    const Vec3<Real> driver = lane(s.origin, l) + (block.driver_fraction[l] * current) * fibre +
                              block.driver_offset[0][l] * up + block.driver_offset[1][l] * side;
    setLane(out->fibre, l, fibre);
    setLane(out->up, l, up);
    setLane(out->side, l, side);
    setLane(out->driver, l, driver);
  }
}

// One frame of a helper: columns x, y, z and the position.
template <typename Real>
void storeFrame(Vec3<Real> x, Vec3<Real> y, Vec3<Real> z, Vec3<Real> position, Real* out) {
  const Real values[16] = {x.x, x.y, x.z, 0, y.x, y.y, y.z, 0, z.x, z.y, z.z, 0, position.x, position.y, position.z, 1};
  for (int k = 0; k < 16; ++k) out[k] = values[k];
}

// Base [f, up, side] at the origin, tip [-f, up, -side] at the insertion, driver [f, up, side] at the
// driver point, 48 numbers a muscle.
template <typename Real>
void storeHelpers(const MuscleLanes<Real>& block, const BlockState<Real>& s, const HelperLanes<Real>& h, Real* out) {
  for (int l = 0; l < block.count; ++l) {
    const Vec3<Real> fibre = lane(h.fibre, l), up = lane(h.up, l), side = lane(h.side, l);
    Real* frames = out + 48 * block.muscle[l];
    storeFrame(fibre, up, side, lane(s.origin, l), frames);
    storeFrame(Real(-1) * fibre, up, Real(-1) * side, lane(s.insertion, l), frames + 16);
    storeFrame(fibre, up, side, lane(h.driver, l), frames + 32);
  }
}

// Whether a twist key leaves the rest response (up 0, side 0, scale 1): a curve of rest keys adds nothing.
template <typename Real>
bool twistMoves(const MuscleRig<Real>& rig, const RigMuscle<Real>& muscle) {
  for (int k = 0; k < muscle.twist_key_count; ++k) {
    const ResponseKey<Real>& key = rig.keys[muscle.twist_key_begin + k];
    if (!(key.up == Real(0) && key.side == Real(0) && key.scale == Real(1))) return true;
  }
  return false;
}

template <typename Real>
void prepareCurve(const ResponseKey<Real>* keys, int count, int l, MuscleCurveLanes<Real>* curve,
                  MuscleSegmentLanes<Real>* segments) {
  curve->up[l] = count > 0 ? keys[0].up : Real(0);
  curve->side[l] = count > 0 ? keys[0].side : Real(0);
  curve->scale[l] = count > 0 ? keys[0].scale : Real(1);
  for (int k = 0; k + 1 < count; ++k) {
    const ResponseKey<Real>& a = keys[k];
    const ResponseKey<Real>& b = keys[k + 1];
    MuscleSegmentLanes<Real>& g = segments[k];
    g.from[l] = a.at;
    g.inverse_span[l] = Real(1) / (b.at - a.at);
    g.up_change[l] = b.up - a.up;
    g.side_change[l] = b.side - a.side;
    g.scale_change[l] = b.scale - a.scale;
  }
}

// A segment no driver is ever through: from +inf, no change.
template <typename Real>
MuscleSegmentLanes<Real> emptySegment() {
  MuscleSegmentLanes<Real> g;
  for (int l = 0; l < kLanes; ++l) {
    g.from[l] = std::numeric_limits<Real>::infinity();
    g.inverse_span[l] = 1;
    g.up_change[l] = g.side_change[l] = g.scale_change[l] = 0;
  }
  return g;
}

// The twist reference pairs of one muscle (MuscleLanes::origin_across, insertion_across), in double.
void twistReferencePairs(const double twist_axis[3], const double bind_quaternion[4], Vec3<double> origin_pair[2],
                         Vec3<double> insertion_pair[2]) {
  const Vec3<double> a = normalized(Vec3<double>{twist_axis[0], twist_axis[1], twist_axis[2]});
  Vec3<double> u1 = {0, 0, 0}, u2 = {0, 0, 0};  // a zero axis: no twist, as 2 atan2(0, w) was
  if (dot(a, a) > 0.0) {
    // u1: the coordinate axis most nearly across a, made perpendicular to it.
    const double ax = std::fabs(a.x), ay = std::fabs(a.y), az = std::fabs(a.z);
    const Vec3<double> axis = ax <= ay && ax <= az ? Vec3<double>{1, 0, 0} : (ay <= az ? Vec3<double>{0, 1, 0} : Vec3<double>{0, 0, 1});
    u1 = normalized(axis - dot(axis, a) * a);
    u2 = cross(a, u1);
  }
  // Q0^-1 u = B0^T u, B0 the rotation matrix of the bind quaternion made unit (the quaternion form's
  // atan2 did not depend on its length either); c0, c1, c2 are B0's columns.
  double x = bind_quaternion[0], y = bind_quaternion[1], z = bind_quaternion[2], w = bind_quaternion[3];
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  if (n > 0.0) {
    x /= n, y /= n, z /= n, w /= n;
  } else {
    x = y = z = 0.0, w = 1.0;
  }
  const Vec3<double> c0 = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)};
  const Vec3<double> c1 = {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)};
  const Vec3<double> c2 = {2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
  origin_pair[0] = u1;
  origin_pair[1] = u2;
  insertion_pair[0] = {dot(c0, u1), dot(c1, u1), dot(c2, u1)};
  insertion_pair[1] = {dot(c0, u2), dot(c1, u2), dot(c2, u2)};
}

template <typename Real>
void prepareLane(const MuscleRig<Real>& rig, int m, int l, MuscleLanes<Real>* block, MuscleSegmentLanes<Real>* segments) {
  const RigMuscle<Real>& muscle = rig.muscles[m];
  block->muscle[l] = m;
  block->origin_joint[l] = muscle.origin_joint;
  block->insertion_joint[l] = muscle.insertion_joint;
  block->carrier_joint[l] = muscle.carrier_joint;
  block->carrier_is_origin[l] = muscle.carrier_joint == muscle.origin_joint ? Real(1) : Real(0);
  for (int c = 0; c < 3; ++c) {
    block->origin_local[c][l] = muscle.origin_local[c];
    block->insertion_local[c][l] = muscle.insertion_local[c];
  }
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r) block->skinned_in_carrier[3 * c + r][l] = muscle.skinned_in_carrier[4 * c + r];
  }
  block->rest_length[l] = muscle.rest_length;
  block->compression[l] = muscle.compression;
  block->stretch[l] = muscle.stretch;
  // In double whatever Real is: constants, rounded once.
  const double axis[3] = {muscle.twist_axis_local[0], muscle.twist_axis_local[1], muscle.twist_axis_local[2]};
  const double bind[4] = {muscle.insertion_bind_in_origin[0], muscle.insertion_bind_in_origin[1],
                          muscle.insertion_bind_in_origin[2], muscle.insertion_bind_in_origin[3]};
  Vec3<double> origin_pair[2], insertion_pair[2];
  twistReferencePairs(axis, bind, origin_pair, insertion_pair);
  for (int k = 0; k < 2; ++k) {
    setLane(block->origin_across[k], l, Vec3<Real>{static_cast<Real>(origin_pair[k].x), static_cast<Real>(origin_pair[k].y),
                                                     static_cast<Real>(origin_pair[k].z)});
    setLane(block->insertion_across[k], l,
            Vec3<Real>{static_cast<Real>(insertion_pair[k].x), static_cast<Real>(insertion_pair[k].y),
                       static_cast<Real>(insertion_pair[k].z)});
  }
  const ResponseKey<Real>* keys = rig.keys.data();
  prepareCurve(keys + muscle.ratio_key_begin, muscle.ratio_key_count, l, &block->ratio_curve, segments);
  prepareCurve(keys + muscle.twist_key_begin, muscle.twist_key_count, l, &block->twist_curve,
               segments + block->ratio_segment_count);
  for (int c = 0; c < 3; ++c) {
    block->fibre_local[c][l] = muscle.fibre_local[c];
    block->up_local[c][l] = muscle.up_local[c];
  }
  block->driver_fraction[l] = muscle.driver_fraction;
  block->driver_offset[0][l] = muscle.driver_offset[0];
  block->driver_offset[1][l] = muscle.driver_offset[1];
}

}  // namespace

template <typename Real>
void prepareMuscleRig(MuscleRig<Real>* rig) {
  rig->blocks.clear();
  rig->segments.clear();
  // Muscles whose twist moves the response first, so that the blocks after them need no twist.
  std::vector<int> order(rig->muscles.size());
  for (std::size_t m = 0; m < order.size(); ++m) order[m] = static_cast<int>(m);
  auto group = [&](int m) {
    const RigMuscle<Real>& muscle = rig->muscles[m];
    const int carrier = muscle.carrier_joint == muscle.origin_joint ? 0 : (muscle.carrier_joint == muscle.insertion_joint ? 1 : 2);
    return (twistMoves(*rig, muscle) ? 0 : 3) + carrier;
  };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return group(a) < group(b); });
  const int muscles = static_cast<int>(order.size());
  for (int begin = 0; begin < muscles; begin += kLanes) {
    MuscleLanes<Real> block;
    block.count = std::min(kLanes, muscles - begin);
    block.segment_begin = static_cast<int>(rig->segments.size());
    int origins = 0, insertions = 0;
    for (int l = 0; l < block.count; ++l) {
      const RigMuscle<Real>& m = rig->muscles[order[begin + l]];
      block.ratio_segment_count = std::max(block.ratio_segment_count, m.ratio_key_count - 1);
      block.twist_segment_count = std::max(block.twist_segment_count, m.twist_key_count - 1);
      block.twist_moves = block.twist_moves || twistMoves(*rig, m);
      // A carrier that is both (origin and insertion on one joint) counts as the origin, as
      // carrier_is_origin says.
      origins += m.carrier_joint == m.origin_joint ? 1 : 0;
      insertions += m.carrier_joint != m.origin_joint && m.carrier_joint == m.insertion_joint ? 1 : 0;
    }
    block.carriers = origins == block.count      ? MuscleCarriers::kOrigins
                     : insertions == block.count ? MuscleCarriers::kInsertions
                     : origins + insertions == block.count ? MuscleCarriers::kPicked
                                                            : MuscleCarriers::kRead;
    rig->segments.resize(rig->segments.size() + block.ratio_segment_count + block.twist_segment_count, emptySegment<Real>());
    // Lanes past the last muscle repeat it, so that they compute finite numbers nobody reads.
    for (int l = 0; l < kLanes; ++l) {
      prepareLane(*rig, order[begin + std::min(l, block.count - 1)], l, &block, rig->segments.data() + block.segment_begin);
    }
    rig->blocks.push_back(block);
  }
  rig->prepared_muscles = rig->muscles.size();
}

template <typename Real>
const char* rigProblem(const MuscleRig<Real>& rig) {
  if (rig.joint_count <= 0) return "the rig has no joints";
  for (const RigMuscle<Real>& m : rig.muscles) {
    for (int joint : {m.origin_joint, m.insertion_joint, m.carrier_joint}) {
      if (joint < 0 || joint >= rig.joint_count) return "a muscle names a joint outside the skeleton";
    }
    if (!(m.rest_length > Real(0))) return "a muscle's rest length is not positive";
    if (!(m.compression > Real(0) && m.compression <= Real(1) && m.stretch >= Real(1)))
      return "a muscle's compression / stretch are not 0 < compression <= 1 <= stretch";
    for (auto [begin, count] : {std::pair<int, int>{m.ratio_key_begin, m.ratio_key_count}, {m.twist_key_begin, m.twist_key_count}}) {
      if (begin < 0 || count < 0 || static_cast<std::size_t>(begin) + static_cast<std::size_t>(count) > rig.keys.size())
        return "a muscle's response keys lie outside the key array";
      for (int k = 1; k < count; ++k) {
        if (!(rig.keys[begin + k].at > rig.keys[begin + k - 1].at)) return "a muscle's response keys are not ascending";
      }
    }
  }
  return "";
}

template <typename Real>
ResponseKey<Real> evaluateResponse(const MuscleRig<Real>& rig, const RigMuscle<Real>& muscle,
                                   const MuscleDrivers<Real>& drivers) {
  ResponseKey<Real> sum;
  sum.at = 0;
  addCurve(rig.keys.data() + muscle.ratio_key_begin, muscle.ratio_key_count, drivers.clamped_ratio, &sum);
  addCurve(rig.keys.data() + muscle.twist_key_begin, muscle.twist_key_count, drivers.twist, &sum);
  return sum;
}

template <typename Real>
bool MuscleRigJob<Real>::Validate() const {
  if (rig == nullptr) return false;
  const std::size_t muscles = rig->muscles.size();
  if (rig->prepared_muscles != muscles || rig->blocks.size() != (muscles + kLanes - 1) / kLanes) return false;
  if (joint_matrices.data == nullptr || joint_matrices.size < 16 * static_cast<std::size_t>(rig->joint_count)) return false;
  if (skinned_matrices.size < 16 * muscles || (muscles > 0 && skinned_matrices.data == nullptr)) return false;
  if (!helper_matrices.empty() && helper_matrices.size < 48 * muscles) return false;
  if (!drivers.empty() && drivers.size < muscles) return false;
  return true;
}

template <typename Real>
bool MuscleRigJob<Real>::Run() const {
  if (!Validate()) return false;
  const Real* joints = joint_matrices.data;
  const bool report = !drivers.empty();
  const bool helpers = !helper_matrices.empty();
  BlockState<Real> s;
  Real skinned[12][kLanes];
  HelperLanes<Real> helper_lanes;
  for (const MuscleLanes<Real>& block : rig->blocks) {
    gatherJoints(joints, block.origin_joint, &s.origin_joint);
    gatherJoints(joints, block.insertion_joint, &s.insertion_joint);
    if (block.carriers == MuscleCarriers::kRead) gatherJoints(joints, block.carrier_joint, &s.carrier_joint);
    if (block.carriers == MuscleCarriers::kPicked) pickCarriers(block, &s);
    evaluateLocators(block, &s);
    if (report || block.twist_moves) {
      evaluateTwist(block, &s);
    } else {
      RIGBAKE_LANE_LOOP
      for (int l = 0; l < kLanes; ++l) s.twist[l] = 0;
    }
    evaluateResponses(block, rig->segments.data(), &s);
    evaluateSkinned(block, block.carriers == MuscleCarriers::kOrigins      ? s.origin_joint
                           : block.carriers == MuscleCarriers::kInsertions ? s.insertion_joint
                                                                           : s.carrier_joint,
                    s, skinned);
    for (int l = 0; l < block.count; ++l) {
      Real* out = skinned_matrices.data + 16 * block.muscle[l];
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r) out[4 * c + r] = skinned[3 * c + r][l];
        out[4 * c + 3] = c == 3 ? Real(1) : Real(0);
      }
    }
    if (report) {
      for (int l = 0; l < block.count; ++l) drivers[block.muscle[l]] = {s.ratio[l], s.clamped_ratio[l], s.twist[l]};
    }
    if (helpers) {
      evaluateHelpers(block, s, &helper_lanes);
      storeHelpers(block, s, helper_lanes, helper_matrices.data);
    }
  }
  return true;
}

template struct MuscleRigJob<float>;
template struct MuscleRigJob<double>;
template void prepareMuscleRig(MuscleRig<float>*);
template void prepareMuscleRig(MuscleRig<double>*);
template const char* rigProblem(const MuscleRig<float>&);
template const char* rigProblem(const MuscleRig<double>&);
template ResponseKey<float> evaluateResponse(const MuscleRig<float>&, const RigMuscle<float>&, const MuscleDrivers<float>&);
template ResponseKey<double> evaluateResponse(const MuscleRig<double>&, const RigMuscle<double>&, const MuscleDrivers<double>&);

}  // namespace rigbake::runtime
