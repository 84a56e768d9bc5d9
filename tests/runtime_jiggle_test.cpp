// The jiggle in runtime/ (runtime/jiggle.h) as the bake and an engine use it: the bake's tracks equal
// what the pre-runtime pipeline code produced, the float runtime agrees with the double one, and the
// engine-facing job (leftover time, impulses, reset, outputs) behaves as docs/runtime.md says.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>

#include "anatomy/placement.h"
#include "anatomy_fixture.h"
#include "formats/jiggle_json.h"
#include "pipeline/bake.h"
#include "pipeline/jiggle.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "runtime/jiggle.h"

namespace rigbake {
namespace runtime_jiggle_test {

// The jiggle as pipeline/jiggle.cpp computed it before it moved to runtime/jiggle.cpp (commit 7ebe1d4),
// kept verbatim apart from its namespace, forward declarations and four names prefixed "old" (so that
// argument-dependent lookup does not find the pipeline's): the frozen reference the
// runtime-driven bake must reproduce to 1e-12. Not to be updated when the jiggle changes on purpose;
// delete it (and the test below) then instead.
namespace legacy {

constexpr double kJiggleTimestep = 1.0 / 240.0;
constexpr double kMinJiggleHz = 1.0;
constexpr double kMaxJiggleHz = 12.0;
constexpr double kMinDampingRatio = 0.02;
constexpr double kMinClampDeg = 0.01;
constexpr double kMaxJiggleOffset = 1.5;

SpringConstants oldSpringConstants(const JiggleParams& params);
Eigen::Vector3d oldClampToCone(const JiggleSetup& setup, const Eigen::Vector3d& q);
ConeAngle oldConeAngle(const JiggleSetup& setup, const Eigen::Vector3d& q);
Eigen::Quaterniond oldAimRotation(const JiggleSetup& setup, const Eigen::Vector3d& q, const Eigen::Vector3d& up);

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
// Below this |sin| between the aim and the up vector the talk's aim frame is ill-conditioned; the
// shortest-arc rotation (identical for motion in the aim-up plane) takes over.
constexpr double kAimDegenerateSin = 1e-6;
// Frame times this close are the same instant (t0 + n h and n/fps differ by rounding).
constexpr double kFrameTimeTolerance = 1e-9;

struct RigidFrame {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // the pivot's, scale removed
  Eigen::Quaterniond root = Eigen::Quaterniond::Identity();      // the root's, scale removed
};

// One cone in the (major, aim, minor) = (x, y, z) coordinates of the talk, with its equation
// y^2 = x^2 / tan^2(a) + z^2 / tan^2(b) multiplied through by sin^2(a) sin^2(b), so that 90-degree
// half-angles (tan infinite) stay finite: G = x^2 c_a^2 s_b^2 + z^2 c_b^2 s_a^2 - y^2 s_a^2 s_b^2.
struct Cone {
  Eigen::Vector3d aim, major, minor;
  double gx, gy, gz;  // G = gx x^2 + gz z^2 - gy y^2
  double sa, ca, sb, cb;

