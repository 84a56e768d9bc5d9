// Jiggle dynamics (pipeline/jiggle.h): frame-rate independence, stability over the whole parameter
// range, the elliptical cone limit, rest, hits, determinism, and the VRM spring bone export.
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/error.h"
#include "anatomy/placement.h"
#include "anatomy_fixture.h"
#include "external_tools.h"
#include "formats/gltf_write.h"
#include "formats/jiggle_json.h"
#include "formats/vrm_spring.h"
#include "pipeline/jiggle.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "math_fixture.h"

namespace rigbake {
namespace {

using test::kPi;
using test::maxDifference;

bool verbose() { return std::getenv("RIGBAKE_TEST_VERBOSE") != nullptr; }

const Character& sampleCharacter() {
  static const Character character = loadCharacter(test::sampleGlbPath()).character;
  return character;
}

const Clip& clipNamed(const Character& character, const std::string& name) {
  for (const Clip& clip : character.clips) {
    if (clip.name == name) return clip;
  }
  FAIL("no clip " << name);
  return character.clips.front();
}

JiggleParams params(double stiffness, double damping, double major = 90.0, double minor = 90.0) {
  JiggleParams p;
  p.stiffness = stiffness;
  p.damping = damping;
  p.clamp_major_deg = major;
  p.clamp_minor_deg = minor;
  return p;
}

std::vector<double> uniformTimes(double duration, double fps) {
  std::vector<double> times;
  const int count = static_cast<int>(std::round(duration * fps));
  for (int i = 0; i <= count; ++i) times.push_back(i / fps);
  return times;
}

// The talk's five example settings and the bicep.
std::vector<JiggleParams> talkSettings() {
  return {params(0.05, 0.1), params(0.15, 0.1), params(0.15, 0.025), params(0.1, 0.1), params(0.1, 0.1, 15, 15),
          params(0.5, 0.05, 90, 2.5)};
}

// Largest distance between the jiggle points of two tracks at the times they share (`a` the coarser).
double maxPointGap(const JiggleTrack& a, const JiggleTrack& b) {
  double gap = 0.0;
  int shared = 0;
  for (size_t i = 0; i < a.times.size(); ++i) {
    for (size_t k = 0; k < b.times.size(); ++k) {
      if (std::abs(a.times[i] - b.times[k]) < 1e-9) {
        gap = std::max(gap, (a.point[i] - b.point[k]).norm());
        ++shared;
      }
    }
  }
  REQUIRE(shared == static_cast<int>(a.times.size()));
  return gap;
}

double maxAngle(const JiggleTrack& track) {
  double angle = 0.0;
  for (double a : track.angle_deg) angle = std::max(angle, a);
  return angle;
}

TEST_CASE("jiggle: stiffness and damping map onto a frequency and a damping ratio") {
  const SpringConstants soft = springConstants(params(0.0, 0.0));
  const SpringConstants stiff = springConstants(params(1.0, 1.0));
  CHECK(std::sqrt(soft.k) == Approx(2.0 * kPi * kMinJiggleHz));
  CHECK(std::sqrt(stiff.k) == Approx(2.0 * kPi * kMaxJiggleHz));
  CHECK(soft.beta / (2.0 * std::sqrt(soft.k)) == Approx(kMinDampingRatio));
  CHECK(stiff.beta / (2.0 * std::sqrt(stiff.k)) == Approx(1.0));  // critical at damping 1
  double previous = 0.0;
  for (int i = 0; i <= 10; ++i) {
    const double k = springConstants(params(i / 10.0, 0.5)).k;
    CHECK(k > previous);
    previous = k;
  }
}

TEST_CASE("jiggle: the same clip at 30, 60 and 120 fps gives the same jiggle within 1% of its length") {
  const Character& character = sampleCharacter();
  const Skeleton& skeleton = character.skeleton;
  const int forearm = skeleton.find("JOLeftLowerArm1");
  const int hand = skeleton.find("JOLeftHand1");
  REQUIRE(forearm >= 0);
  REQUIRE(hand >= 0);
  double worst_joint = 0.0, least_motion = 1e9;
  for (const std::string clip_name : {"ArmRaise", "ElbowFlexion"}) {
    const Clip& clip = clipNamed(character, clip_name);
    for (const JiggleParams& p : talkSettings()) {
      const std::vector<JiggleSetup> setups = {makeJointJiggle(skeleton, forearm, p), makeJointJiggle(skeleton, hand, p)};
      std::vector<std::vector<JiggleTrack>> runs;
      for (double fps : {30.0, 60.0, 120.0}) {
        const std::vector<double> times = sampleTimes(clip, fps);
        runs.push_back(simulateJiggle(skeleton, clip, times, setups, {}));
      }
      for (size_t s = 0; s < setups.size(); ++s) {
        least_motion = std::min(least_motion, maxAngle(runs[0][s]));
        for (size_t r = 1; r < runs.size(); ++r)
          worst_joint = std::max(worst_joint, maxPointGap(runs[0][s], runs[r][s]) / setups[s].length);
      }
    }
  }
  if (verbose())
    std::printf("jiggle fps agreement, joint host: %.6f%% of jiggle length; least max angle %.3f deg\n", 100.0 * worst_joint,
                least_motion);
  CHECK(least_motion > 0.5);  // the clips do make every jiggle move
  CHECK(worst_joint < 0.01);
}

TEST_CASE("jiggle: caller-driven frames of a smooth motion at 30, 60 and 120 fps agree within 1% of the length") {
  // The caller host only knows the samples, so the motion between them must be smooth for any
  // interpolation to recover it: a swing of the pivot about two axes and a sway of its position.
  auto frameAt = [](double time) {
    JiggleFrame frame;
    const double swing = 1.2 * std::sin(2.0 * kPi * 0.7 * time);
    const double roll = 0.6 * std::sin(2.0 * kPi * 1.3 * time + 0.4);
    frame.pivot = Eigen::Translation3d(0.2 * std::sin(2.0 * kPi * 0.9 * time), 0.1 * std::cos(2.0 * kPi * 0.5 * time), 0.0) *
                  Eigen::AngleAxisd(swing, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitY());
    return frame;
  };
  JiggleSetup setup;
  setup.name = "probe";
  setup.host = JiggleHost::kMuscle;
  setup.muscle = 0;
  setup.length = 0.25;
  double worst = 0.0, worst_samples_only = 0.0, least_motion = 1e9;
  for (const JiggleParams& p : talkSettings()) {
    setup.params = p;
    std::vector<JiggleTrack> runs, samples_only;
    for (double fps : {30.0, 60.0, 120.0}) {
      const std::vector<double> times = uniformTimes(3.0, fps);
      const std::vector<double> frame_times = jiggleFrameTimes(times);
      std::vector<JiggleFrame> frames, sampled;
      for (double time : frame_times) frames.push_back(frameAt(time));
      for (double time : times) sampled.push_back(frameAt(time));
      runs.push_back(simulateJiggleFrames(setup, times, frame_times, frames, {}, ""));
      samples_only.push_back(simulateJiggleFrames(setup, times, times, sampled, {}, ""));
    }
    least_motion = std::min(least_motion, maxAngle(runs[0]));
    for (size_t r = 1; r < runs.size(); ++r) {
      worst = std::max(worst, maxPointGap(runs[0], runs[r]) / setup.length);
      worst_samples_only = std::max(worst_samples_only, maxPointGap(samples_only[0], samples_only[r]) / setup.length);
    }
  }
  if (verbose())
    std::printf("jiggle fps agreement, frames host: %.6f%% of jiggle length with frames at jiggleFrameTimes, %.3f%% with "
                "frames at the samples only (interpolated)\n",
                100.0 * worst, 100.0 * worst_samples_only);
  CHECK(least_motion > 0.5);
  CHECK(worst < 0.01);
}

TEST_CASE("jiggle: frame times hold every step and every sample time") {
  const std::vector<double> samples = {0.0, 0.01, 1.0 / 30.0, 0.055, 0.1};
  const std::vector<double> times = jiggleFrameTimes(samples);
  CHECK(std::is_sorted(times.begin(), times.end()));
  CHECK(times.size() == 25 + 2);  // 24 steps of 1/240 s to 0.1 s, plus 0.01 and 0.055 between steps
  for (double sample : samples) {
    bool found = false;
    for (double time : times) found |= std::abs(time - sample) <= 1e-9;
    CHECK(found);
  }
}

TEST_CASE("jiggle: stable for every stiffness and damping at 30 fps, and energy decays without input") {
  // A joint 0.3 m long, its pivot swung by a 1-second move and then held for 11 seconds.
  JiggleSetup setup;
  setup.name = "probe";
  setup.host = JiggleHost::kMuscle;
  setup.muscle = 0;
  setup.length = 0.3;
  const std::vector<double> coarse = uniformTimes(12.0, 30.0);
  std::vector<JiggleFrame> moving;
  for (double time : coarse) {
    JiggleFrame frame;
    const double s = std::min(time, 1.0);
    frame.pivot = Eigen::Translation3d(0.4 * std::sin(kPi * s), 0.0, 0.0) * Eigen::AngleAxisd(2.0 * s, Eigen::Vector3d::UnitZ());
    moving.push_back(frame);
  }
  // Energy needs velocities: on the 240 Hz grid, (p[n+1] - p[n]) / h is semi-implicit Euler's v[n+1].
  const std::vector<double> fine = uniformTimes(12.0, 1.0 / kJiggleTimestep);
  const std::vector<JiggleFrame> still(fine.size());
  HitImpulse kick;
  kick.time = 0.0;
  kick.direction = Eigen::Vector3d(0.3, 0.0, 1.0);
  kick.magnitude = 0.05;  // small enough to stay clear of the cone and the distance limit
  kick.joints = {"probe"};
  setup.parts = {"probe"};
  for (int si = 0; si <= 10; ++si) {
    for (int di = 0; di <= 10; ++di) {
      setup.params = params(si / 10.0, di / 10.0);
      INFO("stiffness " << setup.params.stiffness << " damping " << setup.params.damping);
      REQUIRE(jiggleSetupProblem(setup, Skeleton()).empty());
      // No blow-up under a violent move: finite, within the distance limit, settled at the end.
      const JiggleTrack driven = simulateJiggleFrames(setup, coarse, coarse, moving, {}, "");
      double early = 0.0, late = 0.0;
      for (size_t i = 0; i < coarse.size(); ++i) {
        const double offset = (driven.point[i] - driven.target[i]).norm();
        REQUIRE(std::isfinite(offset));
        REQUIRE(offset <= kMaxJiggleOffset * setup.length * (1.0 + 1e-9));
        if (coarse[i] > 1.0 && coarse[i] <= 3.0) early = std::max(early, offset);
        if (coarse[i] > 10.0) late = std::max(late, offset);
      }
      CHECK(late <= 0.5 * early + 1e-12);
      // Energy per unit mass, 1/2 |v|^2 + 1/2 k |x|^2, of a kicked jiggle: its maximum over each
      // second falls second by second.
      const SpringConstants spring = springConstants(setup.params);
      const JiggleTrack free = simulateJiggleFrames(setup, fine, fine, still, {kick}, "");
      std::vector<double> window_max(12, 0.0);
      for (size_t n = 1; n < fine.size(); ++n) {
        const Eigen::Vector3d x = free.point[n] - free.target[n];
        const Eigen::Vector3d v = (free.point[n] - free.point[n - 1]) / kJiggleTimestep;
        const double energy = 0.5 * v.squaredNorm() + 0.5 * spring.k * x.squaredNorm();
        REQUIRE(std::isfinite(energy));
        const int window = std::min(11, static_cast<int>(fine[n]));
        window_max[window] = std::max(window_max[window], energy);
      }
      CHECK(window_max[0] > 0.0);
      // Below 1e-20 of the start the energy is rounding noise in the positions.
      for (int w = 1; w < 12; ++w) CHECK((window_max[w] < window_max[w - 1] || window_max[w] < 1e-20 * window_max[0]));
      CHECK(window_max[11] < 0.5 * window_max[0]);
    }
  }
}

TEST_CASE("jiggle: the cone clamp never exceeds its angle and leaves inside points untouched") {
  JiggleSetup setup;
  setup.length = 0.2;
  setup.aim_axis = Eigen::Vector3d(1.0, 1.0, 0.0).normalized();
  setup.major_axis = Eigen::Vector3d(-1.0, 1.0, 0.0).normalized();
  const std::vector<std::pair<double, double>> cones = {{90, 2.5}, {15, 15}, {45, 10}, {0, 30}, {90, 90}, {0, 0}, {60, 89.9}, {5, 80}};
  const int directions = 20000;
  double worst_overshoot = -1e9, worst_surface = 0.0;
  int inside = 0, moved = 0;
  for (const auto& [major, minor] : cones) {
    setup.params = params(0.5, 0.5, major, minor);
    // The reported clamp is the half-angle itself on the cone's two axes.
    CHECK(coneAngle(setup, setup.aim_axis + setup.major_axis).clamp_deg == Approx(std::max(major, kMinClampDeg)));
    CHECK(coneAngle(setup, setup.aim_axis + setup.aim_axis.cross(setup.major_axis)).clamp_deg ==
          Approx(std::max(minor, kMinClampDeg)));
    for (int i = 0; i < directions; ++i) {
      // Fibonacci sphere.
      const double z = 1.0 - 2.0 * (i + 0.5) / directions;
      const double phi = i * kPi * (3.0 - std::sqrt(5.0));
      const Eigen::Vector3d direction(std::sqrt(1.0 - z * z) * std::cos(phi), std::sqrt(1.0 - z * z) * std::sin(phi), z);
      for (double radius : {0.3, 1.0, 2.5}) {
        const Eigen::Vector3d q = radius * setup.length * direction;
        const ConeAngle before = coneAngle(setup, q);
        const Eigen::Vector3d clamped = clampToCone(setup, q);
        const ConeAngle after = coneAngle(setup, clamped);
        worst_overshoot = std::max(worst_overshoot, after.angle_deg - after.clamp_deg);
        REQUIRE(after.angle_deg <= after.clamp_deg + 1e-6);
        if (before.angle_deg < before.clamp_deg - 1e-9) {
          ++inside;
          REQUIRE(clamped == q);  // bit for bit
        } else if (before.angle_deg > before.clamp_deg + 1e-9) {
          ++moved;
          // On the surface, on the segment from the rest point to q.
          worst_surface = std::max(worst_surface, std::abs(after.angle_deg - after.clamp_deg));
          const Eigen::Vector3d rest = setup.length * setup.aim_axis;
          CHECK((clamped - rest).cross(q - rest).norm() <= 1e-12 * (q - rest).norm() * setup.length + 1e-15);
        }
        // Clamping twice changes nothing.
        REQUIRE(clampToCone(setup, clamped) == clamped);
      }
    }
  }
  if (verbose())
    std::printf("cone sweep: %d inside, %d clamped, max overshoot %.3g deg, max |angle - clamp| after clamp %.3g deg\n", inside,
                moved, worst_overshoot, worst_surface);
  CHECK(inside > 1000);
  CHECK(moved > 1000);
  CHECK(worst_surface < 1e-6);
}

TEST_CASE("jiggle: the aim transformation points the aim axis at the jiggle point") {
  JiggleSetup setup;
  setup.length = 0.5;
  const Eigen::Vector3d up = Eigen::Vector3d(0.1, 1.0, 0.2).normalized();
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d q = setup.length * setup.aim_axis +
                              0.4 * Eigen::Vector3d(std::sin(i * 1.3), std::cos(i * 0.7), std::sin(i * 2.9 + 1.0));
    const Eigen::Quaterniond rotation = aimRotation(setup, q, up);
    CHECK((rotation * setup.aim_axis - q.normalized()).norm() < 1e-12);
    CHECK(std::abs(rotation.norm() - 1.0) < 1e-12);
  }
  CHECK(aimRotation(setup, setup.length * setup.aim_axis, up).coeffs() == Eigen::Quaterniond::Identity().coeffs());
}

TEST_CASE("jiggle: with no motion the jiggle stays exactly at rest") {
  const Skeleton& skeleton = sampleCharacter().skeleton;
  Clip still;
  still.name = "still";
  still.duration = 2.0;
  std::vector<JiggleSetup> setups;
  for (const char* name : {"JOLeftLowerArm1", "JOLeftHand1", "JOHead1", "JOPelvis1"})
    setups.push_back(makeJointJiggle(skeleton, skeleton.find(name), params(0.3, 0.0)));
  const std::vector<double> times = uniformTimes(2.0, 30.0);
  const std::vector<JiggleTrack> tracks = simulateJiggle(skeleton, still, times, setups, {});
  REQUIRE(tracks.size() == setups.size());
  for (size_t s = 0; s < tracks.size(); ++s) {
    const Trs& rest = skeleton.rest_local[setups[s].joint];
    for (size_t i = 0; i < times.size(); ++i) {
      CHECK(tracks[s].point[i] == tracks[s].target[i]);
      CHECK(tracks[s].angle_deg[i] == 0.0);
      CHECK(tracks[s].local[i].rotation.coeffs() == rest.rotation.coeffs());
      CHECK(tracks[s].local[i].translation == rest.translation);
    }
  }
  // The caller-driven host too.
  JiggleSetup probe = setups[0];
  probe.host = JiggleHost::kMuscle;
  probe.muscle = 0;
  JiggleFrame frame;
  frame.parent = Eigen::Translation3d(0.1, 0.2, 0.3) * Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized());
  frame.pivot = frame.parent * Eigen::Translation3d(0.0, 0.3, 0.0) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX());
  frame.root = frame.parent;
  const JiggleTrack track = simulateJiggleFrames(probe, times, times, std::vector<JiggleFrame>(times.size(), frame), {}, "");
  for (size_t i = 0; i < times.size(); ++i) {
    CHECK(track.point[i] == track.target[i]);
    CHECK(track.angle_deg[i] == 0.0);
  }
}

