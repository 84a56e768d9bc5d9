#include "formats/rom_json.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"
#include "anatomy/point_formula.h"
#include "formats/json_reader.h"

namespace rigbake {
namespace {

const std::vector<std::string>& romDirections() {
  static const std::vector<std::string> kDirections = {"up", "down", "forward", "back", "lateral", "medial"};
  return kDirections;
}

std::string romDirection(const JsonReader& in) {
  std::string name = in.asString();
  if (std::find(romDirections().begin(), romDirections().end(), name) == romDirections().end())
    in.fail("unknown direction '" + name + "' (up, down, forward, back, lateral, medial)");
  return name;
}

// Directions on one body axis (up/down, forward/back, lateral/medial) span no rotation.
bool sameBodyAxis(const std::string& a, const std::string& b) {
  auto axisOf = [](const std::string& name) {
    if (name == "up" || name == "down") return 0;
    if (name == "forward" || name == "back") return 1;
    return 2;
  };
  return axisOf(a) == axisOf(b);
}

bool isSidedBase(const std::string& name) {
  return std::find(sidedLandmarks().begin(), sidedLandmarks().end(), name) != sidedLandmarks().end();
}

// A canonical landmark without a side suffix: a clip names "forearm" and gets both sides.
std::string romLandmark(const JsonReader& in) {
  const std::string name = in.asString();
  const bool central =
      std::find(centralLandmarks().begin(), centralLandmarks().end(), name) != centralLandmarks().end();
  if (!central && !isSidedBase(name)) {
    const std::string where = in.file() + "#" + in.pointer();
    if (isCanonicalLandmark(name))
      fail(errc::PRESET_LANDMARK_UNKNOWN, where,
           "'" + name + "': name the landmark without _l/_r; a sided clip is built for both sides, mirrored");
    fail(errc::PRESET_LANDMARK_UNKNOWN, where, "'" + name + "' is not a canonical landmark (see docs/landmarks.md)");
  }
  return name;
}

std::vector<std::string> romLandmarks(const JsonReader& in, size_t count) {
  if (in.value().is_string() || in.arraySize() != count)
    in.fail("must be an array of " + std::to_string(count) + " landmarks");
  std::vector<std::string> names;
  for (size_t i = 0; i < count; ++i) names.push_back(romLandmark(in.at(i)));
  return names;
}

double numberIn(const JsonReader& in, double low, double high) {
  const double value = in.asNumber();
  if (value < low || value > high)
    in.fail("must be in [" + nlohmann::json(low).dump() + ", " + nlohmann::json(high).dump() + "] (got " +
            nlohmann::json(value).dump() + ")");
  return value;
}

RomMotion readRomMotion(const JsonReader& in) {
  in.requireObject();
  RomMotion motion;
  motion.pointer = in.pointer();
  if (in.has("hinge")) {
    in.allowKeys({"hinge", "towards", "measured"});
    motion.kind = RomMotionKind::kHinge;
    motion.landmarks = romLandmarks(in.at("hinge"), 3);
    const JsonReader towards = in.at("towards");
    motion.towards = towards.asStringList();
    if (motion.towards.empty()) towards.fail("must name at least one direction");
    for (size_t i = 0; i < motion.towards.size(); ++i)
      romDirection(towards.value().is_string() ? towards : towards.at(i));
  } else if (in.has("twist")) {
    in.allowKeys({"twist"});
    motion.kind = RomMotionKind::kTwist;
    motion.landmarks = romLandmarks(in.at("twist"), 2);
  } else if (in.has("from")) {
    in.allowKeys({"from", "towards", "segment", "measured"});
    motion.kind = RomMotionKind::kBodyAxis;
    motion.from = romDirection(in.at("from"));
    motion.towards = {romDirection(in.at("towards"))};
    if (sameBodyAxis(motion.from, motion.towards.front()))
      in.at("towards").fail("'" + motion.towards.front() + "' lies on the same body axis as '" + motion.from +
                            "': the two must span the plane the motion turns in");
    if (in.has("segment")) motion.landmarks = romLandmarks(in.at("segment"), 2);
  } else {
    in.fail("a motion needs one of: from (+ towards, about a body axis), hinge, twist");
  }
  if (in.has("measured")) {
    const JsonReader measured = in.at("measured");
    if (!measured.value().is_boolean()) measured.fail("must be true or false");
    motion.measured = measured.value().get<bool>();
    if (motion.measured && motion.kind == RomMotionKind::kBodyAxis && motion.landmarks.empty())
      measured.fail("a measured angle needs a segment [A, B] to measure");
  }
  return motion;
}

// Every landmark a clip names for its motion and joints, to decide whether it is sided.
void collectLandmarks(const RomMotion& motion, std::vector<std::string>* names) {
  names->insert(names->end(), motion.landmarks.begin(), motion.landmarks.end());
}

}  // namespace

RomPreset parseRomPreset(const nlohmann::json& json, const std::string& file) {
  JsonReader in(json, file, "", errc::PRESET_INVALID);
  in.allowKeys({"$schema", "name", "description", "animation_prefix", "keys_per_second", "clips"});
  RomPreset preset;
  preset.file = file;
  preset.name = in.has("name") ? in.at("name").asString() : fileStem(file);
  if (in.has("description")) in.at("description").asString();
  if (in.has("animation_prefix")) preset.animation_prefix = in.at("animation_prefix").asString();
  if (in.has("keys_per_second")) preset.keys_per_second = numberIn(in.at("keys_per_second"), 1.0, 1000.0);
  const JsonReader clips = in.at("clips");
  if (clips.arraySize() == 0) clips.fail("must list at least one clip");
  std::set<std::string> names;
  for (size_t i = 0; i < clips.arraySize(); ++i) {
    const JsonReader item = clips.at(i);
    item.allowKeys({"name", "why", "duration_s", "curve", "from_deg", "to_deg", "frame", "motion", "joints", "hold",
                    "rhythm", "still"});
    RomClipSpec spec;
    spec.pointer = item.pointer();
    spec.name = item.at("name").asString();
    if (spec.name.empty() || spec.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos)
      item.at("name").fail("must be lowercase letters, digits and '_' (it is the name a clip is chosen by)");
    if (!names.insert(spec.name).second) item.at("name").fail("duplicate clip name '" + spec.name + "'");
    if (item.has("why")) item.at("why").asString();
    if (item.has("duration_s")) spec.duration_s = numberIn(item.at("duration_s"), 0.01, 3600.0);
    if (item.has("curve")) {
      const std::string curve = item.at("curve").asString();
      if (curve == "rise_and_fall") spec.curve = RomCurve::kRiseAndFall;
      else if (curve == "swing") spec.curve = RomCurve::kSwing;
      else item.at("curve").fail("must be 'rise_and_fall' or 'swing'");
    }
    spec.from_deg = numberIn(item.at("from_deg"), -360.0, 360.0);
    spec.to_deg = numberIn(item.at("to_deg"), -360.0, 360.0);
    if (spec.curve == RomCurve::kSwing && !(spec.from_deg <= 0.0 && spec.to_deg >= 0.0))
      item.at("from_deg").fail("a swing goes from 0 to to_deg and to from_deg: needs from_deg <= 0 <= to_deg");
    if (item.has("frame")) spec.frame = romLandmark(item.at("frame"));
    spec.motion = readRomMotion(item.at("motion"));
    if (spec.motion.kind == RomMotionKind::kTwist && spec.motion.measured)
      item.at("motion").fail("a twist has no rest angle to measure");
    std::vector<std::string> named = spec.motion.landmarks;
    const JsonReader joints = item.at("joints");
    if (joints.arraySize() == 0) joints.fail("must list at least one joint");
    for (size_t k = 0; k < joints.arraySize(); ++k) {
      const JsonReader joint = joints.at(k);
      joint.allowKeys({"landmark", "share"});
      RomJointShare share;
      share.landmark = romLandmark(joint.at("landmark"));
      if (joint.has("share")) {
        share.share = joint.at("share").asNumber();
        if (!(share.share > 0.0 && share.share <= 1.0)) joint.at("share").fail("must be in (0, 1]");
      }
      named.push_back(share.landmark);
      spec.joints.push_back(share);
    }
    if (item.has("hold")) {
      const JsonReader hold = item.at("hold");
      hold.allowKeys({"motion", "deg"});
      RomHold held;
      held.motion = readRomMotion(hold.at("motion"));
      if (held.motion.kind != RomMotionKind::kBodyAxis)
        hold.at("motion").fail("a hold turns about a body axis (from, towards)");
      held.deg = numberIn(hold.at("deg"), -360.0, 360.0);
      collectLandmarks(held.motion, &named);
      spec.hold = held;
    }
    if (item.has("rhythm")) {
      const JsonReader rhythm = item.at("rhythm");
      rhythm.allowKeys({"landmark", "from", "towards", "max_deg", "start_deg", "end_deg", "why"});
      RomFollower follower;
      follower.landmark = romLandmark(rhythm.at("landmark"));
      follower.motion.kind = RomMotionKind::kBodyAxis;
      follower.motion.pointer = rhythm.pointer();
      follower.motion.from = romDirection(rhythm.at("from"));
      follower.motion.towards = {romDirection(rhythm.at("towards"))};
      if (sameBodyAxis(follower.motion.from, follower.motion.towards.front()))
        rhythm.at("towards").fail("lies on the same body axis as 'from'");
      follower.max_deg = numberIn(rhythm.at("max_deg"), -180.0, 180.0);
      follower.start_deg = numberIn(rhythm.at("start_deg"), -360.0, 360.0);
      follower.end_deg = numberIn(rhythm.at("end_deg"), -360.0, 360.0);
      if (!(follower.end_deg > follower.start_deg)) rhythm.at("end_deg").fail("must be greater than start_deg");
      if (rhythm.has("why")) rhythm.at("why").asString();
      named.push_back(follower.landmark);
      spec.follower = follower;
    }
    if (item.has("still")) {
      const JsonReader still = item.at("still");
      spec.still = still.asStringList();
      for (size_t k = 0; k < spec.still.size(); ++k) romLandmark(still.value().is_string() ? still : still.at(k));
    }
    size_t sided = 0;
    for (const std::string& name : named) sided += isSidedBase(name);
    if (sided != 0 && sided != named.size())
      item.fail(
          "mixes central and sided landmarks in its motion and joints; a clip is either one sweep of the "
          "trunk or one per side");
    spec.sided = sided != 0;
    if (!spec.sided && isSidedBase(spec.frame))
      item.at("frame").fail("a central clip's body frame must be a central landmark (one joint carries it)");
    preset.clips.push_back(std::move(spec));
  }
  return preset;
}

RomPreset readRomPreset(const std::string& path) { return parseRomPreset(readJsonFile(path), path); }

namespace {
// Six decimals: the axes are for reading, and the file's floats hold about seven digits anyway.
double romRounded(double value) { return std::round(value * 1e6) / 1e6 + 0.0; }
}  // namespace

nlohmann::json romJson(const RomResult& rom, const Skeleton& skeleton) {
  nlohmann::json clips = nlohmann::json::array();
  for (const RomClip& clip : rom.clips) {
    nlohmann::json sides = nlohmann::json::array();
    for (const RomSweep& sweep : clip.sweeps) {
      nlohmann::json joints = nlohmann::json::array();
      for (const RomKeyedJoint& keyed : sweep.joints) {
        nlohmann::json joint = {{"joint", skeleton.names[keyed.joint]}, {"landmark", keyed.landmark}};
        if (keyed.follower) joint["follows"] = true;
        else joint["share"] = keyed.share;
        joints.push_back(joint);
      }
      sides.push_back({{"side", sweep.side.empty() ? "central" : sweep.side},
                       {"axis", {romRounded(sweep.axis.x()), romRounded(sweep.axis.y()), romRounded(sweep.axis.z())}},
                       {"rest_deg", romRounded(sweep.zero_deg)},
                       {"joints", joints}});
    }
    const RomClipSpec& spec = *clip.spec;
    clips.push_back({{"name", clip.name},
                     {"animation", clip.clip.name},
                     {"duration_s", clip.clip.duration},
                     {"keys", clip.angle_deg.size()},
                     {"curve", spec.curve == RomCurve::kRiseAndFall ? "rise_and_fall" : "swing"},
                     {"from_deg", spec.from_deg},
                     {"to_deg", spec.to_deg},
                     {"peak_s", clip.peak_time},
                     {"sides", sides}});
  }
  nlohmann::json skipped = nlohmann::json::array();
  for (const RomSkipped& s : rom.skipped) skipped.push_back({{"name", s.name}, {"reason", s.reason}});
  return {{"clips", clips}, {"skipped", skipped}};
}

}  // namespace rigbake
