#include "formats/preset_json.h"

#include <algorithm>
#include <dirent.h>

#include "core/error.h"
#include "formats/json_reader.h"

namespace rigbake {
namespace {

const ErrorCode& kPresetCode = errc::PRESET_INVALID;

void requireLandmark(const JsonReader& where, const std::string& name) {
  if (!isCanonicalLandmark(name)) {
    std::string known;
    for (const std::string& central : centralLandmarks()) known += central + " ";
    for (const std::string& sided : sidedLandmarks()) known += sided + " ";
    fail(errc::PRESET_LANDMARK_UNKNOWN, where.file() + "#" + where.pointer(),
         "'" + name + "' is not a canonical landmark (known: " + known + "; sided names may end in _l or _r)");
  }
}

// Lengths in a preset are reference metres, scaled to the body: none is negative (a direction gives the
// sign) or more than kMaxReferenceHeights reference heights, and a lerp's t stays within kMaxLerp of its
// segment, so that a placed point lies within about a hundred body heights (docs/presets.md).
constexpr double kMaxReferenceHeights = 100.0, kMaxLerp = 100.0, kMaxReferenceHeight = 1000.0;

PointFormula readFormula(const JsonReader& in, double max_length) {
  in.requireObject();
  PointFormula formula;
  formula.pointer = in.pointer();
  if (in.has("at")) {
    in.allowKeys({"at"});
    formula.kind = PointFormula::Kind::kAt;
    formula.name = in.at("at").asString();
    requireLandmark(in.at("at"), formula.name);
  } else if (in.has("mean")) {
    in.allowKeys({"mean"});
    formula.kind = PointFormula::Kind::kMean;
    JsonReader items = in.at("mean");
    if (items.arraySize() < 1) items.fail("needs at least one point");
    for (size_t i = 0; i < items.arraySize(); ++i) formula.args.push_back(readFormula(items.at(i), max_length));
  } else if (in.has("lerp")) {
    in.allowKeys({"lerp", "t"});
    formula.kind = PointFormula::Kind::kLerp;
    JsonReader items = in.at("lerp");
    if (items.arraySize() != 2) items.fail("needs exactly two points [A, B]");
    formula.args = {readFormula(items.at(0), max_length), readFormula(items.at(1), max_length)};
    formula.t = in.at("t").asNumberIn(-kMaxLerp, kMaxLerp);
  } else if (in.has("sum")) {
    in.allowKeys({"sum"});
    formula.kind = PointFormula::Kind::kSum;
    JsonReader items = in.at("sum");
    if (items.arraySize() < 1) items.fail("needs at least one term");
    for (size_t i = 0; i < items.arraySize(); ++i) formula.args.push_back(readFormula(items.at(i), max_length));
  } else if (in.has("dir")) {
    in.allowKeys({"dir", "ref_m"});
    formula.kind = PointFormula::Kind::kDir;
    formula.name = in.at("dir").asString();
    static const std::vector<std::string> kDirections = {"up", "down", "forward", "back", "lateral", "medial"};
    if (std::find(kDirections.begin(), kDirections.end(), formula.name) == kDirections.end())
      in.at("dir").fail("unknown direction '" + formula.name + "' (up, down, forward, back, lateral, medial)");
    formula.ref_m = in.at("ref_m").asNumberIn(0.0, max_length, "reference metres");
  } else if (in.has("joint_axis")) {
    in.allowKeys({"joint_axis", "axis", "ref_m"});
    formula.kind = PointFormula::Kind::kJointAxis;
    formula.name = in.at("joint_axis").asString();
    requireLandmark(in.at("joint_axis"), formula.name);
    formula.axis = in.at("axis").asString();
    if (formula.axis != "x" && formula.axis != "y" && formula.axis != "z") in.at("axis").fail("must be x, y or z");
    formula.ref_m = in.at("ref_m").asNumberIn(0.0, max_length, "reference metres");
  } else if (in.has("mix")) {
    in.allowKeys({"mix"});
    formula.kind = PointFormula::Kind::kMix;
    JsonReader mix = in.at("mix");
    mix.allowKeys({"lateral", "up", "forward"});
    formula.args = {readFormula(mix.at("lateral"), max_length), readFormula(mix.at("up"), max_length),
                    readFormula(mix.at("forward"), max_length)};
  } else if (in.has("locator")) {
    in.allowKeys({"locator"});
    formula.kind = PointFormula::Kind::kLocator;
    formula.name = in.at("locator").asString();
  } else {
    in.fail("a point formula needs one of: at, mean, lerp, sum, dir, joint_axis, mix, locator");
  }
  return formula;
}

}  // namespace

NamingMap readNamingMap(const std::string& path) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", kPresetCode);
  in.allowKeys({"$schema", "name", "description", "match", "strip_prefixes", "side_tokens", "landmarks"});
  NamingMap map;
  map.file = path;
  map.name = in.has("name") ? in.at("name").asString() : fileStem(path);
  if (in.has("description")) map.description = in.at("description").asString();
  if (in.has("match")) {
    map.match = in.at("match").asString();
    if (map.match != "names" && map.match != "vrm_humanoid") in.at("match").fail("must be 'names' or 'vrm_humanoid'");
  }
  if (in.has("strip_prefixes")) map.strip_prefixes = in.at("strip_prefixes").asStringList();
  if (in.has("side_tokens")) {
    JsonReader sides = in.at("side_tokens");
    sides.allowKeys({"l", "r"});
    for (const std::string& side : sides.keys()) map.side_tokens[side] = sides.at(side).asStringList();
  }
  JsonReader landmarks = in.at("landmarks");
  for (const std::string& key : landmarks.keys()) {
    requireLandmark(landmarks, key);
    map.landmarks[key] = landmarks.at(key).asStringList();
    bool uses_side = false;
    for (const std::string& pattern : map.landmarks[key]) uses_side |= pattern.find("{side}") != std::string::npos;
    if (uses_side && (map.side_tokens["l"].empty() || map.side_tokens["r"].empty()))
      landmarks.at(key).fail("uses {side} but side_tokens does not define both 'l' and 'r'");
  }
  return map;
}