TEST_CASE("jiggle: a hit makes the part that was hit move, then the motion decays") {
  const Skeleton& skeleton = sampleCharacter().skeleton;
  Clip still;
  still.name = "still";
  const int forearm = skeleton.find("JOLeftLowerArm1");
  const std::vector<JiggleSetup> setups = {makeJointJiggle(skeleton, forearm, params(0.15, 0.1)),
                                           makeJointJiggle(skeleton, skeleton.find("JORightLowerArm1"), params(0.15, 0.1))};
  HitImpulse hit;
  hit.time = 0.5;
  hit.direction = Eigen::Vector3d(0.0, 0.0, 1.0);
  hit.magnitude = 1.0;
  hit.joints = {"JOLeftLowerArm1"};
  const std::vector<double> times = uniformTimes(6.0, 30.0);
  const std::vector<JiggleTrack> tracks = simulateJiggle(skeleton, still, times, setups, {hit});
  double peak = 0.0, late = 0.0;
  for (size_t i = 0; i < times.size(); ++i) {
    if (times[i] < 0.5 - 1e-9) CHECK(tracks[0].angle_deg[i] == 0.0);
    if (times[i] > 0.5 && times[i] < 2.0) peak = std::max(peak, tracks[0].angle_deg[i]);
    if (times[i] > 5.0) late = std::max(late, tracks[0].angle_deg[i]);
    CHECK(tracks[1].angle_deg[i] == 0.0);  // the other arm was not hit
    CHECK(tracks[0].angle_deg[i] <= tracks[0].clamp_deg[i] + 1e-6);
  }
  CHECK(peak > 2.0);
  CHECK(late < 0.2 * peak);
  // Initially the jiggle point moves along the hit direction.
  const size_t after = 16;  // t = 0.533 s
  CHECK((tracks[0].point[after] - tracks[0].target[after]).normalized().dot(hit.direction) > 0.9);
  // A hit for another clip does nothing here.
  hit.clip = "ArmRaise";
  for (const JiggleTrack& track : simulateJiggle(skeleton, still, times, setups, {hit})) CHECK(maxAngle(track) == 0.0);
}