  explicit Cone(const JiggleSetup& setup) {
    aim = setup.aim_axis;
    major = setup.major_axis;
    minor = aim.cross(major);
    const double a = std::max(setup.params.clamp_major_deg, kMinClampDeg) * kDegree;
    const double b = std::max(setup.params.clamp_minor_deg, kMinClampDeg) * kDegree;
    sa = std::sin(a);
    ca = std::cos(a);
    sb = std::sin(b);
    cb = std::cos(b);
    gx = ca * ca * sb * sb;
    gz = cb * cb * sa * sa;
    gy = sa * sa * sb * sb;
  }
  Eigen::Vector3d coords(const Eigen::Vector3d& q) const { return {q.dot(major), q.dot(aim), q.dot(minor)}; }
  double value(const Eigen::Vector3d& c) const { return gx * c.x() * c.x() + gz * c.z() * c.z() - gy * c.y() * c.y(); }
  bool inside(const Eigen::Vector3d& c) const { return c.y() >= 0.0 && value(c) <= 0.0; }
  // Outward normal (grad G) in the joint's frame.
  Eigen::Vector3d normal(const Eigen::Vector3d& c) const {
    return 2.0 * (gx * c.x() * major - gy * c.y() * aim + gz * c.z() * minor);
  }
};

// The axis (of `order`) of a rotation most perpendicular to a unit direction given in the same frame.
Eigen::Vector3d mostPerpendicular(const Eigen::Vector3d& direction, const std::vector<Eigen::Vector3d>& order) {
  Eigen::Vector3d best = order.front();
  double best_dot = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& axis : order) {
    const double dot = std::abs(axis.dot(direction));
    if (dot < best_dot - 1e-12) {
      best_dot = dot;
      best = axis;
    }
  }
  return best;
}

Eigen::Quaterniond rotationOf(const Eigen::Affine3d& transform) { return decomposeTrs(transform).rotation.normalized(); }

RigidFrame rigidFrame(const Eigen::Affine3d& pivot, const Eigen::Affine3d& root) {
  const Trs trs = decomposeTrs(pivot);
  return {trs.translation, trs.rotation.normalized(), rotationOf(root)};
}

bool hitReaches(const HitImpulse& hit, const JiggleSetup& setup, const std::string& clip_name) {
  if (!hit.clip.empty() && hit.clip != clip_name) return false;
  for (const std::string& part : hit.joints) {
    if (std::find(setup.parts.begin(), setup.parts.end(), part) != setup.parts.end()) return true;
  }
  return false;
}

struct OutputFrame {
  RigidFrame rigid;
  Trs local;  // the jiggling joint's animated local TRS
};

// The simulation shared by both hosts: `grid[n]` is the animated frame at t0 + n h (n = 0..N),
// `outputs[i]` the one at sample_times[i].
JiggleTrack simulate(const JiggleSetup& setup, const std::vector<double>& sample_times, const std::vector<RigidFrame>& grid,
                     const std::vector<OutputFrame>& outputs, const std::vector<HitImpulse>& hits,
                     const std::string& clip_name) {
  assert(!sample_times.empty() && grid.size() >= 2 && outputs.size() == sample_times.size());
  const double h = kJiggleTimestep;
  const double t0 = sample_times.front();
  const int steps = static_cast<int>(grid.size()) - 1;
  const SpringConstants spring = oldSpringConstants(setup.params);
  const Cone cone(setup);
  const Eigen::Vector3d rest_point = setup.length * setup.aim_axis;
  const double max_offset = kMaxJiggleOffset * setup.length;
  auto target = [&](int n) -> Eigen::Vector3d { return grid[n].translation + grid[n].rotation * rest_point; };

  // Velocity changes per step: a hit at time t acts at the first step at or after t.
  std::vector<Eigen::Vector3d> kicks(grid.size(), Eigen::Vector3d::Zero());
  for (const HitImpulse& hit : hits) {
    if (!hitReaches(hit, setup, clip_name) || hit.direction.norm() == 0.0) continue;
    const int n = std::max(0, static_cast<int>(std::ceil((hit.time - t0) / h - 1e-9)));
    if (n <= steps) kicks[n] += hit.magnitude * hit.direction.normalized();
  }

  // The distance limit and the cone, at step n: move p back and drop the outward part of the velocity
  // relative to the target (an inelastic contact with the limit). Returns the offset in the frame.
  auto constrain = [&](int n, Eigen::Vector3d& p, Eigen::Vector3d& v, const Eigen::Vector3d& target_velocity) {
    const Eigen::Vector3d r = target(n);
    Eigen::Vector3d offset = p - r;
    const double distance = offset.norm();
    if (distance > max_offset) {
      const Eigen::Vector3d outward = offset / distance;
      offset = outward * max_offset;
      p = r + offset;
      const double away = (v - target_velocity).dot(outward);
      if (away > 0.0) v -= away * outward;
    }
    const Eigen::Quaterniond& rotation = grid[n].rotation;
    Eigen::Vector3d local = rotation.conjugate() * offset;
    const Eigen::Vector3d q = rest_point + local;
    const Eigen::Vector3d clamped = oldClampToCone(setup, q);
    if (clamped != q) {
      local = clamped - rest_point;
      p = r + rotation * local;
      const Eigen::Vector3d normal = rotation * cone.normal(cone.coords(clamped));
      if (normal.norm() > 0.0) {
        const Eigen::Vector3d outward = normal.normalized();
        const double away = (v - target_velocity).dot(outward);
        if (away > 0.0) v -= away * outward;
      }
    }
    return local;
  };

  // Start at rest on the target, moving with it, so a clip that starts in motion does not kick.
  std::vector<Eigen::Vector3d> offsets(grid.size());
  Eigen::Vector3d p = target(0);
  Eigen::Vector3d v = (target(1) - target(0)) / h + kicks[0];
  offsets[0] = constrain(0, p, v, (target(1) - target(0)) / h);
  for (int n = 0; n < steps; ++n) {
    // Semi-implicit Euler on x = p - r: the velocity first, then the position with the new velocity.
    // Damping acts on the velocity relative to the target, so a body in uniform motion does not lag.
    const Eigen::Vector3d r = target(n);
    const Eigen::Vector3d target_velocity = (target(n + 1) - r) / h;
    v += h * (-spring.k * (p - r) - spring.beta * (v - target_velocity));
    p += h * v;
    v += kicks[n + 1];
    offsets[n + 1] = constrain(n + 1, p, v, target_velocity);
  }

  JiggleTrack track;
  track.name = setup.name;
  track.host = setup.host;
  track.joint = setup.joint;
  track.muscle = setup.muscle;
  track.times = sample_times;
  for (size_t i = 0; i < sample_times.size(); ++i) {
    // The state between two steps, as the offset in the joint's frame (the cone is convex there, so
    // the blend of two clamped offsets is inside it), put back on the exactly sampled animation.
    const double u = (sample_times[i] - t0) / h;
    const int n = std::min(std::max(static_cast<int>(std::floor(u)), 0), steps - 1);
    const double frac = std::min(std::max(u - n, 0.0), 1.0);
    const Eigen::Vector3d offset = frac == 0.0 ? offsets[n] : frac == 1.0 ? offsets[n + 1]
                                                                          : (1.0 - frac) * offsets[n] + frac * offsets[n + 1];
    const Eigen::Vector3d q = oldClampToCone(setup, rest_point + offset);
    const RigidFrame& frame = outputs[i].rigid;
    const Eigen::Vector3d up = frame.rotation.conjugate() * (frame.root * setup.root_up);
    Trs local = outputs[i].local;
    local.rotation = (local.rotation * oldAimRotation(setup, q, up)).normalized();
    if (q == rest_point) local.rotation = outputs[i].local.rotation;  // exactly the animation at rest
    track.local.push_back(local);
    track.point.push_back(frame.translation + frame.rotation * q);
    track.target.push_back(frame.translation + frame.rotation * rest_point);
    const ConeAngle angle = oldConeAngle(setup, q);
    track.angle_deg.push_back(angle.angle_deg);
    track.clamp_deg.push_back(angle.clamp_deg);
  }
  return track;
}

int gridSteps(const std::vector<double>& sample_times) {
  const double span = sample_times.back() - sample_times.front();
  return std::max(1, static_cast<int>(std::ceil(span / kJiggleTimestep - 1e-9)));
}

SpringConstants oldSpringConstants(const JiggleParams& params) {
  const double frequency = kMinJiggleHz * std::pow(kMaxJiggleHz / kMinJiggleHz, params.stiffness);
  const double omega = 2.0 * kPi * frequency;
  const double zeta = kMinDampingRatio + (1.0 - kMinDampingRatio) * params.damping;
  return {omega * omega, 2.0 * zeta * omega};
}

Eigen::Vector3d oldClampToCone(const JiggleSetup& setup, const Eigen::Vector3d& q) {
  const Cone cone(setup);
  const Eigen::Vector3d c1 = cone.coords(q);
  if (cone.inside(c1)) return q;
  // The talk's segment from the rest point x0 = (0, L, 0), inside the cone, to q: f(t) = G(x0 + t d)
  // = A t^2 + B t + C with C = G(x0) < 0, so the first root in (0, 1] is where it leaves the cone.
  const double length = setup.length;
  const Eigen::Vector3d d = c1 - Eigen::Vector3d(0.0, length, 0.0);
  const double a = cone.gx * d.x() * d.x() + cone.gz * d.z() * d.z() - cone.gy * d.y() * d.y();
  const double b = -2.0 * cone.gy * d.y() * length;
  const double c = -cone.gy * length * length;
  double t = -1.0;
  auto consider = [&t](double root) {
    if (std::isfinite(root) && root > 0.0 && root <= 1.0 && (t < 0.0 || root < t)) t = root;
  };
  if (std::abs(a) <= 1e-300) {
    consider(-c / b);
  } else {
    const double discriminant = b * b - 4.0 * a * c;
    if (discriminant >= 0.0) {
      // Numerically stable roots (no cancellation between -b and the square root).
      const double half = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
      consider(half / a);
      if (half != 0.0) consider(c / half);
    }
  }
  const Eigen::Vector3d rest = length * setup.aim_axis;
  auto insideAt = [&](double s) { return cone.inside(cone.coords(rest + s * (q - rest))); };
  // The front nappe is convex, so the points of the segment inside it are one interval [0, t*]. The
  // quadratic's root is t* up to rounding, which near a double root (a segment grazing a 90-degree
  // cone's plane y = 0) is only sqrt(epsilon) accurate, or even lost to a slightly negative
  // discriminant: bisect for the last inside t in a bracket around the root (or in [0, 1] without one),
  // so the result is inside, on the surface to the last bit, and clamping it again changes nothing.
  double inside = 0.0, outside = 1.0;
  if (t > 0.0) {
    const double low = t * (1.0 - 1e-6), high = std::min(1.0, t * (1.0 + 1e-6));
    if (insideAt(low) && !insideAt(high)) {
      inside = low;
      outside = high;
    }
  }
  for (int i = 0; i < 200; ++i) {
    const double middle = 0.5 * (inside + outside);
    if (middle <= inside || middle >= outside) break;
    (insideAt(middle) ? inside : outside) = middle;
  }
  return rest + inside * (q - rest);
}

ConeAngle oldConeAngle(const JiggleSetup& setup, const Eigen::Vector3d& q) {
  const Cone cone(setup);
  const Eigen::Vector3d c = cone.coords(q);
  const double radial = std::hypot(c.x(), c.z());
  ConeAngle result;
  result.angle_deg = std::atan2(radial, c.y()) / kDegree;
  const double cos_phi = radial > 0.0 ? c.x() / radial : 1.0;
  const double sin_phi = radial > 0.0 ? c.z() / radial : 0.0;
  // tan(theta_c) = 1 / sqrt(cos^2 phi / tan^2 a + sin^2 phi / tan^2 b), times sin a sin b / (sin a sin b).
  const double denominator = std::sqrt(cos_phi * cos_phi * cone.sb * cone.sb * cone.ca * cone.ca +
                                       sin_phi * sin_phi * cone.sa * cone.sa * cone.cb * cone.cb);
  result.clamp_deg = std::atan2(cone.sa * cone.sb, denominator) / kDegree;
  return result;
}

Eigen::Quaterniond oldAimRotation(const JiggleSetup& setup, const Eigen::Vector3d& q, const Eigen::Vector3d& up) {
  if (q == setup.length * setup.aim_axis || q.norm() == 0.0) return Eigen::Quaterniond::Identity();
  const Eigen::Vector3d u = q.normalized();
  const Eigen::Vector3d a = setup.aim_axis;
  const Eigen::Vector3d up_unit = up.normalized();
  const Eigen::Vector3d w_jiggle = u.cross(up_unit);
  const Eigen::Vector3d w_rest = a.cross(up_unit);
  if (w_jiggle.norm() < kAimDegenerateSin || w_rest.norm() < kAimDegenerateSin)
    return Eigen::Quaterniond::FromTwoVectors(a, u);
  // The talk's aim frame [u, v, w] with w = u x up, v = w x u, for the jiggle point and for the rest
  // point; the jiggle rotation maps one onto the other.
  auto frame = [&up_unit](const Eigen::Vector3d& aim) {
    const Eigen::Vector3d w = aim.cross(up_unit).normalized();
    const Eigen::Vector3d v = w.cross(aim);
    Eigen::Matrix3d m;
    m.col(0) = aim;
    m.col(1) = v;
    m.col(2) = w;
    return m;
  };
  const Eigen::Matrix3d rotation = frame(u) * frame(a).transpose();
  return Eigen::Quaterniond(rotation).normalized();
}

std::vector<JiggleTrack> simulateJiggle(const Skeleton& skeleton, const Clip& clip, const std::vector<double>& sample_times,
                                        const std::vector<JiggleSetup>& setups, const std::vector<HitImpulse>& hits) {
  assert(!sample_times.empty() && std::is_sorted(sample_times.begin(), sample_times.end()));
  std::vector<const JiggleSetup*> active;
  for (const JiggleSetup& setup : setups) {
    assert(jiggleSetupProblem(setup, skeleton).empty());
    if (setup.host == JiggleHost::kSkeletonJoint) active.push_back(&setup);
  }
  if (active.empty()) return {};
  // The animation at every internal step, sampled from the clip itself: the steps are the same
  // whatever the output rate, so the motion is too.
  const int steps = gridSteps(sample_times);
  std::vector<Pose> grid_poses;
  grid_poses.reserve(steps + 1);
  for (int n = 0; n <= steps; ++n) grid_poses.push_back(sampleClip(skeleton, clip, sample_times.front() + n * kJiggleTimestep));
  std::vector<Pose> output_poses;
  for (double time : sample_times) output_poses.push_back(sampleClip(skeleton, clip, time));

  std::vector<JiggleTrack> tracks;
  for (const JiggleSetup* setup : active) {
    const int j = setup->joint;
    auto rootWorld = [&](const Pose& pose) -> const Eigen::Affine3d& {
      return setup->root >= 0 ? pose.world[setup->root] : skeleton.root_parent_world[j];
    };
    std::vector<RigidFrame> grid;
    for (const Pose& pose : grid_poses) grid.push_back(rigidFrame(pose.world[j], rootWorld(pose)));
    std::vector<OutputFrame> outputs;
    for (const Pose& pose : output_poses) outputs.push_back({rigidFrame(pose.world[j], rootWorld(pose)), pose.local[j]});
    tracks.push_back(simulate(*setup, sample_times, grid, outputs, hits, clip.name));
  }
  return tracks;
}

JiggleTrack simulateJiggleFrames(const JiggleSetup& setup, const std::vector<double>& sample_times,
                                 const std::vector<double>& frame_times, const std::vector<JiggleFrame>& frames,
                                 const std::vector<HitImpulse>& hits, const std::string& clip_name) {
  assert(!sample_times.empty() && frames.size() == frame_times.size() && !frame_times.empty());
  assert(std::is_sorted(sample_times.begin(), sample_times.end()) && std::is_sorted(frame_times.begin(), frame_times.end()));
  std::vector<OutputFrame> known;
  for (const JiggleFrame& frame : frames)
    known.push_back({rigidFrame(frame.pivot, frame.root), decomposeTrs(frame.parent.inverse() * frame.pivot)});
  // Every sample time must be among the frame times (jiggleFrameTimes() guarantees it).
  std::vector<OutputFrame> outputs;
  size_t at = 0;
  for (double time : sample_times) {
    while (at + 1 < frame_times.size() && frame_times[at] < time - kFrameTimeTolerance) ++at;
    assert(std::abs(frame_times[at] - time) <= kFrameTimeTolerance);
    outputs.push_back(known[at]);
  }
  // Between samples the animation is only known through the samples. A piecewise-linear path would
  // turn the target's acceleration into a train of impulses at the samples, which the spring rings
  // on, differently at every frame rate; a cubic Hermite (Catmull-Rom) path through the samples is
  // C1, so the forcing stays smooth. Quaternions are interpolated as 4-vectors on one hemisphere and
  // normalized.
  const int steps = gridSteps(sample_times);
  assert(frame_times.front() <= sample_times.front() + kFrameTimeTolerance);
  const int last = static_cast<int>(frame_times.size()) - 1;
  auto translationAt = [&](int k) -> Eigen::Vector4d {
    const Eigen::Vector3d& t = known[k].rigid.translation;
    return {t.x(), t.y(), t.z(), 0.0};
  };
  auto pivotAt = [&](int k) -> Eigen::Vector4d { return known[k].rigid.rotation.coeffs(); };
  auto rootAt = [&](int k) -> Eigen::Vector4d { return known[k].rigid.root.coeffs(); };
  auto hermite = [&](const std::function<Eigen::Vector4d(int)>& value, int k, double s, bool hemisphere) -> Eigen::Vector4d {
    const Eigen::Vector4d reference = value(k);
    auto aligned = [&](int index) -> Eigen::Vector4d {
      const Eigen::Vector4d v = value(std::min(std::max(index, 0), last));
      return hemisphere && v.dot(reference) < 0.0 ? Eigen::Vector4d(-v) : v;
    };
    auto tangent = [&](int index) -> Eigen::Vector4d {
      const int before = std::max(index - 1, 0), after = std::min(index + 1, last);
      return (aligned(after) - aligned(before)) / (frame_times[after] - frame_times[before]);
    };
    const double span = frame_times[k + 1] - frame_times[k];
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * aligned(k) + (s3 - 2 * s2 + s) * span * tangent(k) + (-2 * s3 + 3 * s2) * aligned(k + 1) +
           (s3 - s2) * span * tangent(k + 1);
  };
  auto same = [](const RigidFrame& a, const RigidFrame& b) {
    return a.translation == b.translation && a.rotation.coeffs() == b.rotation.coeffs() && a.root.coeffs() == b.root.coeffs();
  };
  std::vector<RigidFrame> grid;
  int k = 0;
  for (int n = 0; n <= steps; ++n) {
    const double time = sample_times.front() + n * kJiggleTimestep;
    while (k < last && frame_times[k + 1] <= time + kFrameTimeTolerance) ++k;
    // Past the last sample, and across repeated sample times, the pose is held.
    if (k >= last || std::abs(frame_times[k] - time) <= kFrameTimeTolerance) {
      grid.push_back(known[k].rigid);
      continue;
    }
    // A held pose stays bit-exact, so a still jiggle stays exactly at rest.
    bool held = true;
    for (int m = std::max(k - 1, 0); m <= std::min(k + 2, last); ++m) held = held && same(known[m].rigid, known[k].rigid);
    if (held) {
      grid.push_back(known[k].rigid);
      continue;
    }
    const double s = std::min(1.0, std::max(0.0, (time - frame_times[k]) / (frame_times[k + 1] - frame_times[k])));
    RigidFrame blended;
    blended.translation = hermite(translationAt, k, s, false).head<3>();
    blended.rotation = Eigen::Quaterniond(hermite(pivotAt, k, s, true)).normalized();
    blended.root = Eigen::Quaterniond(hermite(rootAt, k, s, true)).normalized();
    grid.push_back(blended);
  }
  return simulate(setup, sample_times, grid, outputs, hits, clip_name);
}

}  // namespace legacy

namespace {

bool verboseRun() { return std::getenv("RIGBAKE_TEST_VERBOSE") != nullptr; }

const Clip& clipOfBake(const Character& character, const std::string& name) {
  for (const Clip& clip : character.clips) {
    if (clip.name == name) return clip;
  }
  FAIL("no clip " << name);
  return character.clips.front();
}

constexpr double kRadian = 3.14159265358979323846 / 180.0;

// Largest difference between two tracks of one jiggle: the baked channels (TRS), the jiggle and
// target points (scene units), the jiggle's angle (radians), and its cone half-angle there (radians,
// times the sine of the angle: the half-angle belongs to the jiggle's azimuth about the aim axis, which
// a rounding-level move of a point near the axis turns by rounding / sin(angle), so near rest it is
// ill-conditioned; measured up to 1.5e-6 degrees at an angle of 3e-5 degrees on RobotExpressive).
double trackGap(const JiggleTrack& a, const JiggleTrack& b) {
  REQUIRE(a.times.size() == b.times.size());
  REQUIRE(a.local.size() == b.local.size());
  double gap = 0.0;
  for (size_t i = 0; i < a.times.size(); ++i) {
    gap = std::max(gap, std::abs(a.times[i] - b.times[i]));
    gap = std::max(gap, (a.local[i].rotation.coeffs() - b.local[i].rotation.coeffs()).cwiseAbs().maxCoeff());
    gap = std::max(gap, (a.local[i].translation - b.local[i].translation).cwiseAbs().maxCoeff());
    gap = std::max(gap, (a.local[i].scale - b.local[i].scale).cwiseAbs().maxCoeff());
    gap = std::max(gap, (a.point[i] - b.point[i]).cwiseAbs().maxCoeff());
    gap = std::max(gap, (a.target[i] - b.target[i]).cwiseAbs().maxCoeff());
    gap = std::max(gap, kRadian * std::abs(a.angle_deg[i] - b.angle_deg[i]));
    gap = std::max(gap, kRadian * std::abs(a.clamp_deg[i] - b.clamp_deg[i]) * std::sin(kRadian * a.angle_deg[i]));
  }
  return gap;
}

struct BakeGap {
  double worst = 0.0;
  int tracks = 0;
  int samples = 0;
  double max_angle = 0.0;
};

// Bakes `path` with `preset`'s jiggles and `hits` (the muscles of the shipped biped preset), then runs
// the frozen pre-runtime code on the same clips, sample times and muscle transforms.
BakeGap bakeAgainstLegacy(const std::string& path, const JigglePreset& preset, std::vector<HitImpulse> hits) {
  test::Resolved r = test::resolveShipped(path);
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  const Skeleton& skeleton = r.character.skeleton;
  BakeOptions options;
  options.jiggles = resolveJiggles(preset, skeleton, &r.landmarks, &muscles);
  options.hits = std::move(hits);
  options.measure_quality = false;  // volumes do not touch the jiggles
  const BakeResult result = bakeCharacter(r.character, muscles, options);
  BakeGap gap;
  for (const BakedClip& baked : result.clips) {
    const Clip& clip = clipOfBake(r.character, baked.name);
    REQUIRE(baked.jiggles.size() == options.jiggles.size());
    const std::vector<JiggleTrack> skeleton_tracks =
        legacy::simulateJiggle(skeleton, clip, baked.times, options.jiggles, options.hits);
    size_t next = 0;
    for (size_t s = 0; s < options.jiggles.size(); ++s) {
      const JiggleSetup& setup = options.jiggles[s];
      JiggleTrack old;
      if (setup.host == JiggleHost::kSkeletonJoint) {
        old = skeleton_tracks[next++];
      } else {
        // As pipeline/bake.cpp drives a muscle jiggle: the baked muscle's skinned joint at every frame time.
        const MusclePart& part = result.muscles.parts[setup.muscle];
        const std::vector<double> frame_times = jiggleFrameTimes(baked.times);
        std::vector<JiggleFrame> frames;
        for (double time : frame_times) {
          const Pose pose = sampleClip(skeleton, clip, time);
          JiggleFrame frame;
          frame.parent = pose.world[muscleCarrierJoint(part)];
          frame.root = pose.world[setup.root >= 0 ? setup.root : part.origin.joint];
          frame.pivot = evaluateMuscle(part, skeleton, pose).skinned;
          frames.push_back(frame);
        }
        old = legacy::simulateJiggleFrames(setup, baked.times, frame_times, frames, options.hits, clip.name);
      }
      INFO(path << " clip " << baked.name << " jiggle " << setup.name);
      const double track_gap = trackGap(old, baked.jiggles[s]);
      CHECK(track_gap <= 1e-12);
      gap.worst = std::max(gap.worst, track_gap);
      ++gap.tracks;
      gap.samples += static_cast<int>(baked.times.size());
      for (double angle : old.angle_deg) gap.max_angle = std::max(gap.max_angle, angle);
    }
  }
  return gap;
}

HitImpulse hitOn(const std::vector<std::string>& joints, double time, const Eigen::Vector3d& direction, double magnitude) {
  HitImpulse hit;
  hit.time = time;
  hit.direction = direction;
  hit.magnitude = magnitude;
  hit.joints = joints;
  hit.where = "test";
  return hit;
}

TEST_CASE("runtime jiggle: the bake's jiggle tracks equal the pre-runtime code's within 1e-12 (sample, CesiumMan)") {
  const std::string presets = test::presetsDir() + "/jiggle/";
  // The sample: the talk's five settings on skeleton joints and the bicep, with hits at the first step,
  // inside a clip and for one clip only.
  const JigglePreset examples = readJigglePreset(presets + "gow_examples.json");
  const std::vector<HitImpulse> sample_hits = {
      hitOn({"JOLeftHand1", "LeftBicep"}, 0.0, {0.0, 0.0, 1.0}, 1.5),
      hitOn({"JORightHand1", "JOHead1"}, 0.41, {1.0, 0.5, -0.2}, 2.0),
      hitOn({"LeftBicep"}, 0.8, {0.0, 1.0, 0.0}, 0.7),
  };
  std::vector<HitImpulse> clip_hits = sample_hits;
  clip_hits[1].clip = "ArmRaise";
  const BakeGap sample = bakeAgainstLegacy(test::sampleGlbPath(), examples, clip_hits);
  CHECK(sample.tracks == 6 * 3);
  CHECK(sample.max_angle > 1.0);

  // A real character: CesiumMan has no forearm twist joints, so those two entries go; both biceps too.
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  if (cesium.empty()) return;
  JigglePreset real = examples;
  real.jiggles.erase(real.jiggles.begin() + 2, real.jiggles.begin() + 4);
  const JigglePreset biceps = readJigglePreset(presets + "biceps.json");
  real.jiggles.push_back(biceps.jiggles[1]);
  const BakeGap cesium_gap =
      bakeAgainstLegacy(cesium, real, {hitOn({"LeftBicep", "RightBicep"}, 0.5, {0.3, 0.0, 1.0}, 1.0)});
  CHECK(cesium_gap.tracks == 5);
  CHECK(cesium_gap.max_angle > 0.5);
  if (verboseRun())
    std::printf("bake vs pre-runtime jiggle: sample %d tracks x %d samples max |diff| %.3g, CesiumMan %d tracks max |diff| %.3g\n",
                sample.tracks, sample.samples / std::max(1, sample.tracks), sample.worst, cesium_gap.tracks, cesium_gap.worst);
}

// An engine's view of a character: its skeleton's model-space matrices for a clip time, followed by
// the skinned joints the runtime muscle rig computes from them (docs/runtime.md, "Jiggle").
struct EngineCharacter {
  test::Resolved resolved;
  MuscleSet muscles;
  std::vector<JiggleSetup> setups;
  runtime::MuscleRig<double> muscle_rig;
  std::vector<int> carriers;

