// Range-of-motion clips (pipeline/rom.h, docs/rom.md).
//
// Sources. The ranges are the American Academy of Orthopaedic Surgeons' normal joint motion ("Joint
// Motion: Method of Measuring and Recording", AAOS 1965; the same table in Norkin & White, "Measurement
// of Joint Motion: A Guide to Goniometry", appendix A), trimmed where a game mesh meets itself first
// (docs/rom.md says which and why). The clavicle's share of arm elevation is the scapulohumeral rhythm
// (Inman, Saunders & Abbott, "Observations on the function of the shoulder joint", J Bone Joint Surg
// 1944: about 1 degree of scapular and clavicular motion for 2 of glenohumeral past the first 30).
//
// The maths. Every motion is a world rotation D(t) about a unit axis n of the body frame (or of the
// limb's own geometry for a hinge and a twist) through the joint's own origin. Joint j's glTF local
// rotation that turns its bone by D_j(t) in the world, under a parent whose world has turned by
// D_p(t), is
//     q_j(t) = P^-1 * D_p(t)^-1 * D_j(t) * P * q_j(rest)
// with P the parent's world rotation at rest (world_j = world_p * local_j, rotations composing when
// the scales are uniform: FBX2glTF's 100x armatures are). D_p is the motion of the nearest keyed
// joint above j (identity when none), since joints in between keep their rest transforms.
#include "pipeline/rom.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <set>

#include "core/error.h"
#include "anatomy/point_formula.h"
#include "pipeline/pose.h"

namespace rigbake {

namespace {

constexpr double kRomPi = 3.14159265358979323846;
constexpr double kRomDegree = kRomPi / 180.0;
// A rest elbow or knee bent more than this is a hinge in its own plane (u x d); a straighter one takes
// its plane from the body frame, where u x d is noise.
constexpr double kHingeBentDegrees = 10.0;
// A `towards` direction within about 20 degrees of the bending segment cannot say which way it bends.
constexpr double kTowardsMinSine = 0.35;
// A measured segment must stand out of its rotation axis by this fraction of its length.
constexpr double kSegmentMinOffAxis = 0.2;
// Key times this close are one key (the peak times are added to the regular keys).
constexpr double kRomTimeTolerance = 1e-9;

Eigen::Quaterniond worldRotation(const Eigen::Affine3d& transform) { return decomposeTrs(transform).rotation; }

Eigen::Quaterniond angleAxis(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kRomDegree, axis));
}

struct RomContext {
  const Character* character = nullptr;
  const LandmarkSet* landmarks = nullptr;
  Pose rest;
};

// A bone's direction in the rest pose, from landmark `from` towards landmark `to`: `to`'s bind-pose
// offset carried by the joint `from` rides on. Not the two rest positions: a rig's foot joint can be
// an IK target outside the leg chain (RobotExpressive, the Quaternius characters), resting wherever
// the last animation left it, while the shin's joint still says where the shin points.
Eigen::Vector3d restSegment(const RomContext& context, const Landmark& from, const Landmark& to) {
  const Skeleton& skeleton = context.character->skeleton;
  const Eigen::Affine3d carry = context.rest.world[from.joint] * skeleton.bind_world[from.joint].inverse();
  return carry * to.position - carry * from.position;
}

// The body frame as the part of the body `frame_joint` carries rests: the bind-pose frame turned by
// that joint's rotation from bind to rest.
BodyFrame carriedBodyFrame(const RomContext& context, int frame_joint) {
  const Skeleton& skeleton = context.character->skeleton;
  const Eigen::Quaterniond carry =
      worldRotation(context.rest.world[frame_joint]) * worldRotation(skeleton.bind_world[frame_joint]).conjugate();
  BodyFrame body = context.landmarks->body;
  body.lateral = (carry * body.lateral).normalized();
  body.up = (carry * body.up).normalized();
  body.forward = (carry * body.forward).normalized();
  return body;
}