TEST_CASE("jiggle: results are deterministic") {
  const Character& character = sampleCharacter();
  const Skeleton& skeleton = character.skeleton;
  const Clip& clip = clipNamed(character, "ArmRaise");
  const std::vector<JiggleSetup> setups = {makeJointJiggle(skeleton, skeleton.find("JOLeftHand1"), params(0.15, 0.025))};
  HitImpulse hit;
  hit.time = 0.3;
  hit.magnitude = 0.7;
  hit.joints = {"JOLeftHand1"};
  const std::vector<double> times = sampleTimes(clip, 30.0);
  const std::vector<JiggleTrack> a = simulateJiggle(skeleton, clip, times, setups, {hit});
  const std::vector<JiggleTrack> b = simulateJiggle(skeleton, clip, times, setups, {hit});
  for (size_t i = 0; i < times.size(); ++i) {
    CHECK(a[0].point[i] == b[0].point[i]);
    CHECK(a[0].local[i].rotation.coeffs() == b[0].local[i].rotation.coeffs());
  }
}

TEST_CASE("jiggle: the shipped presets resolve on the sample character") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  const Skeleton& skeleton = r.character.skeleton;
  const JigglePreset examples = readJigglePreset(test::presetsDir() + "/jiggle/gow_examples.json");
  const std::vector<JiggleSetup> setups = resolveJiggles(examples, skeleton, &r.landmarks, &muscles);
  REQUIRE(setups.size() == 6);
  CHECK(setups[0].name == "JOLeftHand1");
  CHECK(setups[4].name == "JOHead1");
  CHECK(setups[4].params.clamp_major_deg == 15.0);
  CHECK(setups[5].name == "LeftBicep_muscleSkinned");
  CHECK(setups[5].host == JiggleHost::kMuscle);
  CHECK(setups[5].params.stiffness == 0.5);
  CHECK(setups[5].params.damping == 0.05);
  CHECK(setups[5].params.clamp_minor_deg == 2.5);
  for (const JiggleSetup& setup : setups) CHECK(jiggleSetupProblem(setup, skeleton).empty());
  const std::vector<JiggleSetup> biceps =
      resolveJiggles(readJigglePreset(test::presetsDir() + "/jiggle/biceps.json"), skeleton, &r.landmarks, &muscles);
  REQUIRE(biceps.size() == 2);
  CHECK(biceps[1].name == "RightBicep_muscleSkinned");
  // Without muscles, or with an unknown joint, the preset does not resolve.
  try {
    resolveJiggles(examples, skeleton, &r.landmarks, nullptr);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == "JIGGLE_UNRESOLVED");
    CHECK(e.where().find("gow_examples.json#/jiggles/5") != std::string::npos);
  }
  JigglePreset unknown = examples;
  unknown.jiggles.resize(1);
  unknown.jiggles[0].landmark.clear();
  unknown.jiggles[0].joint = "Tail1";
  CHECK_THROWS_WITH(resolveJiggles(unknown, skeleton, &r.landmarks, &muscles), Catch::Contains("JIGGLE_UNRESOLVED"));
  // Hits must name a part with a jiggle.
  HitImpulse hit;
  hit.joints = {"JOLeftHand1", "LeftBicep"};
  CHECK_NOTHROW(checkHits({hit}, setups));
  hit.joints = {"JOLeftFoot1"};
  hit.where = "hits.json#/hits/0";
  CHECK_THROWS_WITH(checkHits({hit}, setups), Catch::Contains("HITS_INVALID hits.json#/hits/0"));
}