  std::vector<double> matricesAt(const Clip& clip, double time) const {
    const Pose pose = sampleClip(resolved.character.skeleton, clip, time);
    std::vector<double> matrices = jointMatrices(pose);
    std::vector<double> skinned(16 * muscle_rig.muscles.size());
    runtime::MuscleRigJob<double> job;
    job.rig = &muscle_rig;
    job.joint_matrices = matrices;
    job.skinned_matrices = skinned;
    REQUIRE(job.Run());
    matrices.insert(matrices.end(), skinned.begin(), skinned.end());
    return matrices;
  }
};

EngineCharacter engineCharacter(const std::string& path, const JigglePreset& preset) {
  EngineCharacter c;
  c.resolved = test::resolveShipped(path);
  c.muscles = placeMuscles(c.resolved.character, c.resolved.landmarks, test::gowPreset(), Sides::kBoth);
  c.setups = resolveJiggles(preset, c.resolved.character.skeleton, &c.resolved.landmarks, &c.muscles);
  c.muscle_rig = buildMuscleRig(c.muscles, c.resolved.character.skeleton);
  for (const MusclePart& part : c.muscles.parts) c.carriers.push_back(muscleCarrierJoint(part));
  return c;
}

const EngineCharacter& engineSample() {
  static const EngineCharacter character =
      engineCharacter(test::sampleGlbPath(), readJigglePreset(test::presetsDir() + "/jiggle/gow_examples.json"));
  return character;
}

// What the bake computes for these setups over one clip (pipeline/bake.cpp's two hosts).
std::vector<JiggleTrack> bakedTracks(const EngineCharacter& c, const Clip& clip, const std::vector<double>& times,
                                     const std::vector<HitImpulse>& hits) {
  const Skeleton& skeleton = c.resolved.character.skeleton;
  const std::vector<JiggleTrack> skeleton_tracks = simulateJiggle(skeleton, clip, times, c.setups, hits);
  std::vector<JiggleTrack> tracks;
  size_t next = 0;
  for (const JiggleSetup& setup : c.setups) {
    if (setup.host == JiggleHost::kSkeletonJoint) {
      tracks.push_back(skeleton_tracks[next++]);
      continue;
    }
    const MusclePart& part = c.muscles.parts[setup.muscle];
    const std::vector<double> frame_times = jiggleFrameTimes(times);
    std::vector<JiggleFrame> frames;
    for (double time : frame_times) {
      const Pose pose = sampleClip(skeleton, clip, time);
      JiggleFrame frame;
      frame.parent = pose.world[muscleCarrierJoint(part)];
      frame.root = pose.world[setup.root];
      frame.pivot = evaluateMuscle(part, skeleton, pose).skinned;
      frames.push_back(frame);
    }
    tracks.push_back(simulateJiggleFrames(setup, times, frame_times, frames, hits, clip.name));
  }
  return tracks;
}

// One engine frame's outputs for every jiggle.
template <typename Real>
struct EngineFrame {
  double time = 0.0;
  std::vector<Real> corrections, local_rotations, model_matrices, points, cone_angles;
};

// Drives the runtime as an engine does: a reset on the first frame (moving with the pose one step
// later, as the bake starts), then one Run per frame with the frame's delta time; a hit is applied
// before the Run whose steps include the step it acts at (the bake's rule).
template <typename Real>
std::vector<EngineFrame<Real>> runEngine(const EngineCharacter& c, const Clip& clip, const std::vector<double>& frame_times,
                                         const std::vector<HitImpulse>& hits, const std::vector<double>* one_step_later = nullptr) {
  const runtime::JiggleRig<Real> rig = buildJiggleRig<Real>(c.setups, c.resolved.character.skeleton, c.carriers);
  REQUIRE(std::string(runtime::jiggleRigProblem(rig)).empty());
  const size_t n = rig.jiggles.size();
  std::vector<runtime::JiggleState> states(n);
  auto asReal = [](const std::vector<double>& m) { return std::vector<Real>(m.begin(), m.end()); };
  const double h = kJiggleTimestep, t0 = frame_times.front();
  auto kick = [&](double from, double to) {
    for (const HitImpulse& hit : hits) {
      if (!hit.clip.empty() && hit.clip != clip.name) continue;
      const double at = t0 + std::max(0.0, std::ceil((hit.time - t0) / h - 1e-9)) * h;
      if (!(at > from + 1e-9 && at <= to + 1e-9)) continue;
      const Real direction[3] = {Real(hit.direction.x()), Real(hit.direction.y()), Real(hit.direction.z())};
      for (size_t j = 0; j < n; ++j) {
        for (const std::string& part : hit.joints) {
          const std::vector<std::string>& parts = c.setups[j].parts;
          if (std::find(parts.begin(), parts.end(), part) != parts.end()) {
            REQUIRE(runtime::applyJiggleImpulse<Real>(states, j, direction, Real(hit.magnitude)));
            break;
          }
        }
      }
    }
  };
  kick(-1e300, t0);
  const std::vector<Real> first = asReal(c.matricesAt(clip, t0));
  const std::vector<Real> next = asReal(one_step_later ? *one_step_later : c.matricesAt(clip, t0 + h));
  runtime::JiggleResetJob<Real> reset;
  reset.rig = &rig;
  reset.joint_matrices = first;
  reset.velocity_matrices = next;
  reset.velocity_time = Real(h);
  reset.states = states;
  REQUIRE(reset.Run());
  std::vector<EngineFrame<Real>> out;
  for (size_t f = 0; f < frame_times.size(); ++f) {
    EngineFrame<Real> frame;
    frame.time = frame_times[f];
    frame.corrections.resize(4 * n);
    frame.local_rotations.resize(4 * n);
    frame.model_matrices.resize(16 * n);
    frame.points.resize(3 * n);
    frame.cone_angles.resize(2 * n);
    if (f > 0) kick(frame_times[f - 1], frame_times[f]);
    const std::vector<Real> matrices = f == 0 ? first : asReal(c.matricesAt(clip, frame_times[f]));
    runtime::JiggleJob<Real> job;
    job.rig = &rig;
    job.joint_matrices = matrices;
    job.delta_time = Real(f == 0 ? 0.0 : frame_times[f] - frame_times[f - 1]);
    job.states = states;
    job.corrections = frame.corrections;
    job.local_rotations = frame.local_rotations;
    job.model_matrices = frame.model_matrices;
    job.points = frame.points;
    job.cone_angles = frame.cone_angles;
    REQUIRE(job.Run());
    out.push_back(std::move(frame));
  }
  return out;
}

std::vector<double> framesAt(double fps, double duration) {
  std::vector<double> times;
  for (int k = 0; k / fps <= duration + 1e-9; ++k) times.push_back(k / fps);
  return times;
}

template <typename Real>
Eigen::Quaterniond quaternionAt(const std::vector<Real>& values, size_t j) {
  return Eigen::Quaterniond(values[4 * j + 3], values[4 * j], values[4 * j + 1], values[4 * j + 2]);
}

// The angle of the rotation between two orientations (atan2 of the relative quaternion: acos of a
// dot product near 1 resolves only 1e-8 radians).
double angleBetweenDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const Eigen::Quaterniond d = a.normalized().conjugate() * b.normalized();
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w())) / kRadian;
}