struct SweepSide {
  std::string side;  // "l", "r" or ""
  std::string name(const std::string& base) const { return side.empty() ? base : sidedName(base, side); }
  std::string directionSide() const { return side.empty() ? "l" : side; }
};

struct MotionAxis {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  double zero_deg = 0.0;
  std::string problem;  // why this character cannot do it; empty when it can
};

// The axis of a motion and, when measured, the rest angle of its segment, with `pre` (a held pose)
// applied to the segment first.
MotionAxis motionAxis(const RomContext& context, const RomMotion& motion, const SweepSide& side, const BodyFrame& body,
                      const Eigen::Quaterniond& pre) {
  MotionAxis result;
  std::vector<const Landmark*> points;
  for (const std::string& base : motion.landmarks) {
    if (!context.landmarks->has(side.name(base))) {
      result.problem = "needs landmark " + side.name(base) + ", which this character does not have";
      return result;
    }
    points.push_back(&context.landmarks->get(side.name(base)));
  }
  const double tiny = 1e-9 * std::max(body.height, 1e-6);
  const std::string dir_side = side.directionSide();
  switch (motion.kind) {
    case RomMotionKind::kBodyAxis: {
      const Eigen::Vector3d from = body.direction(motion.from, dir_side);
      const Eigen::Vector3d towards = body.direction(motion.towards.front(), dir_side);
      result.axis = from.cross(towards).normalized();
      if (!motion.measured) return result;
      const Eigen::Vector3d segment = pre * restSegment(context, *points[0], *points[1]);
      const double length = segment.norm();
      const Eigen::Vector3d off_axis = segment - result.axis * segment.dot(result.axis);
      if (length < tiny || off_axis.norm() < kSegmentMinOffAxis * length) {
        result.problem = side.name(motion.landmarks[0]) + " -> " + side.name(motion.landmarks[1]) +
                         " lies along the rotation axis, so its angle cannot be measured";
        return result;
      }
      const Eigen::Vector3d across = result.axis.cross(from);  // `towards`, square to the axis and `from`
      result.zero_deg = std::atan2(segment.dot(across), segment.dot(from)) / kRomDegree;
      return result;
    }
    case RomMotionKind::kHinge: {
      const Eigen::Vector3d upper = pre * restSegment(context, *points[0], *points[1]);
      const Eigen::Vector3d lower = pre * restSegment(context, *points[1], *points[2]);
      if (upper.norm() < tiny || lower.norm() < tiny) {
        result.problem = "two of " + side.name(motion.landmarks[0]) + ", " + side.name(motion.landmarks[1]) + ", " +
                         side.name(motion.landmarks[2]) + " coincide";
        return result;
      }
      const Eigen::Vector3d bend = upper.normalized().cross(lower.normalized());
      if (bend.norm() >= std::sin(kHingeBentDegrees * kRomDegree)) {
        result.axis = bend.normalized();
      } else {
        bool found = false;
        for (const std::string& name : motion.towards) {
          const Eigen::Vector3d cross = lower.normalized().cross(body.direction(name, dir_side));
          if (cross.norm() < kTowardsMinSine) continue;
          result.axis = cross.normalized();
          found = true;
          break;
        }
        if (!found) {
          result.problem = side.name(motion.landmarks[1]) + " -> " + side.name(motion.landmarks[2]) +
                           " points along every `towards` direction, so the hinge has no plane";
          return result;
        }
      }
      // Seen along the axis: the flexion angle is from the upper segment's line to the lower segment.
      const Eigen::Vector3d upper_across = upper - result.axis * upper.dot(result.axis);
      result.zero_deg = std::atan2(upper_across.cross(lower).dot(result.axis), upper_across.dot(lower)) / kRomDegree;
      return result;
    }
    case RomMotionKind::kTwist: {
      const Eigen::Vector3d along = pre * restSegment(context, *points[0], *points[1]);
      if (along.norm() < tiny) {
        result.problem = side.name(motion.landmarks[0]) + " and " + side.name(motion.landmarks[1]) + " coincide";
        return result;
      }
      // Mirror images: a right-handed turn about the left forearm is a left-handed one about the right.
      result.axis = (side.side == "r" ? -1.0 : 1.0) * along.normalized();
      return result;
    }
  }
  return result;
}

