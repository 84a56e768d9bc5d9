// Jiggle dynamics (pipeline/jiggle.h).
//
// Sources:
//  - Tenghao Wang, "Joint-Based Skin Deformation in God of War Ragnarök", GDC 2023: "Jiggle Dynamics"
//    (root joint, pivot joint, jiggle joint; Stiffness, Damping 0-1, ClampMajorAngle, ClampMinorAngle
//    0-90), "Damped Spring Simple Motion" (x = p - r, F = -beta v - k x; semi-implicit Euler), "Aim
//    Transformation" (u = jigglePoint - pivot, up from the root joint, w = u x up, rotation matrix from
//    the two frames), "Line - Elliptical Cone Intersection" (y^2 = x^2/tan^2 a + z^2/tan^2 b with the
//    segment x0 + t (x1 - x0): A t^2 + B t + C = 0), "Combat Reaction" (initial velocity from the hit
//    direction and magnitude, on the part that was attacked).
//  - B. Wasiak, "Physical Animation in Star Wars Jedi: Fallen Order", GDC 2020: a fixed simulation
//    time step regardless of the frame rate, and a distance limit to the animation target.
//  - M. Cook, "JiggleBone" (Unity wiki, 2011): the per-frame model this replaces (its constants act
//    once per rendered frame, so its motion changes with the frame rate).
//  - R. Juckett, "Damped Springs" (ryanjuckett.com): omega and zeta as the artist-facing parameters.
#include "pipeline/jiggle.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>

#include "anatomy/error.h"
#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"

namespace rigbake {
namespace {

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
  const SpringConstants spring = springConstants(setup.params);
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
    const Eigen::Vector3d clamped = clampToCone(setup, q);
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
    const Eigen::Vector3d q = clampToCone(setup, rest_point + offset);
    const RigidFrame& frame = outputs[i].rigid;
    const Eigen::Vector3d up = frame.rotation.conjugate() * (frame.root * setup.root_up);
    Trs local = outputs[i].local;
    local.rotation = (local.rotation * aimRotation(setup, q, up)).normalized();
    if (q == rest_point) local.rotation = outputs[i].local.rotation;  // exactly the animation at rest
    track.local.push_back(local);
    track.point.push_back(frame.translation + frame.rotation * q);
    track.target.push_back(frame.translation + frame.rotation * rest_point);
    const ConeAngle angle = coneAngle(setup, q);
    track.angle_deg.push_back(angle.angle_deg);
    track.clamp_deg.push_back(angle.clamp_deg);
  }
  return track;
}

int gridSteps(const std::vector<double>& sample_times) {
  const double span = sample_times.back() - sample_times.front();
  return std::max(1, static_cast<int>(std::ceil(span / kJiggleTimestep - 1e-9)));
}

bool unitVector(const Eigen::Vector3d& v) { return v.allFinite() && std::abs(v.norm() - 1.0) < 1e-9; }

bool inRange(double value, double low, double high) { return std::isfinite(value) && value >= low && value <= high; }

}  // namespace

SpringConstants springConstants(const JiggleParams& params) {
  const double frequency = kMinJiggleHz * std::pow(kMaxJiggleHz / kMinJiggleHz, params.stiffness);
  const double omega = 2.0 * kPi * frequency;
  const double zeta = kMinDampingRatio + (1.0 - kMinDampingRatio) * params.damping;
  return {omega * omega, 2.0 * zeta * omega};
}

std::string jiggleSetupProblem(const JiggleSetup& setup, const Skeleton& skeleton) {
  const int size = skeleton.size();
  if (setup.host == JiggleHost::kSkeletonJoint && (setup.joint < 0 || setup.joint >= size))
    return "joint " + std::to_string(setup.joint) + " is not a joint of the " + std::to_string(size) + "-joint skeleton";
  if (setup.host == JiggleHost::kMuscle && setup.muscle < 0) return "muscle index is not set";
  if (setup.root < -1 || setup.root >= size) return "root " + std::to_string(setup.root) + " is not a joint";
  if (!unitVector(setup.aim_axis)) return "aim_axis is not a unit vector";
  if (!unitVector(setup.major_axis)) return "major_axis is not a unit vector";
  if (std::abs(setup.aim_axis.dot(setup.major_axis)) > 1e-9) return "major_axis is not perpendicular to aim_axis";
  if (!unitVector(setup.root_up)) return "root_up is not a unit vector";
  if (!(std::isfinite(setup.length) && setup.length > 0.0)) return "length must be positive";
  const JiggleParams& p = setup.params;
  if (!inRange(p.stiffness, 0.0, 1.0)) return "stiffness must be in [0, 1]";
  if (!inRange(p.damping, 0.0, 1.0)) return "damping must be in [0, 1]";
  if (!inRange(p.clamp_major_deg, 0.0, 90.0)) return "clamp_major_deg must be in [0, 90]";
  if (!inRange(p.clamp_minor_deg, 0.0, 90.0)) return "clamp_minor_deg must be in [0, 90]";
  return "";
}