struct EngineGap {
  double point = 0.0;         // jiggle point, fraction of the jiggle's length
  double correction_deg = 0.0;  // the jiggle rotation in the joint's frame
  double rotation_deg = 0.0;  // the jiggled local rotation
  int compared = 0;
};

// The joint's animated local rotation as the bake reads it: the clip's own TRS for a skeleton joint,
// the muscle's skinned joint relative to its carrier for a muscle.
Eigen::Quaterniond animatedLocalRotation(const EngineCharacter& c, const Clip& clip, double time, const JiggleSetup& setup) {
  const Skeleton& skeleton = c.resolved.character.skeleton;
  const Pose pose = sampleClip(skeleton, clip, time);
  if (setup.host == JiggleHost::kSkeletonJoint) return pose.local[setup.joint].rotation;
  const MusclePart& part = c.muscles.parts[setup.muscle];
  return decomposeTrs(pose.world[muscleCarrierJoint(part)].inverse() * evaluateMuscle(part, skeleton, pose).skinned).rotation;
}

// The engine's frames against the bake's samples at the times they share.
template <typename Real>
EngineGap engineAgainstBake(const EngineCharacter& c, const Clip& clip, const std::vector<EngineFrame<Real>>& frames,
                            const std::vector<JiggleTrack>& tracks) {
  EngineGap gap;
  for (const EngineFrame<Real>& frame : frames) {
    for (size_t s = 0; s < tracks.size(); ++s) {
      const JiggleTrack& track = tracks[s];
      for (size_t i = 0; i < track.times.size(); ++i) {
        if (std::abs(track.times[i] - frame.time) > 1e-9) continue;
        const Eigen::Vector3d point(frame.points[3 * s], frame.points[3 * s + 1], frame.points[3 * s + 2]);
        gap.point = std::max(gap.point, (point - track.point[i]).norm() / c.setups[s].length);
        const Eigen::Quaterniond animated = animatedLocalRotation(c, clip, frame.time, c.setups[s]);
        const Eigen::Quaterniond baked_correction = (animated.inverse() * track.local[i].rotation).normalized();
        gap.correction_deg = std::max(gap.correction_deg, angleBetweenDeg(quaternionAt(frame.corrections, s), baked_correction));
        gap.rotation_deg = std::max(gap.rotation_deg, angleBetweenDeg(quaternionAt(frame.local_rotations, s), track.local[i].rotation));
        ++gap.compared;
      }
    }
  }
  return gap;
}