std::vector<NamingMap> readNamingMaps(const std::string& directory) {
  std::vector<std::string> files;
  if (DIR* dir = opendir(directory.c_str())) {
    while (dirent* entry = readdir(dir)) {
      std::string name = entry->d_name;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0) files.push_back(directory + "/" + name);
    }
    closedir(dir);
  } else {
    fail(errc::IO_FILE_NOT_FOUND, directory, "the naming map directory cannot be read");
  }
  std::sort(files.begin(), files.end());
  std::vector<NamingMap> maps;
  for (const std::string& file : files) maps.push_back(readNamingMap(file));
  return maps;
}

LandmarkRules readLandmarkRules(const std::string& path) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", kPresetCode);
  in.allowKeys({"$schema", "description", "reference_height", "derivations", "limb_roots"});
  LandmarkRules rules;
  rules.file = path;
  if (in.has("reference_height")) rules.reference_height = in.at("reference_height").asNumberIn(1e-3, kMaxReferenceHeight, "m");
  JsonReader derivations = in.at("derivations");
  for (size_t i = 0; i < derivations.arraySize(); ++i) {
    JsonReader item = derivations.at(i);
    item.allowKeys({"landmark", "formula", "rides_on", "why"});
    LandmarkDerivation derivation;
    derivation.pointer = item.pointer();
    derivation.landmark = item.at("landmark").asString();
    requireLandmark(item.at("landmark"), derivation.landmark);
    derivation.formula = readFormula(item.at("formula"), kMaxReferenceHeights * rules.reference_height);
    derivation.rides_on = item.at("rides_on").asString();
    requireLandmark(item.at("rides_on"), derivation.rides_on);
    rules.derivations.push_back(std::move(derivation));
  }
  if (in.has("limb_roots")) {
    JsonReader limb_roots = in.at("limb_roots");
    for (size_t i = 0; i < limb_roots.arraySize(); ++i) {
      JsonReader item = limb_roots.at(i);
      item.allowKeys({"limb", "anchor", "not_under", "why"});
      LimbRootRule rule;
      rule.pointer = item.pointer();
      rule.limb = item.at("limb").asStringList();
      rule.anchor = item.at("anchor").asString();
      rule.not_under = item.at("not_under").asStringList();
      // Each name canonical (PRESET_LANDMARK_UNKNOWN otherwise) and of the kind its key takes.
      const auto requireKind = [&](const char* key, const std::vector<std::string>& names, const std::vector<std::string>& kind,
                                   const std::string& what) {
        for (const std::string& name : names) {
          requireLandmark(item.at(key), name);
          if (std::find(kind.begin(), kind.end(), name) == kind.end()) item.at(key).fail("'" + name + "' is not " + what);
        }
      };
      if (rule.limb.empty()) item.at("limb").fail("needs at least one landmark");
      requireKind("limb", rule.limb, sidedLandmarks(), "a sided landmark's base name (clavicle, upper_arm, upper_leg, ...)");
      requireKind("anchor", {rule.anchor}, centralLandmarks(), "a central landmark (pelvis, chest, ...)");
      requireKind("not_under", rule.not_under, centralLandmarks(), "a central landmark (spine_l5, neck, ...)");
      rules.limb_roots.push_back(std::move(rule));
    }
  }
  return rules;
}

