// Range-of-motion (ROM) clips: each major joint swept through its normal range, one motion per clip,
// both sides at once, the way riggers check skinning. Built from the landmarks and the body frame, so
// a clip means the same anatomical motion on every naming, facing, unit and rest pose; the ranges,
// curves, key rates and joint shares are data (presets/rom/*.json, docs/rom.md).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/landmarks.h"

namespace rigbake {

// ---- The preset (formats/rom_json.cpp reads it strictly) ----

// How a clip's angle moves over its duration T.
enum class RomCurve {
  kRiseAndFall,  // from + (to - from) * (1 - cos(2 pi t / T)) / 2: from, up to `to` at T/2, back
  kSwing,        // 0, `to` at T/4, 0 at T/2, `from` at 3T/4, 0: sin(2 pi t / T) scaled by to or -from
};

// The rotation a clip sweeps, in the body frame (BodyFrame::direction names: up, down, forward, back,
// lateral, medial; lateral and medial are per side, and mean the left for a central clip).
enum class RomMotionKind {
  kBodyAxis,  // about from x towards: the rotation that takes direction `from` towards `towards`
  kHinge,     // a hinge at the middle of `landmarks` [A, B, C]: B->C bends away from A->B's line
  kTwist,     // about the segment `landmarks` [A, B] itself (right-handed on the left, mirrored on the right)
};

struct RomMotion {
  RomMotionKind kind = RomMotionKind::kBodyAxis;
  std::string from = "down";           // kBodyAxis
  std::vector<std::string> towards;    // kBodyAxis: one; kHinge: first not along B->C wins
  std::vector<std::string> landmarks;  // kBodyAxis: optional [A, B] segment; kHinge: [A, B, C]; kTwist: [A, B]
  // Angles count from the rest pose (false), or are the segment's measured angle (true: kBodyAxis with
  // a segment, from `from` towards `towards` seen along the axis; kHinge, the angle between A->B and
  // B->C seen along the axis). Measured angles are absolute: 10 degrees of abduction is the arm 10
  // degrees out from hanging straight down, whatever the rest pose.
  bool measured = false;
  std::string pointer;  // JSON pointer, for messages
};

// A pose held for the whole clip before its motion, e.g. the arm brought down to 10 degrees of
// abduction so that shoulder flexion starts from the side of the body even on a T-pose character.
struct RomHold {
  RomMotion motion;
  double deg = 0.0;
};

// A joint that follows the motion by a share of its own: the clavicle's elevation during arm elevation
// (scapulohumeral rhythm). Elevation = max_deg * clamp((angle - start_deg) / (end_deg - start_deg)).
struct RomFollower {
  std::string landmark;
  RomMotion motion;  // kBodyAxis, rest-relative
  double max_deg = 0.0, start_deg = 0.0, end_deg = 0.0;
};

struct RomJointShare {
  std::string landmark;
  // The fraction of the motion this joint's bone has turned by in the world: 1 for the joint that
  // carries the whole motion; spine joints split it (docs/rom.md). Shares are world, not local, so
  // they mean the same whatever the hierarchy between the joints.
  double share = 1.0;
};

struct RomClipSpec {
  std::string name;  // for --clips; the animation is named preset.animation_prefix + name
  double duration_s = 2.0;
  RomCurve curve = RomCurve::kRiseAndFall;
  double from_deg = 0.0, to_deg = 0.0;
  // The landmark whose joint carries the body frame from the bind pose to the rest pose: the body
  // axes a motion turns about are those of this part of the body as the file rests (a rest pose can be
  // an animation frame: RobotExpressive rests leaning 16 degrees forward, the Cyberpunk character with
  // its hips turned 28 degrees).
  std::string frame = "chest";
  RomMotion motion;
  std::vector<RomJointShare> joints;
  std::optional<RomHold> hold;
  std::optional<RomFollower> follower;
  // Landmarks that must not move: a joint at or above any of them is not keyed (a spine motion keeps
  // the legs planted on a rig whose lumbar joint carries the legs).
  std::vector<std::string> still;
  bool sided = false;  // set by the parser: the clip's landmarks have a left and a right
  std::string pointer;
};

struct RomPreset {
  std::string file;
  std::string name;
  std::string animation_prefix = "rom_";
  double keys_per_second = 30.0;
  std::vector<RomClipSpec> clips;
};

// ---- The clips ----

// One keyed joint of one side of a clip.
struct RomKeyedJoint {
  int joint = -1;
  std::string landmark;  // sided name, e.g. forearm_l
  double share = 1.0;    // of the motion; a follower's is 0 (it has its own angle)
  bool follower = false;
};

// One side of a clip (or the only sweep of a central clip) as built on this character.
struct RomSweep {
  std::string side;                                 // "l", "r", or "" for a central clip
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // world, unit, in the rest pose
  double zero_deg = 0.0;                            // the measured rest angle (0 for rest-relative motions)
  Eigen::Vector3d follower_axis = Eigen::Vector3d::UnitX();
  std::vector<RomKeyedJoint> joints;
};

struct RomClip {
  std::string name;  // the preset clip's name
  Clip clip;         // name = animation_prefix + name; one LINEAR rotation track per keyed joint
  std::vector<RomSweep> sweeps;
  // The clip's angle at each key of clip.tracks (they all share the same times); the peak is `to_deg`
  // at peak_time, and a swing also reaches `from_deg` at low_time.
  std::vector<double> angle_deg;
  double peak_time = 0.0;
  double low_time = -1.0;             // kSwing only
  const RomClipSpec* spec = nullptr;  // into the preset given to buildRom
};

struct RomSkipped {
  std::string name;
  std::string reason;
};

struct RomResult {
  std::vector<RomClip> clips;
  std::vector<RomSkipped> skipped;  // preset clips this character cannot do (no legs, no such joint)
};

// `only`: preset clip names to build (empty: all). A named clip the character cannot do throws
// ROM_CLIP_UNAVAILABLE, an unknown name ROM_CLIP_UNKNOWN; unnamed clips it cannot do are skipped.
// Throws ROM_CLIP_EXISTS when the character already has an animation of a ROM clip's name, and
// ROM_CLIP_UNAVAILABLE when no clip at all can be built. Deterministic: the same inputs give the same
// numbers.
RomResult buildRom(const Character& character, const LandmarkSet& landmarks, const RomPreset& preset,
                   const std::vector<std::string>& only = {});

// The clips of buildRom as the bake and validate measure them: appended after the character's own,
// marked measure_only so that no writer puts them into an output file.
void appendMeasureOnlyClips(Character* character, const RomResult& rom);

// The angle of `spec` at `time` (degrees), per its curve.
double romAngleAt(const RomClipSpec& spec, double time);

}  // namespace rigbake
