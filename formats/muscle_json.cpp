#include "formats/muscle_json.h"
#include "core/file_name.h"

#include <algorithm>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy/placement.h"
#include "formats/json_reader.h"
#include "formats/json_text.h"

namespace rigbake {
namespace {

nlohmann::json vectorJson(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json locatorJson(const MuscleLocator& locator, const Skeleton& skeleton) {
  return {{"joint", skeleton.names[locator.joint]}, {"local", vectorJson(locator.local)}};
}

Eigen::Vector3d readVector(const JsonReader& in) {
  if (in.arraySize() != 3) in.fail("must be [x, y, z]");
  return {in.at(0).asNumber(), in.at(1).asNumber(), in.at(2).asNumber()};
}

// Every length in a muscle file reaches the bake's geometry (joint matrices, weights, the extension): a
// locator 1e300 m away made NaN inverse bind matrices. No muscle of a body lies further than this many
// body heights from the scene's origin, or bulges further (docs/muscle-json.md).
constexpr double kMaxBodyHeights = 100.0;

// The bound for a character `body_height` tall, in metres.
double maxReach(double body_height) { return kMaxBodyHeights * std::max(body_height, 1e-3); }

// A world position within maxReach of the origin; fails naming the pointer otherwise.
void requireWithinReach(const JsonReader& in, const Eigen::Vector3d& world, double body_height) {
  if (!(world.norm() <= maxReach(body_height))) {
    std::ostringstream text;
    text << std::setprecision(6) << "puts the point " << world.norm() << " m from the origin; a muscle lies within "
         << kMaxBodyHeights << " body heights (" << maxReach(body_height) << " m)";
    in.fail(text.str());
  }
}

const ErrorCode& kMusclesCode = errc::MUSCLES_INVALID;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

nlohmann::json curveJson(const std::vector<ResponseKey>& keys, double at_unit) {
  nlohmann::json out = nlohmann::json::array();
  for (const ResponseKey& key : keys) out.push_back({{"at", key.at / at_unit}, {"bulge", {key.up, key.side}}, {"scale", key.scale}});
  return out;
}

nlohmann::json responseJson(const MuscleResponse& response) {
  nlohmann::json out = {{"ratio", curveJson(response.ratio, 1.0)}, {"twist_deg", curveJson(response.twist, kDegree)}};
  if (response.fitted) out["fitted"] = true;
  return out;
}

// Curve keys: `at` a length ratio (0 to kMaxRatio) or a twist in degrees (within kMaxTwistDeg either
// way), the bulge within maxReach, the scale positive and at most kMaxScale.
constexpr double kMaxRatio = 100.0, kMaxTwistDeg = 3600.0, kMaxScale = 100.0;

std::vector<ResponseKey> readCurve(const JsonReader& in, double at_unit, double body_height) {
  std::vector<ResponseKey> keys;
  const double reach = maxReach(body_height);
  for (size_t k = 0; k < in.arraySize(); ++k) {
    JsonReader key = in.at(k);
    key.allowKeys({"at", "bulge", "scale"});
    JsonReader bulge = key.at("bulge");
    if (bulge.arraySize() != 2) bulge.fail("must be [up, side] in metres");
    const double at = at_unit == 1.0 ? key.at("at").asNumberIn(0.0, kMaxRatio) : key.at("at").asNumberIn(-kMaxTwistDeg, kMaxTwistDeg, "degrees");
    keys.push_back({at * at_unit, bulge.at(0).asNumberIn(-reach, reach, "m"), bulge.at(1).asNumberIn(-reach, reach, "m"),
                    key.at("scale").asNumberIn(0.0, kMaxScale)});
  }
  return keys;
}

MuscleResponse readResponse(const JsonReader& in, double body_height) {
  in.allowKeys({"ratio", "twist_deg", "fitted"});
  MuscleResponse response;
  response.ratio = readCurve(in.at("ratio"), 1.0, body_height);
  response.twist = in.has("twist_deg") ? readCurve(in.at("twist_deg"), kDegree, body_height) : std::vector<ResponseKey>{};
  response.fitted = in.has("fitted") && in.at("fitted").asBool();
  const std::string problem = muscleResponseProblem(response);
  if (!problem.empty()) in.fail(problem);
  return response;
}

}  // namespace

std::string muscleJson(const MuscleSet& muscles, const Skeleton& skeleton, const std::string& preset_name) {
  nlohmann::json root = nlohmann::json::object();
  nlohmann::json parts = nlohmann::json::object();
  for (const MusclePart& part : muscles.parts) {
    std::string full = part.fullName();
    nlohmann::json& side = root[part.group][part.side];
    side[full + "_muscleOrigin"] = vectorJson(part.origin.world);
    side[full + "_muscleInsertion"] = vectorJson(part.insertion.world);
    side[full + "_muscleDriver"] = vectorJson(part.driver.world);
    parts[full] = {
        {"group", part.group},
        {"part", part.name},
        {"side", part.side},
        {"compression", part.compression},
        {"stretch", part.stretch},
        {"bulge", {part.bulge.x(), part.bulge.y()}},
        {"weight_radius", part.weight_radius},
        {"response", responseJson(part.response)},
        {"origin", locatorJson(part.origin, skeleton)},
        {"insertion", locatorJson(part.insertion, skeleton)},
        {"driver", locatorJson(part.driver, skeleton)},
    };
    // Muscles are written as before (their files stay byte for byte); a corrective says what it is and
    // which landmark carries it.
    if (part.kind == PartKind::kCorrective) {
      parts[full]["kind"] = partKindName(part.kind);
      parts[full]["carrier_landmark"] = part.carrier_landmark;
    }
  }
  root["rigbake"] = {
      {"schema_version", kMuscleSchemaVersion},
      {"units", "m"},
      {"character", muscles.character},
      {"preset", preset_name},
      {"body_height", muscles.body_height},
      {"muscles", parts},
  };
  return jsonText(root) + "\n";
}

MuscleSet readMuscleJson(const std::string& path, const Character& character, const LandmarkSet& landmarks,
                         const MusclePreset& preset) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", kMusclesCode);
  in.requireObject();
  const Skeleton& skeleton = character.skeleton;
  MuscleSet set;
  set.character = fileNameOf(character.source);
  set.body_height = landmarks.body.height;
  set.anatomical_parents = landmarks.anatomical_parents;