namespace {
std::vector<std::string> presetPartNames(const PresetPart& part) {
  if (part.kind == PartKind::kMuscle) return {part.name};
  std::vector<std::string> names;
  for (const std::string& carrier : part.carriers) names.push_back(correctivePartName(part.name, carrier));
  return names;
}
}  // namespace

MusclePreset readMusclePreset(const std::string& path) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", kPresetCode);
  in.allowKeys({"$schema", "name", "description", "reference_height", "muscles"});
  MusclePreset preset;
  preset.file = path;
  preset.name = in.has("name") ? in.at("name").asString() : fileStem(path);
  if (in.has("reference_height")) {
    preset.reference_height = in.at("reference_height").asNumber();
    if (preset.reference_height <= 0) in.at("reference_height").fail("must be positive");
    preset.reference_height = in.at("reference_height").asNumberIn(1e-3, kMaxReferenceHeight, "m");
  }
  JsonReader muscles = in.at("muscles");
  if (muscles.arraySize() == 0) muscles.fail("must list at least one muscle part");
  for (size_t i = 0; i < muscles.arraySize(); ++i) {
    JsonReader item = muscles.at(i);
    item.allowKeys({"group", "group_aliases", "name", "why", "origin_attach", "insertion_attach", "origin", "insertion", "driver",
                    "compression", "stretch", "bulge", "weight_radius_ref_m", "optional", "kind", "carriers"});
    PresetPart part;
    part.pointer = item.pointer();
    part.group = item.at("group").asString();
    if (item.has("group_aliases")) part.group_aliases = item.at("group_aliases").asStringList();
    part.name = item.at("name").asString();
    part.origin_attach = item.at("origin_attach").asStringList();
    part.insertion_attach = item.at("insertion_attach").asStringList();
    for (const std::string& name : part.origin_attach) requireLandmark(item.at("origin_attach"), name);
    for (const std::string& name : part.insertion_attach) requireLandmark(item.at("insertion_attach"), name);
    if (part.origin_attach.empty()) item.at("origin_attach").fail("must name at least one landmark");
    if (part.insertion_attach.empty()) item.at("insertion_attach").fail("must name at least one landmark");
    const double max_length = kMaxReferenceHeights * preset.reference_height;
    part.origin = readFormula(item.at("origin"), max_length);
    part.insertion = readFormula(item.at("insertion"), max_length);
    if (item.has("driver")) {
      part.has_driver = true;
      part.driver = readFormula(item.at("driver"), max_length);
    }
    if (item.has("compression")) part.compression = item.at("compression").asNumber();
    if (item.has("stretch")) part.stretch = item.at("stretch").asNumber();
    if (!(part.compression > 0 && part.compression <= 1)) item.at("compression").fail("must be in (0, 1]");
    if (!(part.stretch >= 1)) item.at("stretch").fail("must be at least 1");
    if (item.has("bulge")) {
      JsonReader bulge = item.at("bulge");
      if (bulge.arraySize() != 2) bulge.fail("must be [across_up, across_side]");
      part.bulge[0] = bulge.at(0).asNumberIn(-max_length, max_length, "reference metres");
      part.bulge[1] = bulge.at(1).asNumberIn(-max_length, max_length, "reference metres");
    }
    part.optional = item.has("optional") && item.at("optional").asBool();
    if (item.has("kind") && !parsePartKind(item.at("kind").asString(), &part.kind))
      item.at("kind").fail("must be \"muscle\" or \"corrective\"");
    if (part.kind == PartKind::kCorrective) {
      part.carriers = item.at("carriers").asStringList();
      if (part.carriers.empty()) item.at("carriers").fail("must name at least one landmark");
      for (const std::string& name : part.carriers) requireLandmark(item.at("carriers"), name);
    } else if (item.has("carriers")) {
      item.at("carriers").fail("only a corrective names carriers (a muscle takes weight from the joint its field covers most)");
    }
    // Part names are unique: a corrective's are its name with each carrier.
    for (const std::string& name : presetPartNames(part)) {
      for (const PresetPart& earlier : preset.parts) {
        for (const std::string& taken : presetPartNames(earlier)) {
          if (taken == name) item.at("name").fail("duplicate muscle part name '" + name + "'");
        }
      }
    }
    if (item.has("weight_radius_ref_m")) {
      part.weight_radius_ref_m = item.at("weight_radius_ref_m").asNumber();
      if (part.weight_radius_ref_m < 0) item.at("weight_radius_ref_m").fail("must not be negative");
      part.weight_radius_ref_m = item.at("weight_radius_ref_m").asNumberIn(0.0, max_length, "reference metres");
    }
    preset.parts.push_back(std::move(part));
  }
  // Locator references must point backwards so evaluation order is the file order.
  return preset;
}

