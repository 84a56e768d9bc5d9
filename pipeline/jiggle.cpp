// Jiggle dynamics (pipeline/jiggle.h): presets and hits resolved by name, the animation supplied at
// every internal step, and the runtime's jobs (runtime/jiggle.cpp, where the spring, the limits, the
// cone and the aim transformation are implemented, once) stepped through it.
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
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>

#include "core/error.h"
#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"
#include "pipeline/checks.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"

namespace rigbake {
namespace {

// Frame times this close are the same instant (t0 + n h and n/fps differ by rounding).
constexpr double kFrameTimeTolerance = 1e-9;

// The rigid part of a caller's frame (decomposeTrs, scale removed): what the Catmull-Rom path between
// caller-given frames blends, and what tells a held pose.
struct RigidFrame {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // the pivot's, scale removed
  Eigen::Quaterniond root = Eigen::Quaterniond::Identity();      // the root's, scale removed
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

// One instant as the runtime reads it: the model-space (scene world) matrices of the jiggling joint's
// parent, the joint as animated, and its root, 16 numbers each, column-major, at these indices.
constexpr int kFrameParent = 0, kFramePivot = 1, kFrameRoot = 2;
using FrameMatrices = std::array<double, 48>;

FrameMatrices frameMatrices(const Eigen::Affine3d& parent, const Eigen::Affine3d& pivot, const Eigen::Affine3d& root) {
  FrameMatrices out;
  Eigen::Map<Eigen::Matrix4d>(out.data() + 16 * kFrameParent) = parent.matrix();
  Eigen::Map<Eigen::Matrix4d>(out.data() + 16 * kFramePivot) = pivot.matrix();
  Eigen::Map<Eigen::Matrix4d>(out.data() + 16 * kFrameRoot) = root.matrix();
  return out;
}

template <typename Real>
runtime::JiggleSpec<Real> jiggleRuntimeSpec(const JiggleSetup& setup, int joint, int parent, int root) {
  runtime::JiggleSpec<Real> spec;
  spec.joint = joint;
  spec.parent = parent;
  spec.root = root;
  for (int k = 0; k < 3; ++k) {
    spec.aim_axis[k] = static_cast<Real>(setup.aim_axis[k]);
    spec.major_axis[k] = static_cast<Real>(setup.major_axis[k]);
    spec.root_up[k] = static_cast<Real>(setup.root_up[k]);
  }
  spec.length = static_cast<Real>(setup.length);
  spec.stiffness = static_cast<Real>(setup.params.stiffness);
  spec.damping = static_cast<Real>(setup.params.damping);
  spec.clamp_major_deg = static_cast<Real>(setup.params.clamp_major_deg);
  spec.clamp_minor_deg = static_cast<Real>(setup.params.clamp_minor_deg);
  return spec;
}

// The setup as the runtime's data, for one jiggle reading FrameMatrices.
runtime::JiggleSettings<double> jiggleRuntimeSettings(const JiggleSetup& setup) {
  return runtime::buildJiggleSettings(jiggleRuntimeSpec<double>(setup, kFramePivot, kFrameParent, kFrameRoot));
}

struct OutputFrame {
  FrameMatrices matrices;
  Trs local;  // the jiggling joint's animated local TRS
};

// The simulation shared by both hosts, run by the runtime: `grid[n]` is the animated frame at t0 + n h
// (n = 0..N), `outputs[i]` the one at sample_times[i]. The runtime's JiggleJob takes one step per grid
// frame (a frame delta of exactly one step lands on it, so no target is interpolated), and the output
// at a sample time between two steps blends their offsets in the joint's frame (the cone is convex
// there), put back on the animation sampled exactly at that time: the bake knows the next step, which
// an engine does not (its JiggleJob extrapolates from the last two steps instead, docs/runtime.md).
JiggleTrack simulate(const JiggleSetup& setup, const std::vector<double>& sample_times, const std::vector<FrameMatrices>& grid,
                     const std::vector<OutputFrame>& outputs, const std::vector<HitImpulse>& hits,
                     const std::string& clip_name) {
  assert(!sample_times.empty() && grid.size() >= 2 && outputs.size() == sample_times.size());
  const double h = kJiggleTimestep;
  const double t0 = sample_times.front();
  const int steps = static_cast<int>(grid.size()) - 1;
  runtime::JiggleRig<double> rig;
  rig.joint_count = 3;
  rig.jiggles = {jiggleRuntimeSettings(setup)};
  assert(runtime::jiggleRigProblem(rig)[0] == '\0');
  const runtime::JiggleSettings<double>& settings = rig.jiggles.front();
  std::vector<runtime::JiggleState> state(1);

  // Hits per step: a hit at time t acts at the first step at or after t.
  std::vector<std::vector<const HitImpulse*>> kicks(grid.size());
  for (const HitImpulse& hit : hits) {
    if (!hitReaches(hit, setup, clip_name) || hit.direction.norm() == 0.0) continue;
    const int n = std::max(0, static_cast<int>(std::ceil((hit.time - t0) / h - 1e-9)));
    if (n <= steps) kicks[n].push_back(&hit);
  }
  auto kick = [&](int n) {
    for (const HitImpulse* hit : kicks[n]) {
      const double direction[3] = {hit->direction.x(), hit->direction.y(), hit->direction.z()};
      runtime::applyJiggleImpulse<double>(state, 0, direction, hit->magnitude);
    }
  };
  auto localOffset = [&]() -> Eigen::Vector3d { return Eigen::Vector3d::Map(state[0].local_offset); };

  // Start at rest on the target, moving with it, so a clip that starts in motion does not kick; the
  // hits of step 0 act at the start.
  std::vector<Eigen::Vector3d> offsets(grid.size());
  kick(0);
  runtime::JiggleResetJob<double> reset;
  reset.rig = &rig;
  reset.joint_matrices = {grid[0].data(), grid[0].size()};
  reset.velocity_matrices = {grid[1].data(), grid[1].size()};
  reset.velocity_time = h;
  reset.states = state;
  [[maybe_unused]] const bool reset_ran = reset.Run();
  assert(reset_ran);
  offsets[0] = localOffset();
  runtime::JiggleJob<double> job;
  job.rig = &rig;
  job.delta_time = h;
  job.states = state;
  for (int n = 0; n < steps; ++n) {
    kick(n + 1);
    job.joint_matrices = {grid[n + 1].data(), grid[n + 1].size()};
    [[maybe_unused]] const bool ran = job.Run();
    assert(ran && state[0].since_step == 0.0);
    offsets[n + 1] = localOffset();
  }

  JiggleTrack track;
  track.name = setup.name;
  track.host = setup.host;
  track.joint = setup.joint;
  track.muscle = setup.muscle;
  track.times = sample_times;
  for (size_t i = 0; i < sample_times.size(); ++i) {
    const double u = (sample_times[i] - t0) / h;
    const int n = std::min(std::max(static_cast<int>(std::floor(u)), 0), steps - 1);
    const double frac = std::min(std::max(u - n, 0.0), 1.0);
    double offset[3];
    runtime::blendJiggleOffset(offsets[n].data(), offsets[n + 1].data(), frac, offset);
    const double* matrices = outputs[i].matrices.data();
    const runtime::JiggleOutput<double> out =
        runtime::evaluateJiggle(settings, offset, matrices + 16 * kFramePivot, matrices + 16 * kFrameRoot);
    Trs local = outputs[i].local;
    const Eigen::Quaterniond correction(out.correction[3], out.correction[0], out.correction[1], out.correction[2]);
    // Exactly the animation at rest.
    if (!out.at_rest) local.rotation = (local.rotation * correction).normalized();
    track.local.push_back(local);
    track.point.push_back(Eigen::Vector3d::Map(out.point));
    track.target.push_back(Eigen::Vector3d::Map(out.target));
    track.angle_deg.push_back(out.angle_deg);
    track.clamp_deg.push_back(out.clamp_deg);
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
  const runtime::JiggleSpring spring = runtime::jiggleSpring(params.stiffness, params.damping);
  return {spring.k, spring.beta};
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
  Eigen::Vector3d out;
  runtime::clampJiggleToCone(jiggleRuntimeSettings(setup), q.data(), out.data());
  return out;
}

ConeAngle coneAngle(const JiggleSetup& setup, const Eigen::Vector3d& q) {
  ConeAngle result;
  runtime::jiggleConeAngle(jiggleRuntimeSettings(setup), q.data(), &result.angle_deg, &result.clamp_deg);
  return result;
}

Eigen::Quaterniond aimRotation(const JiggleSetup& setup, const Eigen::Vector3d& q, const Eigen::Vector3d& up) {
  double rotation[4];
  runtime::jiggleAimRotation(jiggleRuntimeSettings(setup), q.data(), up.data(), rotation);
  return Eigen::Quaterniond(rotation[3], rotation[0], rotation[1], rotation[2]);
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
    auto parentWorld = [&](const Pose& pose) -> const Eigen::Affine3d& {
      return skeleton.parents[j] >= 0 ? pose.world[skeleton.parents[j]] : skeleton.root_parent_world[j];
    };
    std::vector<FrameMatrices> grid;
    grid.reserve(grid_poses.size());
    for (const Pose& pose : grid_poses) grid.push_back(frameMatrices(parentWorld(pose), pose.world[j], rootWorld(pose)));
    std::vector<OutputFrame> outputs;
    for (const Pose& pose : output_poses)
      outputs.push_back({frameMatrices(parentWorld(pose), pose.world[j], rootWorld(pose)), pose.local[j]});
    tracks.push_back(simulate(*setup, sample_times, grid, outputs, hits, clip.name));
  }
  return tracks;
}

template <typename Real>
runtime::JiggleRig<Real> buildJiggleRig(const std::vector<JiggleSetup>& setups, const Skeleton& skeleton,
                                        const std::vector<int>& carriers) {
  runtime::JiggleRig<Real> rig;
  rig.joint_count = skeleton.size() + static_cast<int>(carriers.size());
  for (const JiggleSetup& setup : setups) {
    assert(jiggleSetupProblem(setup, skeleton).empty());
    const bool on_muscle = setup.host == JiggleHost::kMuscle;
    assert(!on_muscle || setup.muscle < static_cast<int>(carriers.size()));
    const int joint = on_muscle ? skeleton.size() + setup.muscle : setup.joint;
    const int parent = on_muscle ? carriers[setup.muscle] : skeleton.parents[setup.joint];
    const runtime::JiggleSpec<Real> spec = jiggleRuntimeSpec<Real>(setup, joint, parent, setup.root);
    assert(runtime::jiggleSpecProblem(spec, rig.joint_count)[0] == '\0');
    rig.jiggles.push_back(runtime::buildJiggleSettings(spec));
  }
  return rig;
}

template runtime::JiggleRig<float> buildJiggleRig(const std::vector<JiggleSetup>&, const Skeleton&, const std::vector<int>&);
template runtime::JiggleRig<double> buildJiggleRig(const std::vector<JiggleSetup>&, const Skeleton&, const std::vector<int>&);

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
  // The given frames: the runtime reads their matrices; their rigid parts drive the path between them.
  std::vector<RigidFrame> known;
  std::vector<OutputFrame> given;
  for (const JiggleFrame& frame : frames) {
    known.push_back(rigidFrame(frame.pivot, frame.root));
    given.push_back({frameMatrices(frame.parent, frame.pivot, frame.root), decomposeTrs(frame.parent.inverse() * frame.pivot)});
  }
  // Every sample time must be among the frame times (jiggleFrameTimes() guarantees it).
  std::vector<OutputFrame> outputs;
  size_t at = 0;
  for (double time : sample_times) {
    while (at + 1 < frame_times.size() && frame_times[at] < time - kFrameTimeTolerance) ++at;
    assert(std::abs(frame_times[at] - time) <= kFrameTimeTolerance);
    outputs.push_back(given[at]);
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
    const Eigen::Vector3d& t = known[k].translation;
    return {t.x(), t.y(), t.z(), 0.0};
  };
  auto pivotAt = [&](int k) -> Eigen::Vector4d { return known[k].rotation.coeffs(); };
  auto rootAt = [&](int k) -> Eigen::Vector4d { return known[k].root.coeffs(); };
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
  std::vector<FrameMatrices> grid;
  grid.reserve(steps + 1);
  int k = 0;
  for (int n = 0; n <= steps; ++n) {
    const double time = sample_times.front() + n * kJiggleTimestep;
    while (k < last && frame_times[k + 1] <= time + kFrameTimeTolerance) ++k;
    // Past the last sample, and across repeated sample times, the pose is held.
    if (k >= last || std::abs(frame_times[k] - time) <= kFrameTimeTolerance) {
      grid.push_back(given[k].matrices);
      continue;
    }
    // A held pose stays bit-exact, so a still jiggle stays exactly at rest.
    bool held = true;
    for (int m = std::max(k - 1, 0); m <= std::min(k + 2, last); ++m) held = held && same(known[m], known[k]);
    if (held) {
      grid.push_back(given[k].matrices);
      continue;
    }
    const double s = std::min(1.0, std::max(0.0, (time - frame_times[k]) / (frame_times[k + 1] - frame_times[k])));
    // The runtime reads only the rigid parts of the pivot and the root (and never the parent) to step.
    const Eigen::Vector3d translation = hermite(translationAt, k, s, false).head<3>();
    const Eigen::Quaterniond rotation = Eigen::Quaterniond(hermite(pivotAt, k, s, true)).normalized();
    const Eigen::Quaterniond root = Eigen::Quaterniond(hermite(rootAt, k, s, true)).normalized();
    grid.push_back(frameMatrices(frames[k].parent, Eigen::Translation3d(translation) * rotation, Eigen::Affine3d(root)));
  }
  return simulate(setup, sample_times, grid, outputs, hits, clip_name);
}

std::vector<JiggleSetup> resolveJiggles(const JigglePreset& preset, const Skeleton& skeleton, const LandmarkSet* landmarks,
                                        const MuscleSet* muscles) {
  auto resolveJoint = [&](const std::string& where, const std::string& name, bool landmark) {
    if (!landmark) {
      const int joint = skeleton.find(name);
      if (joint < 0) fail(errc::JIGGLE_UNRESOLVED, where, "joint '" + name + "' is not in the skeleton");
      return joint;
    }
    if (!landmarks || !landmarks->has(name))
      fail(errc::JIGGLE_UNRESOLVED, where, "landmark '" + name + "' is not resolved on this character");
    const Landmark& found = landmarks->get(name);
    if (found.from_joint.empty())
      fail(errc::JIGGLE_UNRESOLVED, where,
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
      if (!part) fail(errc::JIGGLE_UNRESOLVED, entry.where, "muscle '" + entry.muscle + "' is not among the placed muscles");
      const std::string problem = musclePartProblem(*part, skeleton);
      if (!problem.empty()) fail(errc::JIGGLE_UNRESOLVED, entry.where, "muscle '" + entry.muscle + "': " + problem);
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
        fail(errc::JIGGLE_UNRESOLVED, entry.where,
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
    if (major.norm() < 1e-6) fail(errc::JIGGLE_UNRESOLVED, entry.where, "major_axis is parallel to the aim axis");
    setup.major_axis = major.normalized();
    for (const JiggleSetup& earlier : setups) {
      if (earlier.name == setup.name) fail(errc::JIGGLE_UNRESOLVED, entry.where, "'" + setup.name + "' already has a jiggle");
    }
    const std::string problem = jiggleSetupProblem(setup, skeleton);
    if (!problem.empty()) fail(errc::JIGGLE_UNRESOLVED, entry.where, problem);
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
        fail(errc::HITS_INVALID, hit.where, "'" + part + "' reaches no jiggle (parts with a jiggle: " + names + ")");
      }
    }
  }
}

RuntimeJiggles simulateFileJiggles(const Character& character, const FileMuscleRig& rig) {
  const Skeleton& skeleton = character.skeleton;
  RuntimeJiggles out;
  std::vector<const FileJiggle*> runnable;
  bool needs_rig = false;
  for (const FileJiggle& jiggle : rig.jiggles) {
    std::string problem = jiggleSetupProblem(jiggle.setup, skeleton);
    if (problem.empty() && jiggle.muscle >= 0 && !rig.problems.empty()) problem = "its muscle's rig is malformed";
    if (!problem.empty()) {
      out.refused.push_back({jiggle.pointer, jiggle.setup.name + ": the runtime refuses it: " + problem});
      continue;
    }
    needs_rig = needs_rig || jiggle.muscle >= 0;
    runnable.push_back(&jiggle);
  }
  if (runnable.empty()) return out;
  for (const Clip& clip : character.clips) {
    if (clip.measure_only) continue;
    ClipJiggles series;
    series.clip = clip.name;
    series.pointer = "/extensions/RIGBAKE_muscle_rig/jiggles";
    series.times = sampleTimes(clip, 0.0);
    // A clip of one key does not move: there is nothing to step.
    if (series.times.size() < 2) continue;
    // The un-jiggled pose at every internal step and sample time: skeleton joints as the clip animates
    // them, a muscle's skinned joint as the runtime's muscle rig moves it.
    const std::vector<double> frame_times = jiggleFrameTimes(series.times);
    std::vector<std::vector<JiggleFrame>> frames(runnable.size());
    for (double time : frame_times) {
      const Pose pose = sampleClip(skeleton, clip, time);
      RigEvaluation evaluation;
      if (needs_rig) evaluation = evaluateRig(rig.rig, pose, false);
      for (size_t j = 0; j < runnable.size(); ++j) {
        const FileJiggle& jiggle = *runnable[j];
        JiggleFrame frame;
        if (jiggle.parent >= 0) frame.parent = pose.world[jiggle.parent];
        if (jiggle.setup.root >= 0) frame.root = pose.world[jiggle.setup.root];
        frame.pivot = jiggle.muscle >= 0 ? matrixAt(evaluation.skinned, jiggle.muscle) : pose.world[jiggle.setup.joint];
        frames[j].push_back(frame);
      }
    }
    for (size_t j = 0; j < runnable.size(); ++j) {
      const FileJiggle& jiggle = *runnable[j];
      const JiggleTrack track = simulateJiggleFrames(jiggle.setup, series.times, frame_times, frames[j], {}, clip.name);
      series.jiggles.push_back({jiggle.setup.name, jiggle.muscle >= 0 ? "muscle" : "joint", track.angle_deg, track.clamp_deg});
    }
    out.clips.push_back(std::move(series));
  }
  return out;
}

}  // namespace rigbake