std::vector<double> romKeyTimes(const RomClipSpec& spec, double keys_per_second) {
  std::vector<double> times;
  const int regular = static_cast<int>(std::floor(spec.duration_s * keys_per_second + kRomTimeTolerance));
  for (int i = 0; i <= regular; ++i) times.push_back(static_cast<double>(i) / keys_per_second);
  // The peaks and the end are keys, so a sampled clip reaches exactly the stated angles.
  for (double fraction : {0.25, 0.5, 0.75, 1.0}) {
    const double t = spec.duration_s * fraction;
    bool present = false;
    for (double existing : times) present |= std::abs(existing - t) < kRomTimeTolerance;
    if (!present) times.push_back(t);
  }
  std::sort(times.begin(), times.end());
  return times;
}

struct BuiltSweep {
  RomSweep sweep;
  Eigen::Quaterniond hold = Eigen::Quaterniond::Identity();
  std::string problem;
};

bool isAtOrAbove(const Skeleton& skeleton, int joint, int below) {
  for (int j = below; j >= 0; j = skeleton.parents[j]) {
    if (j == joint) return true;
  }
  return false;
}

BuiltSweep buildSweep(const RomContext& context, const RomClipSpec& spec, const SweepSide& side) {
  BuiltSweep built;
  built.sweep.side = side.side;
  const LandmarkSet& landmarks = *context.landmarks;
  const Skeleton& skeleton = context.character->skeleton;
  const std::string frame = side.name(spec.frame);
  if (!landmarks.has(frame)) {
    built.problem = "needs landmark " + frame + " (the clip's body frame), which this character does not have";
    return built;
  }
  const BodyFrame body = carriedBodyFrame(context, landmarks.get(frame).joint);

  if (spec.hold) {
    const MotionAxis hold = motionAxis(context, spec.hold->motion, side, body, Eigen::Quaterniond::Identity());
    if (!hold.problem.empty()) {
      built.problem = hold.problem;
      return built;
    }
    built.hold = angleAxis(spec.hold->deg - hold.zero_deg, hold.axis);
  }
  const MotionAxis motion = motionAxis(context, spec.motion, side, body, built.hold);
  if (!motion.problem.empty()) {
    built.problem = motion.problem;
    return built;
  }
  built.sweep.axis = motion.axis;
  built.sweep.zero_deg = motion.zero_deg;

  std::vector<int> still_joints;
  for (const std::string& base : spec.still) {
    std::vector<std::string> names;
    if (std::find(sidedLandmarks().begin(), sidedLandmarks().end(), base) != sidedLandmarks().end())
      names = {base + "_l", base + "_r"};
    else names = {base};
    for (const std::string& name : names) {
      if (landmarks.has(name) && !landmarks.get(name).from_joint.empty())
        still_joints.push_back(landmarks.get(name).joint);
    }
  }
  auto movable = [&](int joint) {
    for (int still : still_joints) {
      if (isAtOrAbove(skeleton, joint, still)) return false;
    }
    return true;
  };
  // Landmarks that are derived ride on some other joint and cannot be keyed; two landmarks on one
  // joint (a skeleton with fewer spine joints than landmarks) key it once, with the later share.
  std::string tried;
  for (const RomJointShare& share : spec.joints) {
    const std::string name = side.name(share.landmark);
    tried += (tried.empty() ? "" : ", ") + name;
    if (!landmarks.has(name) || landmarks.get(name).from_joint.empty()) continue;
    const int joint = landmarks.get(name).joint;
    if (!movable(joint)) continue;
    auto same = std::find_if(built.sweep.joints.begin(), built.sweep.joints.end(),
                             [&](const RomKeyedJoint& keyed) { return keyed.joint == joint; });
    if (same != built.sweep.joints.end()) {
      same->share = share.share;
      same->landmark = name;
      continue;
    }
    built.sweep.joints.push_back({joint, name, share.share, false});
  }
  if (built.sweep.joints.empty()) {
    built.problem =
        "no joint to key: " + tried + " are not joints of this character (or would move a `still` landmark)";
    return built;
  }
  if (spec.follower) {
    const std::string name = side.name(spec.follower->landmark);
    if (landmarks.has(name) && !landmarks.get(name).from_joint.empty()) {
      const int joint = landmarks.get(name).joint;
      const bool keyed = std::any_of(built.sweep.joints.begin(), built.sweep.joints.end(),
                                     [&](const RomKeyedJoint& k) { return k.joint == joint; });
      const MotionAxis follower =
          motionAxis(context, spec.follower->motion, side, body, Eigen::Quaterniond::Identity());
      if (!keyed && movable(joint) && follower.problem.empty()) {
        built.sweep.follower_axis = follower.axis;
        built.sweep.joints.insert(built.sweep.joints.begin(), RomKeyedJoint{joint, name, 0.0, true});
      }
    }
  }
  return built;
}

