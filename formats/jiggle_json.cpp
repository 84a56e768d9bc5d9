#include "formats/jiggle_json.h"

#include "core/error.h"
#include "anatomy/point_formula.h"
#include "formats/json_reader.h"

namespace rigbake {
namespace {

std::string whereOf(const JsonReader& in) { return in.file() + "#" + (in.pointer().empty() ? "/" : in.pointer()); }

double numberIn(const JsonReader& in, double low, double high) {
  const double value = in.asNumber();
  if (value < low || value > high)
    in.fail("must be in [" + nlohmann::json(low).dump() + ", " + nlohmann::json(high).dump() + "] (got " +
            nlohmann::json(value).dump() + ")");
  return value;
}

// A non-zero [x, y, z].
Eigen::Vector3d direction(const JsonReader& in) {
  if (in.arraySize() != 3) in.fail("must be an array of 3 numbers [x, y, z]");
  Eigen::Vector3d v(in.at(size_t{0}).asNumber(), in.at(size_t{1}).asNumber(), in.at(size_t{2}).asNumber());
  if (v.norm() < 1e-12) in.fail("must not be the zero vector");
  return v;
}

}  // namespace

JigglePreset parseJigglePreset(const nlohmann::json& json, const std::string& file) {
  JsonReader in(json, file, "", errc::PRESET_INVALID);
  in.allowKeys({"$schema", "name", "description", "jiggles"});
  JigglePreset preset;
  preset.file = file;
  preset.name = in.has("name") ? in.at("name").asString() : fileStem(file);
  if (in.has("description")) in.at("description").asString();
  const JsonReader jiggles = in.at("jiggles");
  if (jiggles.arraySize() == 0) jiggles.fail("must list at least one jiggle");
  for (size_t i = 0; i < jiggles.arraySize(); ++i) {
    const JsonReader item = jiggles.at(i);
    item.allowKeys({"joint", "landmark", "muscle", "root", "why", "stiffness", "damping", "clamp_major_deg",
                    "clamp_minor_deg", "axis", "major_axis", "length"});
    JigglePresetEntry entry;
    entry.where = whereOf(item);
    const int targets = item.has("joint") + item.has("landmark") + item.has("muscle");
    if (targets != 1) item.fail("needs exactly one of 'joint', 'landmark' or 'muscle' (got " + std::to_string(targets) + ")");
    if (item.has("joint")) entry.joint = item.at("joint").asString();
    if (item.has("muscle")) entry.muscle = item.at("muscle").asString();
    if (item.has("landmark")) {
      entry.landmark = item.at("landmark").asString();
      if (!isCanonicalLandmark(entry.landmark))
        fail(errc::PRESET_LANDMARK_UNKNOWN, whereOf(item.at("landmark")),
             "'" + entry.landmark + "' is not a canonical landmark (see docs/landmarks.md)");
    }
    for (const char* key : {"joint", "landmark", "muscle"}) {
      if (item.has(key) && item.at(key).asString().empty()) item.at(key).fail("must not be empty");
    }
    if (item.has("root")) {
      entry.root = item.at("root").asString();
      if (entry.root.empty()) item.at("root").fail("must not be empty");
    }
    if (item.has("why")) item.at("why").asString();
    entry.params.stiffness = numberIn(item.at("stiffness"), 0.0, 1.0);
    entry.params.damping = numberIn(item.at("damping"), 0.0, 1.0);
    entry.params.clamp_major_deg = numberIn(item.at("clamp_major_deg"), 0.0, 90.0);
    entry.params.clamp_minor_deg = numberIn(item.at("clamp_minor_deg"), 0.0, 90.0);
    if (item.has("axis")) {
      entry.has_axis = true;
      entry.axis = direction(item.at("axis")).normalized();
    }
    if (item.has("major_axis")) {
      entry.has_major_axis = true;
      entry.major_axis = direction(item.at("major_axis")).normalized();
    }
    if (item.has("length")) {
      entry.length = item.at("length").asNumber();
      if (entry.length <= 0.0) item.at("length").fail("must be positive (scene units)");
    }
    preset.jiggles.push_back(std::move(entry));
  }
  return preset;
}

JigglePreset readJigglePreset(const std::string& path) { return parseJigglePreset(readJsonFile(path), path); }

std::vector<HitImpulse> parseHits(const nlohmann::json& json, const std::string& file) {
  JsonReader in(json, file, "", errc::HITS_INVALID);
  in.allowKeys({"$schema", "description", "hits"});
  if (in.has("description")) in.at("description").asString();
  const JsonReader hits = in.at("hits");
  std::vector<HitImpulse> result;
  for (size_t i = 0; i < hits.arraySize(); ++i) {
    const JsonReader item = hits.at(i);
    item.allowKeys({"clip", "time", "direction", "magnitude", "joints", "why"});
    HitImpulse hit;
    hit.where = whereOf(item);
    if (item.has("clip")) hit.clip = item.at("clip").asString();
    if (item.has("why")) item.at("why").asString();
    hit.time = item.at("time").asNumber();
    if (hit.time < 0.0) item.at("time").fail("must not be negative (seconds into the clip)");
    hit.direction = direction(item.at("direction")).normalized();
    hit.magnitude = item.at("magnitude").asNumber();
    if (hit.magnitude < 0.0) item.at("magnitude").fail("must not be negative (metres per second)");
    const JsonReader joints = item.at("joints");
    if (joints.value().is_string() || joints.arraySize() == 0) joints.fail("must be a non-empty array of part names");
    hit.joints = joints.asStringList();
    for (size_t k = 0; k < hit.joints.size(); ++k) {
      if (hit.joints[k].empty()) joints.at(k).fail("must not be empty");
    }
    result.push_back(std::move(hit));
  }
  return result;
}

std::vector<HitImpulse> readHits(const std::string& path) { return parseHits(readJsonFile(path), path); }

}  // namespace rigbake
