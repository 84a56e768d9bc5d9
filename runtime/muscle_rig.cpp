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
//   on that axis), for the twist driver.
// rigbake's skinned joint rides its carrier joint (the joint it takes its skin weight from), so that a
// muscle at rest response reproduces the input skinning exactly, and moves by the response alone:
// docs/muscle-model.md says why (measured: following the driver point costs the shoulder 30 % of its
// volume).
#include "runtime/muscle_rig.h"

#include <cmath>
#include <utility>

#include "runtime/affine.h"

namespace rigbake::runtime {
namespace {

template <typename Real>
struct Vec3 {
  Real x, y, z;
};

template <typename Real>
Vec3<Real> operator+(Vec3<Real> a, Vec3<Real> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename Real>
Vec3<Real> operator-(Vec3<Real> a, Vec3<Real> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename Real>
Vec3<Real> operator*(Real s, Vec3<Real> a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename Real>
Real dot(Vec3<Real> a, Vec3<Real> b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename Real>
Vec3<Real> cross(Vec3<Real> a, Vec3<Real> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Real>
Real length(Vec3<Real> a) { return std::sqrt(dot(a, a)); }
template <typename Real>
Vec3<Real> normalized(Vec3<Real> a) {
  const Real n = length(a);
  return n > Real(0) ? (Real(1) / n) * a : a;
}
template <typename Real>
Vec3<Real> load(const Real* p) { return {p[0], p[1], p[2]}; }

template <typename Real>
Vec3<Real> transformPoint(const Real* m, Vec3<Real> p) {
  return {m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12], m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
          m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]};
}
template <typename Real>
Vec3<Real> transformDirection(const Real* m, Vec3<Real> d) {
  return {m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z,
          m[2] * d.x + m[6] * d.y + m[10] * d.z};
}

template <typename Real>
void storeFrame(Vec3<Real> x, Vec3<Real> y, Vec3<Real> z, Vec3<Real> position, Real* out) {
  const Real values[16] = {x.x, x.y, x.z, 0, y.x, y.y, y.z, 0, z.x, z.y, z.z, 0, position.x, position.y, position.z, 1};
  for (int k = 0; k < 16; ++k) out[k] = values[k];
}

template <typename Real>
struct Quat {
  Real x, y, z, w;
};

template <typename Real>
Quat<Real> multiply(Quat<Real> a, Quat<Real> b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
template <typename Real>
Quat<Real> conjugate(Quat<Real> q) { return {-q.x, -q.y, -q.z, q.w}; }

// The rotation of a joint matrix as a unit quaternion: columns made orthonormal first (Gram-Schmidt;
// exact for a rotation times a uniform scale, the nearest frame for anything else), then Shepperd's
// method ("Quaternion from rotation matrix", J. Guidance and Control 1(3), 1978).
template <typename Real>
Quat<Real> rotationOf(const Real* m) {
  const Vec3<Real> x = normalized(Vec3<Real>{m[0], m[1], m[2]});
  const Vec3<Real> y0 = {m[4], m[5], m[6]};
  const Vec3<Real> y = normalized(y0 - dot(y0, x) * x);
  const Vec3<Real> z = cross(x, y);
  const Real trace = x.x + y.y + z.z;
  Quat<Real> q;
  if (trace > Real(0)) {
    const Real s = std::sqrt(trace + Real(1)) * Real(2);
    q = {(y.z - z.y) / s, (z.x - x.z) / s, (x.y - y.x) / s, Real(0.25) * s};
  } else if (x.x > y.y && x.x > z.z) {
    const Real s = std::sqrt(Real(1) + x.x - y.y - z.z) * Real(2);
    q = {Real(0.25) * s, (y.x + x.y) / s, (z.x + x.z) / s, (y.z - z.y) / s};
  } else if (y.y > z.z) {
    const Real s = std::sqrt(Real(1) + y.y - x.x - z.z) * Real(2);
    q = {(y.x + x.y) / s, Real(0.25) * s, (z.y + y.z) / s, (z.x - x.z) / s};
  } else {
    const Real s = std::sqrt(Real(1) + z.z - x.x - y.y) * Real(2);
    q = {(z.x + x.z) / s, (z.y + y.z) / s, Real(0.25) * s, (x.y - y.x) / s};
  }
  return q;
}

// Below this fraction of the rest length the fibre has no direction; the carried rest fibre stands in.
template <typename Real>
constexpr Real kMinLengthFraction = Real(1e-6);
// 1 + cos(angle) below which the fibre has reversed relative to its origin joint.
template <typename Real>
constexpr Real kReversedFibre = Real(1e-12);

template <typename Real>
Real clampValue(Real v, Real lo, Real hi) { return v < lo ? lo : (v > hi ? hi : v); }

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

template <typename Real>
MuscleDrivers<Real> muscleDrivers(const RigMuscle<Real>& muscle, const Real* joints, Vec3<Real>* origin,
                                  Vec3<Real>* insertion) {
  const Real* origin_joint = joints + 16 * muscle.origin_joint;
  const Real* insertion_joint = joints + 16 * muscle.insertion_joint;
  *origin = transformPoint(origin_joint, load(muscle.origin_local));
  *insertion = transformPoint(insertion_joint, load(muscle.insertion_local));
  MuscleDrivers<Real> drivers;
  drivers.ratio = length(*insertion - *origin) / muscle.rest_length;
  drivers.clamped_ratio = clampValue(drivers.ratio, muscle.compression, muscle.stretch);
  // delta = R_o^-1 R_i Q0^-1: the insertion joint's turn relative to the origin joint since the
  // bind pose, in the origin joint's frame; its twist about the rest fibre is the driver.
  const Quat<Real> q0 = {muscle.insertion_bind_in_origin[0], muscle.insertion_bind_in_origin[1],
                         muscle.insertion_bind_in_origin[2], muscle.insertion_bind_in_origin[3]};
  const Quat<Real> delta = multiply(multiply(conjugate(rotationOf(origin_joint)), rotationOf(insertion_joint)), conjugate(q0));
  const Real along =
      delta.x * muscle.twist_axis_local[0] + delta.y * muscle.twist_axis_local[1] + delta.z * muscle.twist_axis_local[2];
  Real twist = Real(2) * std::atan2(along, delta.w);
  const Real pi = Real(3.14159265358979323846);
  if (twist > pi) twist -= Real(2) * pi;
  if (twist <= -pi) twist += Real(2) * pi;
  drivers.twist = twist;
  return drivers;
}

template <typename Real>
void helperFrames(const RigMuscle<Real>& muscle, const Real* joints, Vec3<Real> origin, Vec3<Real> insertion,
                  Real* out) {
  const Real* origin_joint = joints + 16 * muscle.origin_joint;
  const Vec3<Real> carried_fibre = normalized(transformDirection(origin_joint, load(muscle.fibre_local)));
  const Vec3<Real> carried_up_raw = normalized(transformDirection(origin_joint, load(muscle.up_local)));
  const Vec3<Real> carried_up = normalized(carried_up_raw - dot(carried_up_raw, carried_fibre) * carried_fibre);
  const Vec3<Real> segment = insertion - origin;
  const Real current = length(segment);
  const Vec3<Real> fibre =
      current > kMinLengthFraction<Real> * muscle.rest_length ? (Real(1) / current) * segment : carried_fibre;
  // Swing the carried up vector with the fibre's own motion (Rodrigues, k = from x to).
  const Real cosine = dot(carried_fibre, fibre);
  Vec3<Real> swung = carried_up;
  if (Real(1) + cosine >= kReversedFibre<Real>) {
    const Vec3<Real> k = cross(carried_fibre, fibre);
    swung = cosine * carried_up + cross(k, carried_up) + (dot(k, carried_up) / (Real(1) + cosine)) * k;
  }
  const Vec3<Real> up = normalized(swung - dot(swung, fibre) * fibre);
  const Vec3<Real> side = cross(fibre, up);
  const Vec3<Real> driver = origin + (muscle.driver_fraction * current) * fibre + muscle.driver_offset[0] * up +
                            muscle.driver_offset[1] * side;
  storeFrame(fibre, up, side, origin, out);
  storeFrame(Real(-1) * fibre, up, Real(-1) * side, insertion, out + 16);
  storeFrame(fibre, up, side, driver, out + 32);
}

}  // namespace

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
  for (std::size_t m = 0; m < rig->muscles.size(); ++m) {
    const RigMuscle<Real>& muscle = rig->muscles[m];
    Vec3<Real> origin, insertion;
    const MuscleDrivers<Real> state = muscleDrivers(muscle, joints, &origin, &insertion);
    if (!drivers.empty()) drivers[m] = state;
    if (!helper_matrices.empty()) helperFrames(muscle, joints, origin, insertion, helper_matrices.data + 48 * m);

    // M = W_carrier * K * T(0, up, side) * diag(1, scale, scale), K the bind transform in the carrier.
    const ResponseKey<Real> response = evaluateResponse(*rig, muscle, state);
    Real local[16];
    const Real* k = muscle.skinned_in_carrier;
    for (int c = 0; c < 16; ++c) local[c] = k[c];
    for (int r = 0; r < 3; ++r) local[12 + r] += k[4 + r] * response.up + k[8 + r] * response.side;
    for (int r = 0; r < 3; ++r) {
      local[4 + r] *= response.scale;
      local[8 + r] *= response.scale;
    }
    detail::multiplyAffine(joints + 16 * muscle.carrier_joint, local, skinned_matrices.data + 16 * m);
  }
  return true;
}

template struct MuscleRigJob<float>;
template struct MuscleRigJob<double>;
template const char* rigProblem(const MuscleRig<float>&);
template const char* rigProblem(const MuscleRig<double>&);
template ResponseKey<float> evaluateResponse(const MuscleRig<float>&, const RigMuscle<float>&, const MuscleDrivers<float>&);
template ResponseKey<double> evaluateResponse(const MuscleRig<double>&, const RigMuscle<double>&, const MuscleDrivers<double>&);

}  // namespace rigbake::runtime