// The world motion of one keyed joint at one angle of the clip.
Eigen::Quaterniond keyedMotion(const RomClipSpec& spec, const BuiltSweep& built, const RomKeyedJoint& keyed,
                               double angle_deg) {
  if (keyed.follower) {
    const RomFollower& follower = *spec.follower;
    const double span = follower.end_deg - follower.start_deg;
    const double elevation = follower.max_deg * std::clamp((angle_deg - follower.start_deg) / span, 0.0, 1.0);
    return angleAxis(elevation, built.sweep.follower_axis);
  }
  return angleAxis(keyed.share * (angle_deg - built.sweep.zero_deg), built.sweep.axis) * built.hold;
}

RomClip buildClip(const RomContext& context, const RomPreset& preset, const RomClipSpec& spec,
                  const std::vector<BuiltSweep>& sweeps) {
  const Skeleton& skeleton = context.character->skeleton;
  RomClip rom;
  rom.name = spec.name;
  rom.spec = &spec;
  rom.clip.name = preset.animation_prefix + spec.name;
  rom.clip.duration = spec.duration_s;
  const std::vector<double> times = romKeyTimes(spec, preset.keys_per_second);
  for (double t : times) rom.angle_deg.push_back(romAngleAt(spec, t));
  rom.peak_time = spec.curve == RomCurve::kRiseAndFall ? spec.duration_s * 0.5 : spec.duration_s * 0.25;
  if (spec.curve == RomCurve::kSwing) rom.low_time = spec.duration_s * 0.75;

  // Every keyed joint of every side, for finding each joint's nearest keyed ancestor.
  std::map<int, std::pair<const BuiltSweep*, const RomKeyedJoint*>> keyed_by_joint;
  for (const BuiltSweep& built : sweeps) {
    rom.sweeps.push_back(built.sweep);
    for (const RomKeyedJoint& keyed : built.sweep.joints) keyed_by_joint[keyed.joint] = {&built, &keyed};
  }
  for (const BuiltSweep& built : sweeps) {
    for (const RomKeyedJoint& keyed : built.sweep.joints) {
      const int joint = keyed.joint;
      const int parent = skeleton.parents[joint];
      const Eigen::Quaterniond parent_rest =
          parent >= 0 ? worldRotation(context.rest.world[parent]) : worldRotation(skeleton.root_parent_world[joint]);
      std::pair<const BuiltSweep*, const RomKeyedJoint*> above{nullptr, nullptr};
      for (int a = parent; a >= 0 && !above.first; a = skeleton.parents[a]) {
        auto it = keyed_by_joint.find(a);
        if (it != keyed_by_joint.end()) above = it->second;
      }
      Track track;
      track.joint = joint;
      track.path = AnimatedPath::kRotation;
      track.interpolation = Interpolation::kLinear;
      track.times = times;
      Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
      for (size_t k = 0; k < times.size(); ++k) {
        const double angle = rom.angle_deg[k];
        const Eigen::Quaterniond own = keyedMotion(spec, built, keyed, angle);
        const Eigen::Quaterniond carried =
            above.first ? keyedMotion(spec, *above.first, *above.second, angle) : Eigen::Quaterniond::Identity();
        Eigen::Quaterniond local =
            (parent_rest.conjugate() * carried.conjugate() * own * parent_rest * skeleton.rest_local[joint].rotation)
                .normalized();
        // One hemisphere from key to key, so that the shortest-path slerp between keys is the motion.
        if (k > 0 && local.coeffs().dot(previous.coeffs()) < 0.0) local.coeffs() = -local.coeffs();
        previous = local;
        track.values.insert(track.values.end(), {local.x(), local.y(), local.z(), local.w()});
      }
      rom.clip.tracks.push_back(std::move(track));
    }
  }
  return rom;
}

}  // namespace