const std::vector<HitImpulse>& engineHits() {
  static const std::vector<HitImpulse> hits = {hitOn({"JOLeftHand1", "LeftBicep"}, 0.0, {0.0, 0.0, 1.0}, 1.5),
                                               hitOn({"JORightHand1", "JOHead1"}, 0.41, {1.0, 0.5, -0.2}, 2.0)};
  return hits;
}

// CesiumMan with the talk's settings on what it has: hands, head and both biceps (no forearm twist joints).
JigglePreset cesiumPreset() {
  const std::string presets = test::presetsDir() + "/jiggle/";
  JigglePreset preset = readJigglePreset(presets + "gow_examples.json");
  preset.jiggles.erase(preset.jiggles.begin() + 2, preset.jiggles.begin() + 4);
  preset.jiggles.push_back(readJigglePreset(presets + "biceps.json").jiggles[1]);
  return preset;
}

struct SweepFigures {
  double exact = 0.0;         // 240 fps: jiggle point (fraction of length) and correction (degrees)
  double local_deg = 0.0;     // 240 fps: local rotation read from matrices against the clip's
  double point = 0.0;         // 30 to 144 fps: jiggle point, fraction of length
  double rotation_deg = 0.0;  // 30 to 144 fps: correction
};

SweepFigures engineSweep(const EngineCharacter& c, const std::vector<HitImpulse>& hits) {
  SweepFigures figures;
  for (const Clip& clip : c.resolved.character.clips) {
    INFO("clip " << clip.name);
    // Sampled at 30 fps from 0, the bake's sample times lie on its step grid.
    const std::vector<double> samples = framesAt(30.0, clip.duration);
    // At the step rate the engine takes exactly the bake's steps on exactly its frames, hits included.
    const std::vector<JiggleTrack> kicked = bakedTracks(c, clip, samples, hits);
    const EngineGap exact = engineAgainstBake(c, clip, runEngine<double>(c, clip, framesAt(240.0, samples.back()), hits), kicked);
    CHECK(exact.compared == static_cast<int>(samples.size() * kicked.size()));
    CHECK(exact.point < 1e-12);
    CHECK(exact.correction_deg < 1e-9);
    // The local rotation the engine reads out of parent^-1 * joint against the clip's own key.
    CHECK(exact.rotation_deg < 1e-9);
    figures.exact = std::max({figures.exact, exact.point, exact.correction_deg});
    figures.local_deg = std::max(figures.local_deg, exact.rotation_deg);
    // At lower rates the steps between two frames see the joint interpolated between them rather than
    // the clip sampled there (and at 144 fps most frames fall between steps, extrapolated). Without
    // hits: an engine's hit acts at the first step of its frame, the bake's at its exact step.
    const std::vector<JiggleTrack> free = bakedTracks(c, clip, samples, {});
    for (double fps : {30.0, 60.0, 120.0, 144.0}) {
      const EngineGap gap = engineAgainstBake(c, clip, runEngine<double>(c, clip, framesAt(fps, samples.back()), {}), free);
      CHECK(gap.compared > 0);
      figures.point = std::max(figures.point, gap.point);
      figures.rotation_deg = std::max(figures.rotation_deg, gap.correction_deg);
      if (verboseRun())
        std::printf("engine at %.0f fps vs bake, %s: jiggle point %.4f%% of length, rotation %.4f deg (%d compared)\n", fps,
                    clip.name.c_str(), 100.0 * gap.point, gap.correction_deg, gap.compared);
    }
  }
  return figures;
}