Eigen::Vector3d clampToCone(const JiggleSetup& setup, const Eigen::Vector3d& q) {
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

ConeAngle coneAngle(const JiggleSetup& setup, const Eigen::Vector3d& q) {
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

Eigen::Quaterniond aimRotation(const JiggleSetup& setup, const Eigen::Vector3d& q, const Eigen::Vector3d& up) {
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

JiggleSetup makeJointJiggle(const Skeleton& skeleton, int joint, const JiggleParams& params, const Eigen::Vector3d& aim_axis,
                            double length) {
  assert(joint >= 0 && joint < skeleton.size());
  const Pose rest = restPose(skeleton);
  const Eigen::Quaterniond rotation = rotationOf(rest.world[joint]);
  const Eigen::Vector3d position = rest.world[joint].translation();
  JiggleSetup setup;
  setup.name = skeleton.names[joint];
  setup.host = JiggleHost::kSkeletonJoint;
  setup.joint = joint;
  setup.root = skeleton.parents[joint];
  setup.params = params;
  setup.parts = {skeleton.names[joint]};
  if (setup.root >= 0) setup.parts.push_back(skeleton.names[setup.root]);

  // Default aim: towards the first child away from the joint; a leaf continues its bone.
  Eigen::Vector3d world_aim = Eigen::Vector3d::Zero();
  double default_length = 0.0;
  for (int child : skeleton.children(joint)) {
    const Eigen::Vector3d bone = rest.world[child].translation() - position;
    if (bone.norm() > 1e-9) {
      world_aim = bone.normalized();
      default_length = bone.norm();
      break;
    }
  }
  if (default_length == 0.0 && setup.root >= 0) {
    const Eigen::Vector3d bone = position - rest.world[setup.root].translation();
    if (bone.norm() > 1e-9) {
      world_aim = bone.normalized();
      default_length = 0.5 * bone.norm();
    }
  }
  if (aim_axis.norm() > 0.0) {
    setup.aim_axis = aim_axis.normalized();
  } else if (default_length > 0.0) {
    setup.aim_axis = (rotation.conjugate() * world_aim).normalized();
  }
  setup.length = length > 0.0 ? length : default_length;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d major = mostPerpendicular(setup.aim_axis, {x, y, z});
  setup.major_axis = (major - major.dot(setup.aim_axis) * setup.aim_axis).normalized();
  const Eigen::Quaterniond root_rotation =
      setup.root >= 0 ? rotationOf(rest.world[setup.root]) : rotationOf(skeleton.root_parent_world[joint]);
  setup.root_up = mostPerpendicular(root_rotation.conjugate() * (rotation * setup.aim_axis), {y, z, x});
  return setup;
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

std::vector<double> jiggleFrameTimes(const std::vector<double>& sample_times) {
  assert(!sample_times.empty());
  const int steps = gridSteps(sample_times);
  std::vector<double> times;
  size_t i = 0;
  for (int n = 0; n <= steps; ++n) {
    const double step = sample_times.front() + n * kJiggleTimestep;
    for (; i < sample_times.size() && sample_times[i] <= step + kFrameTimeTolerance; ++i) {
      if (std::abs(sample_times[i] - step) > kFrameTimeTolerance && (times.empty() || sample_times[i] > times.back()))
        times.push_back(sample_times[i]);
    }
    times.push_back(step);
  }
  for (; i < sample_times.size(); ++i) {
    if (sample_times[i] > times.back()) times.push_back(sample_times[i]);
  }
  return times;
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

std::vector<JiggleSetup> resolveJiggles(const JigglePreset& preset, const Skeleton& skeleton, const LandmarkSet* landmarks,
                                        const MuscleSet* muscles) {
  auto resolveJoint = [&](const std::string& where, const std::string& name, bool landmark) {
    if (!landmark) {
      const int joint = skeleton.find(name);
      if (joint < 0) fail("JIGGLE_UNRESOLVED", where, "joint '" + name + "' is not in the skeleton");
      return joint;
    }
    if (!landmarks || !landmarks->has(name))
      fail("JIGGLE_UNRESOLVED", where, "landmark '" + name + "' is not resolved on this character");
    const Landmark& found = landmarks->get(name);
    if (found.from_joint.empty())
      fail("JIGGLE_UNRESOLVED", where,
           "landmark '" + name + "' is derived (" + found.derived + "), not a joint: a jiggle needs a joint to rotate");
    return found.joint;
  };
  std::vector<JiggleSetup> setups;
  for (const JigglePresetEntry& entry : preset.jiggles) {
    JiggleSetup setup;
    if (!entry.muscle.empty()) {
      const MusclePart* part = nullptr;
      int index = -1;
      if (muscles) {
        for (size_t m = 0; m < muscles->parts.size(); ++m) {
          if (muscles->parts[m].fullName() == entry.muscle) {
            part = &muscles->parts[m];
            index = static_cast<int>(m);
          }
        }
      }
      if (!part) fail("JIGGLE_UNRESOLVED", entry.where, "muscle '" + entry.muscle + "' is not among the placed muscles");
      const std::string problem = musclePartProblem(*part, skeleton);
      if (!problem.empty()) fail("JIGGLE_UNRESOLVED", entry.where, "muscle '" + entry.muscle + "': " + problem);
      const MuscleRestFrame rest = muscleRestFrame(*part, skeleton);
      setup.name = part->fullName() + "_muscleSkinned";
      setup.host = JiggleHost::kMuscle;
      setup.muscle = index;
      setup.root = part->origin.joint;  // the up vector rides the bone the muscle starts on
      setup.aim_axis = entry.has_axis ? entry.axis.normalized() : Eigen::Vector3d::UnitX();
      setup.major_axis = entry.has_major_axis ? entry.major_axis : Eigen::Vector3d::UnitY();
      setup.length = entry.length > 0.0 ? entry.length : 0.5 * rest.length;
      setup.params = entry.params;
      const Eigen::Quaterniond root_rotation = rotationOf(skeleton.bind_world[setup.root]);
      const Eigen::Quaterniond pivot_rotation = rotationOf(muscleBindTransform(*part, skeleton));
      setup.root_up = mostPerpendicular(root_rotation.conjugate() * (pivot_rotation * setup.aim_axis),
                                        {Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()});
      setup.parts = {part->fullName(), setup.name, skeleton.names[setup.root]};
    } else {
      const bool by_landmark = !entry.landmark.empty();
      const int joint = resolveJoint(entry.where, by_landmark ? entry.landmark : entry.joint, by_landmark);
      setup = makeJointJiggle(skeleton, joint, entry.params, entry.has_axis ? entry.axis : Eigen::Vector3d::Zero(), entry.length);
      if (by_landmark) setup.parts.push_back(entry.landmark);
      if (entry.has_major_axis) setup.major_axis = entry.major_axis;
      if (setup.length <= 0.0)
        fail("JIGGLE_UNRESOLVED", entry.where,
             "joint '" + skeleton.names[joint] + "' has no child and no parent to take a direction and length from: give axis and length");
    }
    if (!entry.root.empty()) {
      const bool root_is_joint = skeleton.find(entry.root) >= 0;
      setup.root = resolveJoint(entry.where + "/root", entry.root, !root_is_joint);
      if (std::find(setup.parts.begin(), setup.parts.end(), entry.root) == setup.parts.end()) setup.parts.push_back(entry.root);
      // The up axis is chosen again against the new root's rest frame.
      const Pose rest = restPose(skeleton);
      const Eigen::Quaterniond root_rotation = rotationOf(rest.world[setup.root]);
      const Eigen::Quaterniond pivot_rotation = setup.host == JiggleHost::kMuscle
                                                    ? rotationOf(muscleBindTransform(muscles->parts[setup.muscle], skeleton))
                                                    : rotationOf(rest.world[setup.joint]);
      setup.root_up = mostPerpendicular(root_rotation.conjugate() * (pivot_rotation * setup.aim_axis),
                                        {Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()});
    }
    // A major axis given with (or against) the aim: keep only its part perpendicular to the aim.
    const Eigen::Vector3d major = setup.major_axis - setup.major_axis.dot(setup.aim_axis) * setup.aim_axis;
    if (major.norm() < 1e-6) fail("JIGGLE_UNRESOLVED", entry.where, "major_axis is parallel to the aim axis");
    setup.major_axis = major.normalized();
    for (const JiggleSetup& earlier : setups) {
      if (earlier.name == setup.name) fail("JIGGLE_UNRESOLVED", entry.where, "'" + setup.name + "' already has a jiggle");
    }
    const std::string problem = jiggleSetupProblem(setup, skeleton);
    if (!problem.empty()) fail("JIGGLE_UNRESOLVED", entry.where, problem);
    setups.push_back(std::move(setup));
  }
  return setups;
}

void checkHits(const std::vector<HitImpulse>& hits, const std::vector<JiggleSetup>& setups) {
  for (const HitImpulse& hit : hits) {
    for (const std::string& part : hit.joints) {
      bool known = false;
      for (const JiggleSetup& setup : setups)
        known |= std::find(setup.parts.begin(), setup.parts.end(), part) != setup.parts.end();
      if (!known) {
        std::string names;
        for (const JiggleSetup& setup : setups)
          for (const std::string& name : setup.parts) names += (names.empty() ? "" : ", ") + name;
        fail("HITS_INVALID", hit.where, "'" + part + "' reaches no jiggle (parts with a jiggle: " + names + ")");
      }
    }
  }
}

}  // namespace rigbake
