// The runtime jiggle (runtime/jiggle.h). Sources:
// - Tenghao Wang, "Joint-Based Skin Deformation in God of War Ragnarök", GDC 2023: "Jiggle Dynamics"
//   (root, pivot and jiggle joints; Stiffness, Damping, ClampMajorAngle, ClampMinorAngle), "Damped
//   Spring Simple Motion" (x = p - r, F = -beta v - k x, semi-implicit Euler), "Aim Transformation"
//   (u = jigglePoint - pivot, up from the root joint, w = u x up, v = w x u), "Line - Elliptical Cone
//   Intersection" (A t^2 + B t + C = 0 along the segment from the rest point), "Combat Reaction" (a
//   hit's direction and magnitude as an initial velocity of the part that was hit).
// - B. Wasiak, "Physical Animation in Star Wars Jedi: Fallen Order", GDC 2020: a fixed simulation step
//   whatever the frame rate, and a distance limit to the animation target.
// - G. Fiedler, "Fix Your Timestep!" (2004): an accumulator carries the time a frame leaves over to the
//   next frame's steps. Unlike its render interpolation (one step behind), the output here extrapolates
//   the last step's offset to the frame's own time, so at a frame time on the step grid (24, 30, 60, 120
//   or 240 fps) the engine shows exactly what the bake samples there.
// - R. Juckett, "Damped Springs": frequency and damping ratio as the artist-facing pair.
// - Matrix to quaternion: K. Shoemake, "Quaternion Calculus and Fast Animation" (SIGGRAPH 1987 course
//   notes), in the branch order Eigen 3.4 uses, so the double runtime reads a matrix as rigbake's
//   decomposeTrs does; the polar factor by Newton's iteration X <- (X + X^-T) / 2 (N. Higham,
//   "Computing the polar decomposition", SIAM J. Sci. Stat. Comput. 7(4), 1986).
// The spring state is the offset of the point from its target rather than the point itself: the same
// equations, but in float the offset keeps the precision of the jiggle's length instead of that of the
// model-space coordinates (and consecutive targets are close, so their difference is exact).
#include "runtime/jiggle.h"

#include <cmath>
#include <limits>

#include "runtime/affine.h"