namespace {

// A region's or a crease's reach: {"landmark", "radius": {"from", "to", "fraction"}}, within fraction x
// the distance between two landmarks (a bone's length) of a landmark.
void readNear(const JsonReader& near, std::string* landmark, std::string* from, std::string* to, double* fraction) {
  near.allowKeys({"landmark", "radius"});
  *landmark = near.at("landmark").asString();
  requireLandmark(near.at("landmark"), *landmark);
  JsonReader radius = near.at("radius");
  radius.allowKeys({"from", "to", "fraction"});
  *from = radius.at("from").asString();
  *to = radius.at("to").asString();
  requireLandmark(radius.at("from"), *from);
  requireLandmark(radius.at("to"), *to);
  *fraction = radius.at("fraction").asNumber();
  if (!(*fraction > 0)) radius.at("fraction").fail("must be positive");
}

// A crease (anatomy/creases.h): {"name", "sided", "proximal": [landmarks], "distal": [landmarks],
// "bend": [proximal landmark, distal landmark], "near": {"landmark", "radius": {"from", "to", "fraction"}}}.
CreaseRule readCreaseRule(const JsonReader& item) {
  item.allowKeys({"name", "sided", "proximal", "distal", "bend", "near", "why"});
  CreaseRule rule;
  rule.pointer = item.pointer();
  rule.name = item.at("name").asString();
  if (rule.name.empty()) item.at("name").fail("must not be empty");
  rule.sided = item.has("sided") && item.at("sided").asBool();
  for (const char* key : {"proximal", "distal"}) {
    std::vector<std::string>& side = std::string(key) == "proximal" ? rule.proximal : rule.distal;
    side = item.at(key).asStringList();
    if (side.empty()) item.at(key).fail("must name at least one landmark");
    for (const std::string& landmark : side) requireLandmark(item.at(key), landmark);
  }
  JsonReader bend = item.at("bend");
  if (bend.arraySize() != 2) bend.fail("must be [proximal landmark, distal landmark]");
  rule.bend_proximal = bend.at(0).asString();
  rule.bend_distal = bend.at(1).asString();
  requireLandmark(bend.at(0), rule.bend_proximal);
  requireLandmark(bend.at(1), rule.bend_distal);
  readNear(item.at("near"), &rule.near, &rule.radius_from, &rule.radius_to, &rule.radius_fraction);
  return rule;
}

}  // namespace

RegionPreset readRegionPreset(const std::string& path) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", kPresetCode);
  in.allowKeys({"$schema", "name", "description", "regions", "creases"});
  RegionPreset preset;
  preset.file = path;
  preset.name = in.has("name") ? in.at("name").asString() : fileStem(path);
  JsonReader regions = in.at("regions");
  if (regions.arraySize() == 0) regions.fail("must list at least one region rule");
  for (size_t i = 0; i < regions.arraySize(); ++i) {
    JsonReader item = regions.at(i);
    item.allowKeys({"name", "sided", "owners", "near", "facing", "why"});
    RegionRule rule;
    rule.pointer = item.pointer();
    rule.name = item.at("name").asString();
    if (rule.name.empty()) item.at("name").fail("must not be empty");
    rule.sided = item.has("sided") && item.at("sided").asBool();
    rule.owners = item.at("owners").asStringList();
    if (rule.owners.empty()) item.at("owners").fail("must name at least one landmark");
    for (const std::string& owner : rule.owners) requireLandmark(item.at("owners"), owner);
    if (item.has("near")) readNear(item.at("near"), &rule.near, &rule.radius_from, &rule.radius_to, &rule.radius_fraction);
    if (item.has("facing")) {
      JsonReader facing = item.at("facing");
      facing.allowKeys({"side", "of"});
      rule.facing = facing.at("side").asString();
      if (rule.facing != "forward" && rule.facing != "back") facing.at("side").fail("must be \"forward\" or \"back\"");
      rule.facing_landmark = facing.at("of").asString();
      requireLandmark(facing.at("of"), rule.facing_landmark);
    }
    preset.rules.push_back(std::move(rule));
  }
  if (in.has("creases")) {
    JsonReader creases = in.at("creases");
    for (size_t i = 0; i < creases.arraySize(); ++i) preset.creases.push_back(readCreaseRule(creases.at(i)));
  }
  return preset;
}

}  // namespace rigbake