TEST_CASE("jiggle: a muscle jiggle driven by the bake's world transforms") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  const Skeleton& skeleton = r.character.skeleton;
  const std::vector<JiggleSetup> biceps =
      resolveJiggles(readJigglePreset(test::presetsDir() + "/jiggle/biceps.json"), skeleton, &r.landmarks, &muscles);
  const JiggleSetup& left = biceps[0];
  const MusclePart& part = muscles.parts[left.muscle];
  // The skinned joint rides its carrier (the upper arm): the arm swinging up is what shakes it.
  const Clip& clip = clipNamed(r.character, "ArmRaise");
  std::vector<JiggleTrack> runs;
  for (double fps : {30.0, 120.0}) {
    const std::vector<double> times = sampleTimes(clip, fps);
    const std::vector<double> frame_times = jiggleFrameTimes(times);
    std::vector<JiggleFrame> frames;
    for (double time : frame_times) {
      const Pose pose = sampleClip(skeleton, clip, time);
      JiggleFrame frame;
      frame.parent = pose.world[muscleCarrierJoint(part)];
      frame.root = pose.world[left.root];
      frame.pivot = evaluateMuscle(part, skeleton, pose).skinned;
      frames.push_back(frame);
    }
    runs.push_back(simulateJiggleFrames(left, times, frame_times, frames, {}, clip.name));
  }
  CHECK(maxAngle(runs[0]) > 0.1);
  const double gap = maxPointGap(runs[0], runs[1]) / left.length;
  if (verbose()) std::printf("bicep jiggle, 30 vs 120 fps: %.6f%% of its length\n", 100.0 * gap);
  CHECK(gap < 0.01);
  for (size_t i = 0; i < runs[0].times.size(); ++i) CHECK(runs[0].angle_deg[i] <= runs[0].clamp_deg[i] + 1e-6);
}