TEST_CASE("runtime jiggle: an engine stepping the job at 240 fps reproduces the bake, hits included") {
  const EngineCharacter& sample = engineSample();
  REQUIRE(sample.setups.size() == 6);
  const SweepFigures rom = engineSweep(sample, engineHits());
  const std::string cesium_path = test::requireAsset("CesiumMan.glb");
  SweepFigures walk;
  if (!cesium_path.empty()) {
    const EngineCharacter cesium = engineCharacter(cesium_path, cesiumPreset());
    walk = engineSweep(cesium, {hitOn({"LeftBicep", "Skeleton_neck_joint_2"}, 0.5, {0.3, 0.0, 1.0}, 1.0)});
  }
  // At 30 to 144 fps the figures are what an engine sees that the bake does not: the joint between
  // frames. No bound: the sample's clips are range-of-motion sweeps (and CesiumMan's walk starts with a
  // jump) that throw the talk's lightly damped settings against their cone and distance limit, where
  // the motion is as sensitive to what happens between frames as the bake's own Catmull-Rom path from
  // 30 to 120 fps frames shows (3.6 to 9.9% of the length from its exact grid, measured when this test
  // was written). The smooth-motion test below bounds the frame-rate effect where it is meaningful.
  if (verboseRun())
    std::printf("engine vs bake: at 240 fps %.3g (local rotations %.3g deg); 30-144 fps: sample ROM clips %.3f%% of the "
                "length, %.3f deg; CesiumMan walk %.3f%%, %.3f deg\n",
                std::max(rom.exact, walk.exact), std::max(rom.local_deg, walk.local_deg), 100.0 * rom.point, rom.rotation_deg,
                100.0 * walk.point, walk.rotation_deg);
}