  if (in.has("rigbake")) {
    JsonReader block = in.at("rigbake");
    block.allowKeys({"schema_version", "units", "character", "preset", "body_height", "muscles"});
    int version = block.at("schema_version").asInt();
    if (version != kMuscleSchemaVersion)
      block.at("schema_version").fail("unsupported schema version " + std::to_string(version) + " (this rigbake reads " +
                                      std::to_string(kMuscleSchemaVersion) + ")");
    if (block.at("units").asString() != "m") block.at("units").fail("units must be \"m\"");
    JsonReader muscles = block.at("muscles");
    for (const std::string& full : muscles.keys()) {
      JsonReader item = muscles.at(full);
      item.allowKeys({"group", "part", "side", "compression", "stretch", "bulge", "weight_radius", "response", "origin",
                      "insertion", "driver", "kind", "carrier_landmark"});
      MusclePart part;
      part.group = item.at("group").asString();
      part.name = item.at("part").asString();
      part.side = item.at("side").asString();
      if (part.side != "Left" && part.side != "Right") item.at("side").fail("must be \"Left\" or \"Right\"");
      if (part.fullName() != full) item.fail("key must be side + part, i.e. '" + part.fullName() + "'");
      part.compression = item.at("compression").asNumber();
      part.stretch = item.at("stretch").asNumber();
      if (!(part.compression > 0 && part.compression <= 1)) item.at("compression").fail("must be in (0, 1]");
      if (!(part.stretch >= 1)) item.at("stretch").fail("must be at least 1");
      JsonReader bulge = item.at("bulge");
      if (bulge.arraySize() != 2) bulge.fail("must be [across_up, across_side]");
      const double reach = maxReach(set.body_height);
      part.bulge = {bulge.at(0).asNumberIn(-reach, reach, "m"), bulge.at(1).asNumberIn(-reach, reach, "m")};
      part.weight_radius = item.has("weight_radius") ? item.at("weight_radius").asNumberIn(0.0, reach, "m") : 0.0;
      if (item.has("kind") && !parsePartKind(item.at("kind").asString(), &part.kind))
        item.at("kind").fail("must be \"muscle\" or \"corrective\"");
      if (part.kind == PartKind::kCorrective) {
        part.carrier_landmark = item.at("carrier_landmark").asString();
        if (!landmarks.has(part.carrier_landmark))
          rigbake::fail(errc::MUSCLES_MISMATCH, path + "#" + item.at("carrier_landmark").pointer(),
                        "carrier landmark '" + part.carrier_landmark + "' is not resolved on " + set.character);
        part.carrier = landmarks.get(part.carrier_landmark).joint;
      } else if (item.has("carrier_landmark")) {
        item.at("carrier_landmark").fail("only a corrective has a carrier landmark");
      }
      part.response = item.has("response") ? readResponse(item.at("response"), set.body_height) : defaultResponse(part);
      for (auto [key, locator] : {std::pair<const char*, MuscleLocator*>{"origin", &part.origin},
                                  {"insertion", &part.insertion},
                                  {"driver", &part.driver}}) {
        JsonReader loc = item.at(key);
        loc.allowKeys({"joint", "local"});
        std::string joint_name = loc.at("joint").asString();
        int joint = skeleton.find(joint_name);
        if (joint < 0)
          rigbake::fail(errc::MUSCLES_MISMATCH, path + "#" + loc.at("joint").pointer(),
                        "joint '" + joint_name + "' is not in " + set.character + " (is this muscle file for another character? use rigbake retarget)");
        MuscleLocator read;
        read.joint = joint;
        read.local = readVector(loc.at("local"));
        read.world = skeleton.bind_world[joint] * read.local;
        requireWithinReach(loc.at("local"), read.world, set.body_height);
        // Keep the talk-shaped world position when it agrees with the local one, so that a file read
        // and written again is byte-identical; an edit of `local` moves it.
        std::string talk_key = full + (key == std::string("origin") ? "_muscleOrigin"
                                       : key == std::string("insertion") ? "_muscleInsertion"
                                                                          : "_muscleDriver");
        if (in.has(part.group) && in.at(part.group).has(part.side) && in.at(part.group).at(part.side).has(talk_key)) {
          Eigen::Vector3d world = readVector(in.at(part.group).at(part.side).at(talk_key));
          if ((world - read.world).norm() <= 1e-9 * std::max(1.0, landmarks.body.height)) read.world = world;
        }
        *locator = read;
      }
      set.parts.push_back(std::move(part));
    }
    // Stable order: the preset's order, left before right, then anything the preset lacks by name.
    std::map<std::string, int> rank;
    for (const PresetPart& spec : preset.parts) {
      if (spec.kind == PartKind::kMuscle) rank.emplace(spec.name, static_cast<int>(rank.size()));
      for (const std::string& carrier : spec.carriers) rank.emplace(correctivePartName(spec.name, carrier), static_cast<int>(rank.size()));
    }
    std::stable_sort(set.parts.begin(), set.parts.end(), [&](const MusclePart& a, const MusclePart& b) {
      auto key = [&](const MusclePart& p) {
        auto it = rank.find(p.name);
        return std::make_tuple(p.side == "Left" ? 0 : 1, it == rank.end() ? 1 << 20 : it->second, p.name);
      };
      return key(a) < key(b);
    });
    return set;
  }