void checkVrmExport(SampleVrm variant) {
  const LoadedCharacter loaded = loadCharacter(test::sampleGlbPath(variant));
  const Character& character = loaded.character;
  const int forearm = character.vrm_humanoid.at("leftLowerArm");
  const int head = character.vrm_humanoid.at("head");
  const std::vector<JiggleSetup> setups = {makeJointJiggle(character.skeleton, forearm, params(0.15, 0.1)),
                                           makeJointJiggle(character.skeleton, head, params(0.1, 0.1, 15, 15))};
  tinygltf::Model model = modelOf(*loaded.document);
  const size_t nodes_before = model.nodes.size();
  const std::vector<VrmSpring> springs = vrmSpringsForSkeleton(character.skeleton, setups);
  REQUIRE(springs.size() == 2);
  CHECK(springs[0].stiffness > 0.0);
  CHECK(springs[0].drag_force > 0.0);
  CHECK(springs[0].drag_force < 1.0);
  addVrmSpringBones(&model, springs);
  CHECK(model.nodes.size() == nodes_before + 2);  // one tail per spring
  if (variant == SampleVrm::kVrm1) {
    REQUIRE(model.extensions.count("VRMC_springBone") == 1);
    const tinygltf::Value& extension = model.extensions.at("VRMC_springBone");
    CHECK(extension.Get("specVersion").Get<std::string>() == "1.0");
    REQUIRE(extension.Get("springs").ArrayLen() == 2);
    const tinygltf::Value& joint = extension.Get("springs").Get(0).Get("joints").Get(0);
    CHECK(joint.Get("node").Get<int>() == character.skeleton.nodes[forearm]);
    CHECK(joint.Get("stiffness").GetNumberAsDouble() == Approx(springs[0].stiffness));
  } else {
    const tinygltf::Value& groups = model.extensions.at("VRM").Get("secondaryAnimation").Get("boneGroups");
    REQUIRE(groups.ArrayLen() == 2);
    CHECK(groups.Get(1).Get("bones").Get(0).Get<int>() == character.skeleton.nodes[head]);
  }
  test::external::ScratchDir dir;
  const std::string path = dir.file(variant == SampleVrm::kVrm1 ? "springs1.vrm" : "springs0.vrm");
  writeGltf(model, path);
  // The written file loads back.
  CHECK(loadCharacter(path).character.skeleton.size() == character.skeleton.size());
  if (!test::external::requireTool(test::external::validatorAvailable(), test::external::validatorHint())) return;
  const test::external::ValidationSummary summary = test::external::validateWithKhronos(path);
  INFO(summary.raw);
  CHECK(summary.errors == 0);
}

TEST_CASE("jiggle: VRM 1.0 export as VRMC_springBone passes the Khronos validator") { checkVrmExport(SampleVrm::kVrm1); }

TEST_CASE("jiggle: VRM 0.x export as secondaryAnimation boneGroups passes the Khronos validator") {
  checkVrmExport(SampleVrm::kVrm0);
}

}  // namespace
}  // namespace rigbake