TEST_CASE("runtime jiggle: between frames the job steps against the joint lerped (position) and nlerped (rotation)") {
  // The engine at 30 fps against the pipeline given, at every step, that interpolation of the same
  // 30 fps frames: the same steps, so the same jiggle.
  const EngineCharacter& c = engineSample();
  const Skeleton& skeleton = c.resolved.character.skeleton;
  const Clip& clip = clipOfBake(c.resolved.character, "ArmRaise");
  const std::vector<double> frames30 = framesAt(30.0, clip.duration);
  const std::vector<double> steps = framesAt(240.0, frames30.back());
  // The jiggling joints one step into the clip as the engine's interpolation has them, for the reset's
  // velocity (the pipeline starts moving with the step-1 frame it is given).
  std::vector<double> one_step_later = c.matricesAt(clip, 0.0);
  {
    const Pose a = sampleClip(skeleton, clip, 0.0), b = sampleClip(skeleton, clip, frames30[1]);
    for (const JiggleSetup& setup : c.setups) {
      if (setup.host != JiggleHost::kSkeletonJoint) continue;
      const Trs ta = decomposeTrs(a.world[setup.joint]), tb = decomposeTrs(b.world[setup.joint]);
      Eigen::Quaterniond qb = tb.rotation;
      if (ta.rotation.dot(qb) < 0.0) qb.coeffs() *= -1.0;
      const Eigen::Affine3d m = Eigen::Translation3d(0.875 * ta.translation + 0.125 * tb.translation) *
                                Eigen::Quaterniond(0.875 * ta.rotation.coeffs() + 0.125 * qb.coeffs()).normalized();
      Eigen::Map<Eigen::Matrix4d>(one_step_later.data() + 16 * setup.joint) = m.matrix();
    }
  }
  const std::vector<EngineFrame<double>> engine = runEngine<double>(c, clip, frames30, {}, &one_step_later);
  double worst = 0.0;
  for (size_t s = 0; s < c.setups.size(); ++s) {
    JiggleSetup setup = c.setups[s];
    if (setup.host != JiggleHost::kSkeletonJoint) continue;
    std::vector<Trs> at;
    std::vector<Eigen::Affine3d> roots;
    for (double time : frames30) {
      const Pose pose = sampleClip(skeleton, clip, time);
      at.push_back(decomposeTrs(pose.world[setup.joint]));
      roots.push_back(pose.world[setup.root]);
    }
    std::vector<JiggleFrame> frames;
    for (size_t n = 0; n < steps.size(); ++n) {
      const size_t k = std::min(n / 8, at.size() - 2);
      const double f = (static_cast<double>(n) - 8.0 * static_cast<double>(k)) / 8.0;
      Eigen::Quaterniond a = at[k].rotation, b = at[k + 1].rotation;
      if (a.dot(b) < 0.0) b.coeffs() *= -1.0;
      JiggleFrame frame;
      frame.pivot = Eigen::Translation3d((1.0 - f) * at[k].translation + f * at[k + 1].translation) *
                    Eigen::Quaterniond((1.0 - f) * a.coeffs() + f * b.coeffs()).normalized();
      if (f == 0.0) frame.pivot = Eigen::Translation3d(at[k].translation) * a;
      frame.root = f == 0.0 ? roots[k] : roots[k + 1];
      frames.push_back(frame);
    }
    setup.host = JiggleHost::kMuscle;  // a caller-driven jiggle
    setup.muscle = 0;
    const JiggleTrack lerped = simulateJiggleFrames(setup, frames30, steps, frames, {}, clip.name);
    for (size_t i = 0; i < frames30.size(); ++i) {
      const Eigen::Vector3d point(engine[i].points[3 * s], engine[i].points[3 * s + 1], engine[i].points[3 * s + 2]);
      worst = std::max(worst, (point - lerped.point[i]).norm() / setup.length);
    }
  }
  CHECK(worst < 1e-10);
}

// A smooth swing and sway of one joint (0.3 radians at 0.7 and 1.3 Hz, 6 cm at 0.9 Hz).
Eigen::Affine3d smoothPivot(double time) {
  const double tau = 2.0 * 3.14159265358979323846;
  return Eigen::Translation3d(0.06 * std::sin(tau * 0.9 * time), 0.1 * std::cos(tau * 0.5 * time), 0.0) *
         Eigen::AngleAxisd(0.3 * std::sin(tau * 0.7 * time), Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.15 * std::sin(tau * 1.3 * time + 0.4), Eigen::Vector3d::UnitY());
}