namespace rigbake::runtime {
namespace jiggle_detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
// Below this |sin| between the aim and the up vector the talk's aim frame is ill-conditioned; the
// shortest-arc rotation (identical for motion in the aim-up plane) takes over.
constexpr double kAimDegenerateSin = 1e-6;

// Frame times this close to a step time are that step time (n h and n / fps differ by rounding).
template <typename Real>
constexpr Real timeTolerance() {
  return sizeof(Real) >= sizeof(double) ? Real(1e-9) : Real(1e-7);
}
// |A| at or below this: the cone quadratic is linear.
template <typename Real>
constexpr Real tinyQuadratic() {
  return sizeof(Real) >= sizeof(double) ? Real(1e-300) : Real(1e-37);
}
// 1 + cos below which two unit vectors are antiparallel (Eigen's dummy_precision).
template <typename Real>
constexpr Real antiparallel() {
  return sizeof(Real) >= sizeof(double) ? Real(1e-12) : Real(1e-5);
}

template <typename Real>
struct V3 {
  Real x, y, z;
};
template <typename Real>
V3<Real> add(V3<Real> a, V3<Real> b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename Real>
V3<Real> sub(V3<Real> a, V3<Real> b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename Real>
V3<Real> scaled(Real s, V3<Real> a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename Real>
V3<Real> divided(V3<Real> a, Real s) { return {a.x / s, a.y / s, a.z / s}; }
// The summation order of Eigen's fixed-size dot product, so the bake's sums round as before.
template <typename Real>
Real dot3(V3<Real> a, V3<Real> b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }
template <typename Real>
V3<Real> cross3(V3<Real> a, V3<Real> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Real>
Real norm3(V3<Real> a) { return std::sqrt(dot3(a, a)); }
template <typename Real>
V3<Real> unit3(V3<Real> a) {
  const Real n2 = dot3(a, a);
  return n2 > Real(0) ? divided(a, std::sqrt(n2)) : a;
}
template <typename Real>
bool same3(V3<Real> a, V3<Real> b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
template <typename Real>
V3<Real> load3(const Real* p) { return {p[0], p[1], p[2]}; }
template <typename Real>
void store3(V3<Real> a, Real* p) {
  p[0] = a.x;
  p[1] = a.y;
  p[2] = a.z;
}

template <typename Real>
struct Q4 {
  Real x, y, z, w;
};
template <typename Real>
Q4<Real> loadQ(const Real* p) { return {p[0], p[1], p[2], p[3]}; }
template <typename Real>
void storeQ(Q4<Real> q, Real* p) {
  p[0] = q.x;
  p[1] = q.y;
  p[2] = q.z;
  p[3] = q.w;
}
template <typename Real>
Q4<Real> conjugateQ(Q4<Real> q) { return {-q.x, -q.y, -q.z, q.w}; }
template <typename Real>
Q4<Real> multiplyQ(Q4<Real> a, Q4<Real> b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y + a.y * b.w + a.z * b.x - a.x * b.z,
          a.w * b.z + a.z * b.w + a.x * b.y - a.y * b.x, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
template <typename Real>
Q4<Real> normalizedQ(Q4<Real> q) {
  const Real n = std::sqrt((q.x * q.x + q.y * q.y) + (q.z * q.z + q.w * q.w));
  return n > Real(0) ? Q4<Real>{q.x / n, q.y / n, q.z / n, q.w / n} : q;
}
// q v q*, as Eigen's Quaternion::_transformVector computes it (30 flops).
template <typename Real>
V3<Real> rotate(Q4<Real> q, V3<Real> v) {
  const V3<Real> axis = {q.x, q.y, q.z};
  V3<Real> uv = cross3(axis, v);
  uv = add(uv, uv);
  return add(add(v, scaled(q.w, uv)), cross3(axis, uv));
}

// A 3x3 matrix as three columns.
template <typename Real>
struct M3 {
  V3<Real> c[3];
  Real at(int row, int col) const {
    const V3<Real>& v = c[col];
    return row == 0 ? v.x : (row == 1 ? v.y : v.z);
  }
};

// Shoemake's matrix-to-quaternion in Eigen 3.4's branch order (the sign of the result included).
template <typename Real>
Q4<Real> quaternionOf(const M3<Real>& m) {
  Q4<Real> q;
  Real t = m.at(0, 0) + m.at(1, 1) + m.at(2, 2);
  if (t > Real(0)) {
    t = std::sqrt(t + Real(1));
    q.w = Real(0.5) * t;
    t = Real(0.5) / t;
    q.x = (m.at(2, 1) - m.at(1, 2)) * t;
    q.y = (m.at(0, 2) - m.at(2, 0)) * t;
    q.z = (m.at(1, 0) - m.at(0, 1)) * t;
    return q;
  }
  int i = 0;
  if (m.at(1, 1) > m.at(0, 0)) i = 1;
  if (m.at(2, 2) > m.at(i, i)) i = 2;
  const int j = (i + 1) % 3, k = (j + 1) % 3;
  Real v[3];
  t = std::sqrt(m.at(i, i) - m.at(j, j) - m.at(k, k) + Real(1));
  v[i] = Real(0.5) * t;
  t = Real(0.5) / t;
  q.w = (m.at(k, j) - m.at(j, k)) * t;
  v[j] = (m.at(j, i) + m.at(i, j)) * t;
  v[k] = (m.at(k, i) + m.at(i, k)) * t;
  q.x = v[0];
  q.y = v[1];
  q.z = v[2];
  return q;
}

template <typename Real>
M3<Real> matrixOf(Q4<Real> q) {
  const Real x2 = q.x + q.x, y2 = q.y + q.y, z2 = q.z + q.z;
  const Real xx = q.x * x2, yy = q.y * y2, zz = q.z * z2, xy = q.x * y2, xz = q.x * z2, yz = q.y * z2;
  const Real wx = q.w * x2, wy = q.w * y2, wz = q.w * z2;
  M3<Real> m;
  m.c[0] = {Real(1) - (yy + zz), xy + wz, xz - wy};
  m.c[1] = {xy - wz, Real(1) - (xx + zz), yz + wx};
  m.c[2] = {xz + wy, yz - wx, Real(1) - (xx + yy)};
  return m;
}

template <typename Real>
Real determinant(const M3<Real>& m) { return dot3(m.c[0], cross3(m.c[1], m.c[2])); }

// The rotation nearest a frame of unit axes with a positive determinant: the frame itself when it is
// orthonormal, else its polar factor (what an SVD's U V^T gives), by Newton's iteration.
template <typename Real>
M3<Real> polarRotation(M3<Real> x) {
  const Real eps = std::numeric_limits<Real>::epsilon();
  for (int iteration = 0; iteration < 32; ++iteration) {
    const Real det = determinant(x);
    if (!(det > Real(16) * eps)) break;  // (nearly) singular: keep the unit axes as they are
    // X^-T = cofactors / det: its columns are c1 x c2, c2 x c0, c0 x c1 over det.
    const V3<Real> inverse_t[3] = {cross3(x.c[1], x.c[2]), cross3(x.c[2], x.c[0]), cross3(x.c[0], x.c[1])};
    Real change = 0;
    M3<Real> next;
    for (int k = 0; k < 3; ++k) {
      next.c[k] = scaled(Real(0.5), add(x.c[k], divided(inverse_t[k], det)));
      const V3<Real> d = sub(next.c[k], x.c[k]);
      change = std::fmax(change, std::fmax(std::fabs(d.x), std::fmax(std::fabs(d.y), std::fabs(d.z))));
    }
    x = next;
    if (change <= Real(4) * eps) break;
  }
  return x;
}

template <typename Real>
struct Rigid {
  V3<Real> translation;
  Q4<Real> rotation;
};

// decomposeTrs' reading of a matrix: unit columns, X negated for a mirrored frame, the polar factor.
template <typename Real>
Rigid<Real> rigidOf(const Real* m, V3<Real>* scale) {
  const V3<Real> columns[3] = {load3(m), load3(m + 4), load3(m + 8)};
  M3<Real> directions;
  for (int k = 0; k < 3; ++k) {
    const Real length = norm3(columns[k]);
    directions.c[k] = length > Real(0) ? divided(columns[k], length) : columns[k];
  }
  if (determinant(directions) < Real(0)) directions.c[0] = scaled(Real(-1), directions.c[0]);
  const M3<Real> rotation = polarRotation(directions);
  if (scale) *scale = {dot3(rotation.c[0], columns[0]), dot3(rotation.c[1], columns[1]), dot3(rotation.c[2], columns[2])};
  return {load3(m + 12), normalizedQ(quaternionOf(rotation))};
}

template <typename Real>
Q4<Real> rotationOrIdentity(const Real* m) {
  return m ? rigidOf(m, static_cast<V3<Real>*>(nullptr)).rotation : Q4<Real>{0, 0, 0, 1};
}

// The inverse of an affine 4x4 matrix; false (out untouched) when its linear part is singular.
template <typename Real>
bool invertAffine4(const Real* m, Real* out) {
  const V3<Real> c0 = load3(m), c1 = load3(m + 4), c2 = load3(m + 8);
  const V3<Real> r0 = cross3(c1, c2), r1 = cross3(c2, c0), r2 = cross3(c0, c1);  // rows of det * M^-1
  const Real det = dot3(c0, r0);
  if (!(std::fabs(det) > Real(0)) || !std::isfinite(det)) return false;
  const V3<Real> rows[3] = {divided(r0, det), divided(r1, det), divided(r2, det)};
  const V3<Real> t = load3(m + 12);
  for (int r = 0; r < 3; ++r) {
    out[r] = r == 0 ? rows[0].x : (r == 1 ? rows[1].x : rows[2].x);
    out[4 + r] = r == 0 ? rows[0].y : (r == 1 ? rows[1].y : rows[2].y);
    out[8 + r] = r == 0 ? rows[0].z : (r == 1 ? rows[1].z : rows[2].z);
    out[12 + r] = -dot3(rows[r], t);
  }
  out[3] = out[7] = out[11] = Real(0);
  out[15] = Real(1);
  return true;
}

template <typename Real>
V3<Real> coneCoords(const JiggleSettings<Real>& s, V3<Real> q) {
  return {dot3(q, load3(s.major_axis)), dot3(q, load3(s.aim_axis)), dot3(q, load3(s.minor_axis))};
}
template <typename Real>
Real coneValue(const JiggleSettings<Real>& s, V3<Real> c) {
  return s.cone_gx * c.x * c.x + s.cone_gz * c.z * c.z - s.cone_gy * c.y * c.y;
}
template <typename Real>
bool coneInside(const JiggleSettings<Real>& s, V3<Real> c) { return c.y >= Real(0) && coneValue(s, c) <= Real(0); }
// Outward normal (grad G) in the joint's frame.
template <typename Real>
V3<Real> coneNormal(const JiggleSettings<Real>& s, V3<Real> c) {
  const V3<Real> major = scaled(s.cone_gx * c.x, load3(s.major_axis));
  const V3<Real> aim = scaled(s.cone_gy * c.y, load3(s.aim_axis));
  const V3<Real> minor = scaled(s.cone_gz * c.z, load3(s.minor_axis));
  return scaled(Real(2), add(sub(major, aim), minor));
}

template <typename Real>
V3<Real> clampToConeV(const JiggleSettings<Real>& s, V3<Real> q, bool* moved) {
  const V3<Real> c1 = coneCoords(s, q);
  *moved = false;
  if (coneInside(s, c1)) return q;
  *moved = true;
  // The talk's segment from the rest point x0 = (0, L, 0), inside the cone, to q: f(t) = G(x0 + t d)
  // = A t^2 + B t + C with C = G(x0) < 0, so the first root in (0, 1] is where it leaves the cone.
  const Real length = s.length;
  const V3<Real> d = {c1.x, c1.y - length, c1.z};
  const Real a = s.cone_gx * d.x * d.x + s.cone_gz * d.z * d.z - s.cone_gy * d.y * d.y;
  const Real b = Real(-2) * s.cone_gy * d.y * length;
  const Real c = -s.cone_gy * length * length;
  Real t = -1;
  auto consider = [&t](Real root) {
    if (std::isfinite(root) && root > Real(0) && root <= Real(1) && (t < Real(0) || root < t)) t = root;
  };
  if (std::fabs(a) <= tinyQuadratic<Real>()) {
    consider(-c / b);
  } else {
    const Real discriminant = b * b - Real(4) * a * c;
    if (discriminant >= Real(0)) {
      // Numerically stable roots (no cancellation between -b and the square root).
      const Real half = Real(-0.5) * (b + std::copysign(std::sqrt(discriminant), b));
      consider(half / a);
      if (half != Real(0)) consider(c / half);
    }
  }
  const V3<Real> rest = load3(s.rest_point);
  const V3<Real> along = sub(q, rest);
  auto insideAt = [&](Real fraction) { return coneInside(s, coneCoords(s, add(rest, scaled(fraction, along)))); };
  // The front nappe is convex, so the points of the segment inside it are one interval [0, t*]. The
  // quadratic's root is t* up to rounding, which near a double root (a segment grazing a 90-degree
  // cone's plane y = 0) is only sqrt(epsilon) accurate, or even lost to a slightly negative
  // discriminant: bisect for the last inside t in a bracket around the root (or in [0, 1] without one),
  // so the result is inside, on the surface to the last bit, and clamping it again changes nothing.
  Real inside = 0, outside = 1;
  if (t > Real(0)) {
    const Real low = t * (Real(1) - Real(1e-6)), high = std::fmin(Real(1), t * (Real(1) + Real(1e-6)));
    if (insideAt(low) && !insideAt(high)) {
      inside = low;
      outside = high;
    }
  }
  for (int i = 0; i < 200; ++i) {
    const Real middle = Real(0.5) * (inside + outside);
    if (middle <= inside || middle >= outside) break;
    (insideAt(middle) ? inside : outside) = middle;
  }
  return add(rest, scaled(inside, along));
}

// Eigen's Quaternion::FromTwoVectors (an arbitrary perpendicular axis for opposite vectors).
template <typename Real>
Q4<Real> fromTwoVectors(V3<Real> a, V3<Real> b) {
  const V3<Real> v0 = unit3(a), v1 = unit3(b);
  Real c = dot3(v1, v0);
  if (c < Real(-1) + antiparallel<Real>()) {
    c = std::fmax(c, Real(-1));
    const V3<Real> helper = std::fabs(v0.x) < std::fabs(v0.y) ? (std::fabs(v0.x) < std::fabs(v0.z) ? V3<Real>{1, 0, 0} : V3<Real>{0, 0, 1})
                                                             : (std::fabs(v0.y) < std::fabs(v0.z) ? V3<Real>{0, 1, 0} : V3<Real>{0, 0, 1});
    const V3<Real> axis = unit3(cross3(v0, helper));
    const Real w2 = (Real(1) + c) * Real(0.5);
    const V3<Real> v = scaled(std::sqrt(Real(1) - w2), axis);
    return {v.x, v.y, v.z, std::sqrt(w2)};
  }
  const V3<Real> axis = cross3(v0, v1);
  const Real s = std::sqrt((Real(1) + c) * Real(2));
  const Real invs = Real(1) / s;
  return {axis.x * invs, axis.y * invs, axis.z * invs, s * Real(0.5)};
}

template <typename Real>
Q4<Real> aimRotationV(const JiggleSettings<Real>& s, V3<Real> q, V3<Real> up) {
  const V3<Real> rest = load3(s.rest_point);
  if (same3(q, rest) || norm3(q) == Real(0)) return {0, 0, 0, 1};
  const V3<Real> u = unit3(q);
  const V3<Real> a = load3(s.aim_axis);
  const V3<Real> up_unit = unit3(up);
  const V3<Real> w_jiggle = cross3(u, up_unit);
  const V3<Real> w_rest = cross3(a, up_unit);
  if (norm3(w_jiggle) < Real(kAimDegenerateSin) || norm3(w_rest) < Real(kAimDegenerateSin)) return fromTwoVectors(a, u);
  // The talk's aim frame [u, v, w] with w = u x up, v = w x u, for the jiggle point and for the rest
  // point; the jiggle rotation F(u) F(aim)^T maps one onto the other.
  auto frame = [&up_unit](V3<Real> aim) {
    const V3<Real> w = unit3(cross3(aim, up_unit));
    M3<Real> m;
    m.c[0] = aim;
    m.c[1] = cross3(w, aim);
    m.c[2] = w;
    return m;
  };
  const M3<Real> to = frame(u), from = frame(a);
  // (to * from^T) column k = sum_j to.c[j] * from.c[j][k].
  M3<Real> rotation;
  for (int k = 0; k < 3; ++k) {
    const Real f0 = from.at(k, 0), f1 = from.at(k, 1), f2 = from.at(k, 2);
    rotation.c[k] = {to.c[0].x * f0 + to.c[1].x * f1 + to.c[2].x * f2, to.c[0].y * f0 + to.c[1].y * f1 + to.c[2].y * f2,
                     to.c[0].z * f0 + to.c[1].z * f1 + to.c[2].z * f2};
  }
  return normalizedQ(quaternionOf(rotation));
}

template <typename Real>
void coneAngleV(const JiggleSettings<Real>& s, V3<Real> q, Real* angle_deg, Real* clamp_deg) {
  const V3<Real> c = coneCoords(s, q);
  const Real radial = std::hypot(c.x, c.z);
  *angle_deg = std::atan2(radial, c.y) / Real(kDegree);
  const Real cos_phi = radial > Real(0) ? c.x / radial : Real(1);
  const Real sin_phi = radial > Real(0) ? c.z / radial : Real(0);
  // tan(theta_c) = 1 / sqrt(cos^2 phi / tan^2 a + sin^2 phi / tan^2 b), times sin a sin b / (sin a sin b).
  const Real sa = s.cone_sin_major, ca = s.cone_cos_major, sb = s.cone_sin_minor, cb = s.cone_cos_minor;
  const Real denominator = std::sqrt(cos_phi * cos_phi * sb * sb * ca * ca + sin_phi * sin_phi * sa * sa * cb * cb);
  *clamp_deg = std::atan2(sa * sb, denominator) / Real(kDegree);
}

template <typename Real>
JiggleOutput<Real> evaluate(const JiggleSettings<Real>& s, V3<Real> local_offset, const Rigid<Real>& frame, Q4<Real> root) {
  const V3<Real> rest = load3(s.rest_point);
  bool moved = false;
  const V3<Real> q = clampToConeV(s, add(rest, local_offset), &moved);
  const V3<Real> up = rotate(conjugateQ(frame.rotation), rotate(root, load3(s.root_up)));
  JiggleOutput<Real> out;
  storeQ(aimRotationV(s, q, up), out.correction);
  out.at_rest = same3(q, rest);
  store3(add(frame.translation, rotate(frame.rotation, q)), out.point);
  store3(add(frame.translation, rotate(frame.rotation, rest)), out.target);
  coneAngleV(s, q, &out.angle_deg, &out.clamp_deg);
  return out;
}

// The distance limit and the cone at a step whose joint rotation is `rotation`: the offset is moved
// back and the part of the velocity relative to the target going out through the limit is dropped, an
// inelastic contact. Returns the offset in the joint's frame.
template <typename Real>
V3<Real> constrain(const JiggleSettings<Real>& s, Q4<Real> rotation, V3<Real>* offset, V3<Real>* relative_velocity) {
  const Real distance = norm3(*offset);
  if (distance > s.max_offset) {
    const V3<Real> outward = divided(*offset, distance);
    *offset = scaled(s.max_offset, outward);
    const Real away = dot3(*relative_velocity, outward);
    if (away > Real(0)) *relative_velocity = sub(*relative_velocity, scaled(away, outward));
  }
  V3<Real> local = rotate(conjugateQ(rotation), *offset);
  const V3<Real> rest = load3(s.rest_point);
  const V3<Real> q = add(rest, local);
  bool moved = false;
  const V3<Real> clamped = clampToConeV(s, q, &moved);
  if (moved && !same3(clamped, q)) {
    local = sub(clamped, rest);
    *offset = rotate(rotation, local);
    const V3<Real> normal = rotate(rotation, coneNormal(s, coneCoords(s, clamped)));
    if (norm3(normal) > Real(0)) {
      const V3<Real> outward = unit3(normal);
      const Real away = dot3(*relative_velocity, outward);
      if (away > Real(0)) *relative_velocity = sub(*relative_velocity, scaled(away, outward));
    }
  }
  return local;
}

// A step's joint, against the last frame: its translation minus the last frame's, and its rotation.
template <typename Real>
struct StepPose {
  V3<Real> moved;
  Q4<Real> rotation;
};

// One step of kJiggleStepSeconds to a joint at `pose`: semi-implicit Euler on x = p - r (the velocity
// first, then the offset with the new velocity), damping acting on the velocity relative to the
// target so a body in uniform motion does not lag, then the impulses, then the limits. Written in
// quantities relative to the target (x, v - r', and r against the last frame's joint position), the
// equations of pipeline/jiggle.cpp's old point-and-velocity form:
//   v_{n+1} - r'_n = (v_n - r'_n) + h (-k x_n - beta (v_n - r'_n)),   x_{n+1} = x_n + h (v_{n+1} - r'_n)
// with r'_n = (r_{n+1} - r_n) / h and v_n - r'_n = (v_n - r'_{n-1}) - (r'_n - r'_{n-1}).
template <typename Real>
void step(const JiggleSettings<Real>& s, const StepPose<Real>& pose, JiggleState* state) {
  static_assert(sizeof(Real) == sizeof(double), "the state steps in double");
  const Real h = Real(kJiggleStepSeconds);
  const V3<Real> target = add(pose.moved, rotate(pose.rotation, load3(s.rest_point)));  // minus the frame's position
  const V3<Real> target_velocity = divided(sub(target, load3(state->target_from_frame)), h);
  V3<Real> offset = load3(state->offset);
  V3<Real> relative = sub(load3(state->relative_velocity), sub(target_velocity, load3(state->target_velocity)));
  const V3<Real> acceleration = sub(scaled(-s.spring_k, offset), scaled(s.spring_beta, relative));
  relative = add(relative, scaled(h, acceleration));
  offset = add(offset, scaled(h, relative));
  relative = add(relative, load3(state->impulse));
  store3(V3<Real>{0, 0, 0}, state->impulse);
  const V3<Real> local = constrain(s, pose.rotation, &offset, &relative);
  for (int k = 0; k < 3; ++k) state->previous_local_offset[k] = state->local_offset[k];
  store3(local, state->local_offset);
  store3(offset, state->offset);
  store3(relative, state->relative_velocity);
  store3(target_velocity, state->target_velocity);
  store3(target, state->target_from_frame);
}

// The joint between the last frame (s = 0) and this one (s = 1): positions lerped, rotations as
// 4-vectors on one hemisphere lerped and normalized, as pipeline/jiggle.cpp blends its grid; a held
// pose stays bit-exact, so a still jiggle stays exactly at rest.
template <typename Real>
StepPose<Real> between(const Rigid<Real>& last, const Rigid<Real>& now, Real s) {
  const V3<Real> moved = sub(now.translation, last.translation);
  if (s >= Real(1)) return {moved, now.rotation};
  if (same3(last.translation, now.translation) && last.rotation.x == now.rotation.x && last.rotation.y == now.rotation.y &&
      last.rotation.z == now.rotation.z && last.rotation.w == now.rotation.w)
    return {moved, now.rotation};
  Q4<Real> to = now.rotation;
  const Q4<Real>& from = last.rotation;
  if ((from.x * to.x + from.y * to.y) + (from.z * to.z + from.w * to.w) < Real(0)) to = {-to.x, -to.y, -to.z, -to.w};
  const Real r = Real(1) - s;
  return {scaled(s, moved),
          normalizedQ(Q4<Real>{r * from.x + s * to.x, r * from.y + s * to.y, r * from.z + s * to.z, r * from.w + s * to.w})};
}

template <typename To, typename From>
Rigid<To> castRigid(const Rigid<From>& r) {
  return {{To(r.translation.x), To(r.translation.y), To(r.translation.z)},
          {To(r.rotation.x), To(r.rotation.y), To(r.rotation.z), To(r.rotation.w)}};
}

// The settings the double steps read: the rig's own for a double rig, a widened copy for a float one.
template <typename Real>
const JiggleSettings<double>& stepSettings(const JiggleSettings<Real>& s, JiggleSettings<double>* storage) {
  if constexpr (sizeof(Real) == sizeof(double)) {
    (void)storage;
    return s;
  } else {
    JiggleSettings<double>& w = *storage;
    w.joint = s.joint;
    w.parent = s.parent;
    w.root = s.root;
    for (int k = 0; k < 3; ++k) {
      w.aim_axis[k] = s.aim_axis[k];
      w.major_axis[k] = s.major_axis[k];
      w.minor_axis[k] = s.minor_axis[k];
      w.root_up[k] = s.root_up[k];
      w.rest_point[k] = s.rest_point[k];
    }
    w.length = s.length;
    w.max_offset = s.max_offset;
    w.spring_k = s.spring_k;
    w.spring_beta = s.spring_beta;
    w.cone_gx = s.cone_gx;
    w.cone_gy = s.cone_gy;
    w.cone_gz = s.cone_gz;
    w.cone_sin_major = s.cone_sin_major;
    w.cone_cos_major = s.cone_cos_major;
    w.cone_sin_minor = s.cone_sin_minor;
    w.cone_cos_minor = s.cone_cos_minor;
    return w;
  }
}

template <typename Real>
const Real* matrixOfJoint(const Span<const Real>& matrices, int joint) {
  return joint >= 0 ? matrices.data + 16 * static_cast<std::size_t>(joint) : nullptr;
}

template <typename Real>
void startAt(const JiggleSettings<Real>& s, const Rigid<Real>& frame, V3<Real> target_velocity, JiggleState* state) {
  static_assert(sizeof(Real) == sizeof(double), "the state steps in double");
  store3(V3<Real>{0, 0, 0}, state->offset);
  store3(load3(state->impulse), state->relative_velocity);
  store3(V3<Real>{0, 0, 0}, state->impulse);
  store3(target_velocity, state->target_velocity);
  store3(rotate(frame.rotation, load3(s.rest_point)), state->target_from_frame);
  store3(V3<Real>{0, 0, 0}, state->local_offset);
  store3(V3<Real>{0, 0, 0}, state->previous_local_offset);
  store3(frame.translation, state->frame_translation);
  storeQ(frame.rotation, state->frame_rotation);
  state->since_step = 0;
  state->started = true;
}

template <typename Real>
bool finite3(const Real* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

template <typename Real>
bool unitish(const Real* v) {
  const Real n = norm3(load3(v));
  return std::isfinite(n) && std::fabs(n - Real(1)) < Real(1e-4);
}

template <typename Real>
bool spanFits(const Span<Real>& span, std::size_t needed) {
  return span.empty() ? true : span.size >= needed && span.data != nullptr;
}

template <typename Real>
bool matricesFit(const JiggleRig<Real>& rig, const Span<const Real>& matrices) {
  const std::size_t needed = 16 * static_cast<std::size_t>(rig.joint_count);
  return matrices.size >= needed && (needed == 0 || matrices.data != nullptr);
}

template <typename Real>
bool jointsFit(const JiggleRig<Real>& rig) {
  for (const JiggleSettings<Real>& s : rig.jiggles) {
    if (s.joint < 0 || s.joint >= rig.joint_count || s.parent < -1 || s.parent >= rig.joint_count || s.root < -1 ||
        s.root >= rig.joint_count)
      return false;
  }
  return true;
}

}  // namespace jiggle_detail

using namespace jiggle_detail;

JiggleSpring jiggleSpring(double stiffness, double damping) {
  const double frequency = kJiggleMinHz * std::pow(kJiggleMaxHz / kJiggleMinHz, stiffness);
  const double omega = 2.0 * kPi * frequency;
  const double zeta = kJiggleMinDampingRatio + (1.0 - kJiggleMinDampingRatio) * damping;
  return {omega * omega, 2.0 * zeta * omega};
}

template <typename Real>
const char* jiggleSpecProblem(const JiggleSpec<Real>& spec, int joint_count) {
  if (spec.joint < 0 || spec.joint >= joint_count) return "the jiggling joint is not one of the joint matrices";
  if (spec.parent < -1 || spec.parent >= joint_count) return "the parent is not one of the joint matrices";
  if (spec.root < -1 || spec.root >= joint_count) return "the root is not one of the joint matrices";
  if (!finite3(spec.aim_axis) || !unitish(spec.aim_axis)) return "aim_axis is not a unit vector";
  if (!finite3(spec.major_axis) || !unitish(spec.major_axis)) return "major_axis is not a unit vector";
  if (std::fabs(dot3(load3(spec.aim_axis), load3(spec.major_axis))) > Real(1e-4))
    return "major_axis is not perpendicular to aim_axis";
  if (!finite3(spec.root_up) || !unitish(spec.root_up)) return "root_up is not a unit vector";
  if (!(std::isfinite(spec.length) && spec.length > Real(0))) return "length must be positive";
  auto in = [](Real v, Real lo, Real hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (!in(spec.stiffness, 0, 1)) return "stiffness must be in [0, 1]";
  if (!in(spec.damping, 0, 1)) return "damping must be in [0, 1]";
  if (!in(spec.clamp_major_deg, 0, 90)) return "clamp_major_deg must be in [0, 90]";
  if (!in(spec.clamp_minor_deg, 0, 90)) return "clamp_minor_deg must be in [0, 90]";
  return "";
}

template <typename Real>
JiggleSettings<Real> buildJiggleSettings(const JiggleSpec<Real>& spec) {
  JiggleSettings<Real> s;
  s.joint = spec.joint;
  s.parent = spec.parent;
  s.root = spec.root;
  for (int k = 0; k < 3; ++k) {
    s.aim_axis[k] = spec.aim_axis[k];
    s.major_axis[k] = spec.major_axis[k];
    s.root_up[k] = spec.root_up[k];
  }
  store3(cross3(load3(s.aim_axis), load3(s.major_axis)), s.minor_axis);
  s.length = spec.length;
  store3(scaled(s.length, load3(s.aim_axis)), s.rest_point);
  s.max_offset = Real(kJiggleMaxOffset) * s.length;
  const JiggleSpring spring = jiggleSpring(spec.stiffness, spec.damping);
  s.spring_k = Real(spring.k);
  s.spring_beta = Real(spring.beta);
  // The cone's trigonometry in double whatever Real is: the float settings are the double ones rounded.
  const double a = std::fmax(static_cast<double>(spec.clamp_major_deg), kJiggleMinClampDeg) * kDegree;
  const double b = std::fmax(static_cast<double>(spec.clamp_minor_deg), kJiggleMinClampDeg) * kDegree;
  const double sa = std::sin(a), ca = std::cos(a), sb = std::sin(b), cb = std::cos(b);
  s.cone_sin_major = Real(sa);
  s.cone_cos_major = Real(ca);
  s.cone_sin_minor = Real(sb);
  s.cone_cos_minor = Real(cb);
  s.cone_gx = Real(ca * ca * sb * sb);
  s.cone_gz = Real(cb * cb * sa * sa);
  s.cone_gy = Real(sa * sa * sb * sb);
  return s;
}

template <typename Real>
const char* jiggleRigProblem(const JiggleRig<Real>& rig) {
  if (rig.joint_count < 0) return "the rig's joint count is negative";
  if (!jointsFit(rig)) return "a jiggle names a joint outside the rig's joint matrices";
  for (const JiggleSettings<Real>& s : rig.jiggles) {
    if (!(std::isfinite(s.length) && s.length > Real(0))) return "a jiggle's length is not positive";
    if (!(std::isfinite(s.spring_k) && s.spring_k >= Real(0) && std::isfinite(s.spring_beta) && s.spring_beta >= Real(0)))
      return "a jiggle's spring constants are not finite and non-negative";
  }
  return "";
}

template <typename Real>
JiggleOutput<Real> evaluateJiggle(const JiggleSettings<Real>& settings, const Real local_offset[3], const Real* joint_matrix,
                                  const Real* root_matrix) {
  return evaluate(settings, load3(local_offset), rigidOf(joint_matrix, static_cast<V3<Real>*>(nullptr)),
                  rotationOrIdentity(root_matrix));
}

template <typename Real>
void blendJiggleOffset(const Real a[3], const Real b[3], Real fraction, Real out[3]) {
  for (int k = 0; k < 3; ++k) {
    out[k] = fraction == Real(0) ? a[k] : fraction == Real(1) ? b[k] : (Real(1) - fraction) * a[k] + fraction * b[k];
  }
}

template <typename Real>
bool clampJiggleToCone(const JiggleSettings<Real>& settings, const Real q[3], Real out[3]) {
  bool moved = false;
  store3(clampToConeV(settings, load3(q), &moved), out);
  return moved;
}

template <typename Real>
void jiggleConeAngle(const JiggleSettings<Real>& settings, const Real q[3], Real* angle_deg, Real* clamp_deg) {
  coneAngleV(settings, load3(q), angle_deg, clamp_deg);
}

template <typename Real>
void jiggleAimRotation(const JiggleSettings<Real>& settings, const Real q[3], const Real up[3], Real out[4]) {
  storeQ(aimRotationV(settings, load3(q), load3(up)), out);
}

template <typename Real>
void jiggleRigidFrame(const Real* matrix, Real translation[3], Real rotation[4], Real* scale) {
  V3<Real> s;
  const Rigid<Real> rigid = rigidOf(matrix, &s);
  store3(rigid.translation, translation);
  storeQ(rigid.rotation, rotation);
  if (scale) store3(s, scale);
}

template <typename Real>
bool JiggleResetJob<Real>::Validate() const {
  if (rig == nullptr || !jointsFit(*rig) || !matricesFit(*rig, joint_matrices)) return false;
  if (states.size < rig->jiggles.size() || (!rig->jiggles.empty() && states.data == nullptr)) return false;
  if (!velocity_matrices.empty() && (!matricesFit(*rig, velocity_matrices) || !std::isfinite(velocity_time) ||
                                     velocity_time == Real(0)))
    return false;
  return true;
}

template <typename Real>
bool JiggleResetJob<Real>::Run() const {
  if (!Validate()) return false;
  for (std::size_t i = 0; i < rig->jiggles.size(); ++i) {
    JiggleSettings<double> storage;
    const JiggleSettings<double>& s = stepSettings(rig->jiggles[i], &storage);
    const int joint = rig->jiggles[i].joint;
    const Rigid<double> frame = castRigid<double>(rigidOf(matrixOfJoint(joint_matrices, joint), static_cast<V3<Real>*>(nullptr)));
    V3<double> target_velocity = {0, 0, 0};
    if (!velocity_matrices.empty()) {
      const Rigid<double> other =
          castRigid<double>(rigidOf(matrixOfJoint(velocity_matrices, joint), static_cast<V3<Real>*>(nullptr)));
      const V3<double> rest = load3(s.rest_point);
      const V3<double> moved = add(sub(other.translation, frame.translation), rotate(other.rotation, rest));
      target_velocity = divided(sub(moved, rotate(frame.rotation, rest)), double(velocity_time));
    }
    startAt(s, frame, target_velocity, &states[i]);
  }
  return true;
}

template <typename Real>
bool JiggleJob<Real>::Validate() const {
  if (rig == nullptr || !jointsFit(*rig) || !matricesFit(*rig, joint_matrices)) return false;
  const std::size_t n = rig->jiggles.size();
  if (states.size < n || (n > 0 && states.data == nullptr)) return false;
  if (!std::isfinite(delta_time) || delta_time < Real(0) || max_steps < 0) return false;
  return spanFits(corrections, 4 * n) && spanFits(local_rotations, 4 * n) && spanFits(model_matrices, 16 * n) &&
         spanFits(points, 3 * n) && spanFits(cone_angles, 2 * n);
}

template <typename Real>
bool JiggleJob<Real>::Run() const {
  if (!Validate()) return false;
  const double h = kJiggleStepSeconds;
  const double tolerance = timeTolerance<Real>();
  const double dt = delta_time;
  for (std::size_t i = 0; i < rig->jiggles.size(); ++i) {
    const JiggleSettings<Real>& s = rig->jiggles[i];
    JiggleSettings<double> storage;
    const JiggleSettings<double>& wide = stepSettings(s, &storage);
    JiggleState& state = states[i];
    const Real* joint = matrixOfJoint(joint_matrices, s.joint);
    const Rigid<Real> now = rigidOf(joint, static_cast<V3<Real>*>(nullptr));
    const Rigid<double> now_wide = castRigid<double>(now);
    if (!state.started) {
      startAt(wide, now_wide, V3<double>{0, 0, 0}, &state);
    } else {
      // The steps that fall in this frame: step m is m h - since_step after the last frame.
      const double available = state.since_step + dt;
      const double counted = std::floor((available + tolerance) / h);
      long steps = counted > 0.0 ? static_cast<long>(std::fmin(counted, 1e9)) : 0;
      bool squeezed = false;
      if (max_steps > 0 && steps > max_steps) {
        steps = max_steps;
        squeezed = true;
      }
      const Rigid<double> last = {load3(state.frame_translation), loadQ(state.frame_rotation)};
      bool on_frame = false;
      for (long m = 1; m <= steps; ++m) {
        double fraction;
        if (squeezed) {
          fraction = double(m) / double(steps);
        } else {
          const double after = double(m) * h - state.since_step;
          fraction = std::fabs(after - dt) <= tolerance ? 1.0 : std::fmin(1.0, after / dt);
        }
        step(wide, between(last, now_wide, fraction), &state);
        on_frame = fraction >= 1.0;
      }
      state.since_step = squeezed ? 0.0 : std::fmax(0.0, available - double(steps) * h);
      // The last target, against this frame's joint position from now on (exactly the rotated rest
      // point when the last step was on this frame).
      store3(on_frame ? rotate(now_wide.rotation, load3(wide.rest_point))
                      : sub(load3(state.target_from_frame), sub(now_wide.translation, last.translation)),
             state.target_from_frame);
      store3(now_wide.translation, state.frame_translation);
      storeQ(now_wide.rotation, state.frame_rotation);
    }

    if (corrections.empty() && points.empty() && cone_angles.empty() && local_rotations.empty() && model_matrices.empty())
      continue;
    // This frame's time is since_step after the last step: the offset there, extrapolated from the
    // last two steps (exactly the last step's when the frame is on the step grid).
    double blended[3];
    blendJiggleOffset(state.previous_local_offset, state.local_offset, 1.0 + state.since_step / h, blended);
    const Real offset[3] = {Real(blended[0]), Real(blended[1]), Real(blended[2])};
    const Real* root = matrixOfJoint(joint_matrices, s.root);
    const JiggleOutput<Real> out = evaluate(s, load3(offset), now, rotationOrIdentity(root));
    if (!corrections.empty()) storeQ(loadQ(out.correction), corrections.data + 4 * i);
    if (!points.empty()) store3(load3(out.point), points.data + 3 * i);
    if (!cone_angles.empty()) {
      cone_angles[2 * i] = out.angle_deg;
      cone_angles[2 * i + 1] = out.clamp_deg;
    }
    if (local_rotations.empty() && model_matrices.empty()) continue;
    // The parent-relative TRS of the joint, and the jiggle applied in its own frame: T (R D) S.
    const Real* parent = matrixOfJoint(joint_matrices, s.parent);
    Real local[16];
    Real inverse[16];
    if (parent && invertAffine4(parent, inverse)) {
      detail::multiplyAffine(inverse, joint, local);
    } else {
      for (int k = 0; k < 16; ++k) local[k] = joint[k];
    }
    V3<Real> scale;
    const Rigid<Real> local_rigid = rigidOf(local, &scale);
    const Q4<Real> jiggled = out.at_rest ? local_rigid.rotation : normalizedQ(multiplyQ(local_rigid.rotation, loadQ(out.correction)));
    if (!local_rotations.empty()) storeQ(jiggled, local_rotations.data + 4 * i);
    if (!model_matrices.empty()) {
      Real* model = model_matrices.data + 16 * i;
      if (out.at_rest) {
        for (int k = 0; k < 16; ++k) model[k] = joint[k];
        continue;
      }
      const M3<Real> r = matrixOf(jiggled);
      const Real axis_scale[3] = {scale.x, scale.y, scale.z};
      Real jiggled_local[16];
      for (int c = 0; c < 3; ++c) {
        store3(scaled(axis_scale[c], r.c[c]), jiggled_local + 4 * c);
        jiggled_local[4 * c + 3] = Real(0);
      }
      store3(local_rigid.translation, jiggled_local + 12);
      jiggled_local[15] = Real(1);
      if (parent) {
        detail::multiplyAffine(parent, jiggled_local, model);
      } else {
        for (int k = 0; k < 16; ++k) model[k] = jiggled_local[k];
      }
    }
  }
  return true;
}

template <typename Real>
bool applyJiggleImpulse(const Span<JiggleState>& states, std::size_t jiggle, const Real direction[3],
                        typename JiggleNonDeduced<Real>::type magnitude) {
  if (jiggle >= states.size || states.data == nullptr || !finite3(direction) || !std::isfinite(magnitude)) return false;
  const V3<double> d = {double(direction[0]), double(direction[1]), double(direction[2])};
  const double n2 = dot3(d, d);
  if (!(n2 > 0.0) || !std::isfinite(n2)) return false;
  JiggleState& state = states[jiggle];
  store3(add(load3(state.impulse), scaled(double(magnitude), unit3(d))), state.impulse);
  return true;
}

template <typename Real>
int applyJiggleImpulseMask(const Span<JiggleState>& states, std::uint64_t mask, const Real direction[3],
                           typename JiggleNonDeduced<Real>::type magnitude) {
  int applied = 0;
  for (std::size_t i = 0; i < 64 && i < states.size; ++i) {
    if ((mask >> i) & 1u) applied += applyJiggleImpulse<Real>(states, i, direction, magnitude) ? 1 : 0;
  }
  return applied;
}

#define RIGBAKE_JIGGLE_INSTANTIATE(Real)                                                                                   \
  template struct JiggleResetJob<Real>;                                                                                    \
  template struct JiggleJob<Real>;                                                                                         \
  template const char* jiggleSpecProblem(const JiggleSpec<Real>&, int);                                                    \
  template JiggleSettings<Real> buildJiggleSettings(const JiggleSpec<Real>&);                                              \
  template const char* jiggleRigProblem(const JiggleRig<Real>&);                                                           \
  template JiggleOutput<Real> evaluateJiggle(const JiggleSettings<Real>&, const Real*, const Real*, const Real*);           \
  template void blendJiggleOffset(const Real*, const Real*, Real, Real*);                                                  \
  template bool clampJiggleToCone(const JiggleSettings<Real>&, const Real*, Real*);                                        \
  template void jiggleConeAngle(const JiggleSettings<Real>&, const Real*, Real*, Real*);                                   \
  template void jiggleAimRotation(const JiggleSettings<Real>&, const Real*, const Real*, Real*);                           \
  template void jiggleRigidFrame(const Real*, Real*, Real*, Real*);                                                        \
  template bool applyJiggleImpulse<Real>(const Span<JiggleState>&, std::size_t, const Real*, Real);                                \
  template int applyJiggleImpulseMask<Real>(const Span<JiggleState>&, std::uint64_t, const Real*, Real);

RIGBAKE_JIGGLE_INSTANTIATE(float)
RIGBAKE_JIGGLE_INSTANTIATE(double)
#undef RIGBAKE_JIGGLE_INSTANTIATE

}  // namespace rigbake::runtime