  // The talk's positions-only shape: attach joints come from the preset part of the same name.
  const double scale = landmarks.body.height / preset.reference_height;
  for (const char* side_name : {"Left", "Right"}) {
    std::string side = side_name == std::string("Left") ? "l" : "r";
    for (const PresetPart& spec : preset.parts) {
      // A muscle is read under its name; a corrective under each of its carriers' names.
      std::vector<std::string> carriers = spec.kind == PartKind::kCorrective ? spec.carriers : std::vector<std::string>{""};
      for (const std::string& carrier : carriers) {
        const std::string part_name = carrier.empty() ? spec.name : correctivePartName(spec.name, carrier);
        std::string group_key = spec.group;
        for (const std::string& alias : spec.group_aliases) {
          if (!in.has(group_key) && in.has(alias)) group_key = alias;
        }
        if (!in.has(group_key) || !in.at(group_key).has(side_name)) continue;
        JsonReader group = in.at(group_key).at(side_name);
        std::string full = side_name + part_name;
        if (!group.has(full + "_muscleOrigin") && !group.has(full + "_muscleInsertion")) continue;
        auto attach = [&](const std::vector<std::string>& candidates) {
          for (const std::string& c : candidates) {
            if (landmarks.has(sidedName(c, side))) return landmarks.get(sidedName(c, side)).joint;
          }
          rigbake::fail(errc::MUSCLES_MISMATCH, path + "#" + group.pointer(),
                        "no attach landmark of " + full + " is resolved on " + set.character);
        };
        int origin_joint = attach(spec.origin_attach);
        auto position = [&](const std::string& key) {
          const Eigen::Vector3d world = readVector(group.at(key));
          requireWithinReach(group.at(key), world, set.body_height);
          return world;
        };
        Eigen::Vector3d origin = position(full + "_muscleOrigin");
        Eigen::Vector3d insertion = position(full + "_muscleInsertion");
        Eigen::Vector3d driver = group.has(full + "_muscleDriver") ? position(full + "_muscleDriver") : (origin + insertion) / 2.0;
        MusclePart part = partFromPreset(skeleton, spec, side_name, origin_joint, attach(spec.insertion_attach), origin,
                                         insertion, driver, scale);
        part.name = part_name;
        if (part.kind == PartKind::kCorrective) {
          part.carrier_landmark = sidedName(carrier, side);
          if (!landmarks.has(part.carrier_landmark))
            rigbake::fail(errc::MUSCLES_MISMATCH, path + "#" + group.pointer(),
                          "carrier landmark '" + part.carrier_landmark + "' of " + full + " is not resolved on " + set.character);
          part.carrier = landmarks.get(part.carrier_landmark).joint;
        }
        set.parts.push_back(std::move(part));
      }
    }
  }
  if (set.parts.empty())
    rigbake::fail(kMusclesCode, path, "no muscle part of preset '" + preset.name + "' found (neither a rigbake block nor talk-shaped groups)");
  return set;
}

}  // namespace rigbake