double romAngleAt(const RomClipSpec& spec, double time) {
  const double phase = 2.0 * kRomPi * time / spec.duration_s;
  if (spec.curve == RomCurve::kRiseAndFall)
    return spec.from_deg + (spec.to_deg - spec.from_deg) * (0.5 * (1.0 - std::cos(phase)));
  const double s = std::sin(phase);
  return s >= 0.0 ? spec.to_deg * s : -spec.from_deg * s;
}

RomResult buildRom(const Character& character, const LandmarkSet& landmarks, const RomPreset& preset,
                   const std::vector<std::string>& only) {
  for (const std::string& name : only) {
    const bool known = std::any_of(preset.clips.begin(), preset.clips.end(),
                                   [&](const RomClipSpec& spec) { return spec.name == name; });
    if (known) continue;
    std::string names;
    for (const RomClipSpec& spec : preset.clips) names += (names.empty() ? "" : ", ") + spec.name;
    fail(errc::ROM_CLIP_UNKNOWN, preset.file, "no clip '" + name + "' in the ROM preset (it has: " + names + ")");
  }
  RomContext context;
  context.character = &character;
  context.landmarks = &landmarks;
  context.rest = restPose(character.skeleton);
  RomResult result;
  for (const RomClipSpec& spec : preset.clips) {
    const bool requested = std::find(only.begin(), only.end(), spec.name) != only.end();
    if (!only.empty() && !requested) continue;
    std::vector<SweepSide> sides = spec.sided ? std::vector<SweepSide>{{"l"}, {"r"}} : std::vector<SweepSide>{{""}};
    std::vector<BuiltSweep> sweeps;
    std::string problem;
    for (const SweepSide& side : sides) {
      sweeps.push_back(buildSweep(context, spec, side));
      if (!sweeps.back().problem.empty() && problem.empty()) problem = sweeps.back().problem;
    }
    if (!problem.empty()) {
      if (requested) fail(errc::ROM_CLIP_UNAVAILABLE, character.source, "ROM clip '" + spec.name + "' " + problem);
      result.skipped.push_back({spec.name, problem});
      continue;
    }
    RomClip clip = buildClip(context, preset, spec, sweeps);
    for (const Clip& own : character.clips) {
      if (own.name == clip.clip.name && !own.measure_only)
        fail(errc::ROM_CLIP_EXISTS, character.source,
             "the character already has an animation named '" + own.name +
                 "' (is it a ROM output already?); use a ROM preset with another animation_prefix");
    }
    result.clips.push_back(std::move(clip));
  }
  if (result.clips.empty()) {
    std::string why;
    for (const RomSkipped& skipped : result.skipped)
      why += (why.empty() ? "" : "; ") + skipped.name + ": " + skipped.reason;
    fail(errc::ROM_CLIP_UNAVAILABLE, character.source,
         "no ROM clip can be built (" + (why.empty() ? "the preset has none" : why) + ")");
  }
  return result;
}

void appendMeasureOnlyClips(Character* character, const RomResult& rom) {
  for (const RomClip& clip : rom.clips) {
    Clip measured = clip.clip;
    measured.gltf_animation = -1;
    measured.measure_only = true;
    character->clips.push_back(std::move(measured));
  }
}

}  // namespace rigbake