TEST_CASE("runtime jiggle: on a smooth motion an engine at 30 to 144 fps stays within 1% of the bake at its frames") {
  // The bake, given the motion at every step and frame time (jiggleFrameTimes), samples its output on
  // time between steps; the engine interpolates between its frames and extrapolates to its frame time.
  double worst = 0.0;
  const std::vector<std::pair<double, double>> settings = {{0.05, 0.1}, {0.15, 0.025}, {0.5, 0.05}, {1.0, 1.0}};
  for (const auto& [stiffness, damping] : settings) {
    JiggleSetup setup;
    setup.name = "probe";
    setup.host = JiggleHost::kMuscle;
    setup.muscle = 0;
    setup.length = 0.25;
    setup.params.stiffness = stiffness;
    setup.params.damping = damping;
    runtime::JiggleRig<double> rig;
    rig.joint_count = 1;
    runtime::JiggleSpec<double> spec;
    spec.joint = 0;
    spec.length = setup.length;
    spec.stiffness = stiffness;
    spec.damping = damping;
    rig.jiggles = {runtime::buildJiggleSettings(spec)};
    for (double fps : {30.0, 60.0, 120.0, 144.0}) {
      const std::vector<double> times = framesAt(fps, 3.0);
      const std::vector<double> frame_times = jiggleFrameTimes(times);
      std::vector<JiggleFrame> frames;
      for (double time : frame_times) {
        JiggleFrame frame;
        frame.pivot = smoothPivot(time);
        frames.push_back(frame);
      }
      const JiggleTrack baked = simulateJiggleFrames(setup, times, frame_times, frames, {}, "");
      std::vector<runtime::JiggleState> states(1);
      std::vector<double> point(3);
      for (size_t f = 0; f < times.size(); ++f) {
        const Eigen::Matrix4d m = smoothPivot(times[f]).matrix();
        const Eigen::Matrix4d next = smoothPivot(times[f] + kJiggleTimestep).matrix();
        if (f == 0) {
          runtime::JiggleResetJob<double> reset;
          reset.rig = &rig;
          reset.joint_matrices = {m.data(), 16};
          reset.velocity_matrices = {next.data(), 16};
          reset.velocity_time = kJiggleTimestep;
          reset.states = states;
          REQUIRE(reset.Run());
        }
        runtime::JiggleJob<double> job;
        job.rig = &rig;
        job.joint_matrices = {m.data(), 16};
        job.delta_time = f == 0 ? 0.0 : times[f] - times[f - 1];
        job.states = states;
        job.points = point;
        REQUIRE(job.Run());
        worst = std::max(worst, (Eigen::Vector3d(point[0], point[1], point[2]) - baked.point[f]).norm() / setup.length);
      }
    }
  }
  if (verboseRun()) std::printf("smooth motion, engine at 30-144 fps vs bake: %.4f%% of the jiggle length\n", 100.0 * worst);
  CHECK(worst < 0.01);
}

struct FloatGap {
  double correction_deg = 0.0;  // angle between the float and double corrections
  double local_deg = 0.0;       // between the jiggled local rotations
  double cone_deg = 0.0;        // |difference| of the cone angles
  double model = 0.0;           // largest difference of the model matrices' entries
  double max_angle = 0.0;       // how far the jiggles moved (degrees)
  int frames = 0;
};

void floatAgainstDouble(const EngineCharacter& c, double fps, const std::vector<HitImpulse>& hits, FloatGap* gap) {
  for (const Clip& clip : c.resolved.character.clips) {
    const std::vector<double> times = framesAt(fps, clip.duration);
    const std::vector<EngineFrame<double>> wide = runEngine<double>(c, clip, times, hits);
    const std::vector<EngineFrame<float>> narrow = runEngine<float>(c, clip, times, hits);
    for (size_t f = 0; f < times.size(); ++f) {
      for (size_t s = 0; s < c.setups.size(); ++s) {
        gap->correction_deg =
            std::max(gap->correction_deg, angleBetweenDeg(quaternionAt(wide[f].corrections, s), quaternionAt(narrow[f].corrections, s)));
        gap->local_deg = std::max(gap->local_deg,
                                  angleBetweenDeg(quaternionAt(wide[f].local_rotations, s), quaternionAt(narrow[f].local_rotations, s)));
        gap->cone_deg = std::max(gap->cone_deg, std::abs(wide[f].cone_angles[2 * s] - double(narrow[f].cone_angles[2 * s])));
        for (int k = 0; k < 16; ++k)
          gap->model = std::max(gap->model, std::abs(wide[f].model_matrices[16 * s + k] - double(narrow[f].model_matrices[16 * s + k])));
        gap->max_angle = std::max(gap->max_angle, wide[f].cone_angles[2 * s]);
      }
      ++gap->frames;
    }
  }
}

TEST_CASE("runtime jiggle: the float runtime agrees with the double one within 0.05 degrees over every clip") {
  // The same frames (the float job gets them rounded to float), the talk's settings, hits. The bound is
  // measured, not derived: with the state in double the gap was 0.0023 degrees on the sample and 0.023
  // on CesiumMan when this test was written. The 1e-4 degrees first aimed at is out of reach for any
  // runtime fed float matrices on these clips: the double runtime given the float-rounded matrices
  // was 0.026 degrees from the float runtime on the sample, so (triangle inequality, 0.026 - 0.0023)
  // the double runtime alone moves at least 0.024 degrees when its input is rounded to float - the
  // jiggle's sensitivity to its input near the cone and the distance limit, not float arithmetic. On
  // CesiumMan the two figures are equal (0.023), which does not tell the two causes apart.
  FloatGap sample;
  for (double fps : {30.0, 60.0, 144.0}) floatAgainstDouble(engineSample(), fps, engineHits(), &sample);
  CHECK(sample.max_angle > 45.0);
  CHECK(sample.correction_deg < 0.05);
  CHECK(sample.local_deg < 0.05);
  CHECK(sample.cone_deg < 0.05);
  FloatGap walk;
  const std::string cesium_path = test::requireAsset("CesiumMan.glb");
  if (!cesium_path.empty()) {
    const EngineCharacter cesium = engineCharacter(cesium_path, cesiumPreset());
    floatAgainstDouble(cesium, 60.0, {hitOn({"LeftBicep", "Skeleton_neck_joint_2"}, 0.5, {0.3, 0.0, 1.0}, 1.0)}, &walk);
    CHECK(walk.correction_deg < 0.05);
    CHECK(walk.local_deg < 0.05);
    CHECK(walk.cone_deg < 0.05);
  }
  if (verboseRun())
    std::printf("float vs double runtime: sample (%d frames at 30/60/144 fps, jiggles up to %.1f deg) correction %.3g deg, "
                "local rotation %.3g deg, cone angle %.3g deg, model matrix %.3g; CesiumMan (%d frames) %.3g / %.3g / %.3g deg\n",
                sample.frames, sample.max_angle, sample.correction_deg, sample.local_deg, sample.cone_deg, sample.model, walk.frames,
                walk.correction_deg, walk.local_deg, walk.cone_deg);
}

}  // namespace
}  // namespace runtime_jiggle_test
}  // namespace rigbake
