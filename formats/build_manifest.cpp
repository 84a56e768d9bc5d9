#include "formats/build_manifest.h"

#include <cstdint>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/json_reader.h"

namespace rigbake {
namespace {

std::string resolve(const std::string& directory, const std::string& path) {
  if (path.empty() || path[0] == '/') return path;
  return directory == "." ? path : directory + "/" + path;
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

// glTF files name their buffers and images by uri; those bytes are inputs too.
std::vector<std::string> referencedFiles(const std::string& gltf_path) {
  std::vector<std::string> files;
  if (gltf_path.size() < 5 || gltf_path.compare(gltf_path.size() - 5, 5, ".gltf") != 0) return files;
  nlohmann::json json = nlohmann::json::parse(readFile(gltf_path), nullptr, false);
  if (!json.is_object()) return files;
  for (const char* key : {"buffers", "images"}) {
    if (!json.contains(key) || !json[key].is_array()) continue;
    for (const auto& item : json[key]) {
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      std::string uri = item["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) continue;
      files.push_back(resolve(directoryOf(gltf_path), uri));
    }
  }
  return files;
}

// A name becomes a folder, a file NAME.glb (with its temporary twin NAME.glb.rigbake-tmp-XXXXXX, under
// the file systems' 255-byte limit) and a word of every progress line: short, one line, printable.
constexpr size_t kMaxNameBytes = 128;

void checkNameText(const JsonReader& value, const std::string& name) {
  if (name.size() > kMaxNameBytes)
    value.fail("is " + std::to_string(name.size()) + " bytes long; a name has at most " + std::to_string(kMaxNameBytes));
  for (size_t i = 0; i < name.size();) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    const size_t length = utf8SequenceAt(name, i);
    if (length == 0 || c < 0x20 || c == 0x7F)
      value.fail("holds a control character or a byte that is not UTF-8 at byte " + std::to_string(i) +
                 "; a name is printable text on one line");
    i += length;
  }
}

}  // namespace

BuildManifest readBuildManifest(const std::string& path, const std::string& default_preset_dir) {
  nlohmann::json json = readJsonFile(path);
  JsonReader in(json, path, "", errc::MANIFEST_INVALID);
  in.allowKeys({"$schema", "preset", "influences", "gltf_weights", "rom", "muscle_motion", "helper_joints", "response", "vrm",
                "map", "regions", "jiggle", "hits", "vrm_springs_only", "fps", "fit_poses", "fit_smoothness", "fit_roughness_cap", "fit_volume", "fit_regions", "stats",
                "packed", "out", "characters"});
  BuildManifest manifest;
  manifest.file = path;
  manifest.directory = directoryOf(path);
  auto presetPath = [&](const JsonReader& value) {
    std::string preset = value.asString();
    std::string relative = resolve(manifest.directory, preset);
    if (exists(relative)) return relative;
    std::string shipped = default_preset_dir + "/muscles/" + preset + ".json";
    if (exists(shipped)) return shipped;
    value.fail("preset '" + preset + "' is neither a file (relative to the manifest) nor a shipped preset name");
  };
  manifest.preset = in.has("preset") ? presetPath(in.at("preset")) : default_preset_dir + "/muscles/gow_biped.json";
  auto influencesOf = [](const JsonReader& value) {
    int n = value.asInt();
    if (n != 4 && n != 7 && n != 10) value.fail("must be 4, 7 or 10");
    return n;
  };
  if (in.has("influences")) manifest.influences = influencesOf(in.at("influences"));
  auto gltfWeightsOf = [](const JsonReader& value) {
    GltfWeights weights = GltfWeights::kMilli;
    if (!parseGltfWeights(value.asString(), &weights)) value.fail("must be \"milli\" or \"unorm16\"");
    return weights;
  };
  if (in.has("gltf_weights")) manifest.gltf_weights = gltfWeightsOf(in.at("gltf_weights"));
  // "rom": a ROM preset file or shipped name, true for the default one, false for none (docs/rom.md).
  auto romOf = [&](const JsonReader& value) -> std::string {
    if (value.value().is_boolean()) return value.value().get<bool>() ? default_preset_dir + "/rom/default.json" : "";
    std::string rom = value.asString();
    std::string relative = resolve(manifest.directory, rom);
    if (!rom.empty() && exists(relative)) return relative;
    std::string shipped = default_preset_dir + "/rom/" + rom + ".json";
    if (!rom.empty() && exists(shipped)) return shipped;
    value.fail("ROM preset '" + rom + "' is neither a file (relative to the manifest) nor a shipped ROM preset name");
  };
  if (in.has("rom")) manifest.rom = romOf(in.at("rom"));
  auto motionOf = [](const JsonReader& value) {
    MuscleMotion motion = MuscleMotion::kRuntime;
    if (!parseMuscleMotion(value.asString(), &motion)) value.fail("must be \"runtime\", \"sampled\" or \"both\"");
    return motion;
  };
  auto responseOf = [](const JsonReader& value) {
    ResponseMode mode = ResponseMode::kAuto;
    if (!parseResponseMode(value.asString(), &mode)) value.fail("must be \"auto\", \"fit\" or \"keep\"");
    return mode;
  };
  if (in.has("muscle_motion")) manifest.muscle_motion = motionOf(in.at("muscle_motion"));
  if (in.has("helper_joints")) manifest.helper_joints = in.at("helper_joints").asBool();
  if (in.has("response")) manifest.response = responseOf(in.at("response"));
  auto vrmOf = [](const JsonReader& value) {
    const int version = value.asInt();
    if (version != 0 && version != 1) value.fail("must be 0 or 1 (the VRM version to write)");
    return version;
  };
  if (in.has("vrm")) manifest.vrm = vrmOf(in.at("vrm"));
  // A file relative to the manifest, else the name of a shipped preset under DEFAULT/KIND/.
  auto shippedOrFile = [&](const JsonReader& value, const std::string& kind) -> std::string {
    std::string name = value.asString();
    std::string relative = resolve(manifest.directory, name);
    if (!name.empty() && exists(relative)) return relative;
    std::string shipped = default_preset_dir + "/" + kind + "/" + name + ".json";
    if (!name.empty() && exists(shipped)) return shipped;
    value.fail(kind + " preset '" + name + "' is neither a file (relative to the manifest) nor a shipped " + kind + " preset name");
  };
  // A naming map file relative to the manifest, else the name of a shipped map (checked when it is used,
  // against the maps' own names, as bake --map).
  auto mapOf = [&](const JsonReader& value) -> std::string {
    std::string map = value.asString();
    if (map.empty()) value.fail("must name a naming map file or a shipped map (it is empty)");
    std::string relative = resolve(manifest.directory, map);
    return exists(relative) ? relative : map;
  };
  auto hitsOf = [&](const JsonReader& value) {
    std::string hits = value.asString();
    if (hits.empty()) value.fail("must name a hit file (it is empty)");
    return resolve(manifest.directory, hits);
  };
  auto fpsOf = [](const JsonReader& value) { return value.asNumberIn(0.0, 1e6, "frames per second"); };
  auto fitPosesOf = [](const JsonReader& value) {
    const int poses = value.asInt();
    if (poses < 1 || poses > 100000) value.fail("must be from 1 to 100000");
    return poses;
  };
  if (in.has("map")) manifest.map = mapOf(in.at("map"));
  if (in.has("regions")) manifest.regions = shippedOrFile(in.at("regions"), "regions");
  if (in.has("jiggle")) manifest.jiggle = shippedOrFile(in.at("jiggle"), "jiggle");
  if (in.has("hits")) manifest.hits = hitsOf(in.at("hits"));
  if (in.has("vrm_springs_only")) manifest.vrm_springs_only = in.at("vrm_springs_only").asBool();
  if (in.has("fps")) manifest.fps = fpsOf(in.at("fps"));
  if (in.has("fit_poses")) manifest.fit_poses = fitPosesOf(in.at("fit_poses"));
  auto smoothnessOf = [](const JsonReader& value) { return value.asNumberIn(0.0, 1e6, "per metre"); };
  if (in.has("fit_smoothness")) manifest.fit_smoothness = smoothnessOf(in.at("fit_smoothness"));
  auto roughnessCapOf = [](const JsonReader& value) {
    const double cap = value.asNumberIn(0.0, 100.0, "times plain skinning's roughness rise");
    if (cap > 0.0 && cap < 1.0) value.fail("must be 0 (no cap) or from 1 to 100 times plain skinning's roughness rise");
    return cap;
  };
  if (in.has("fit_roughness_cap")) manifest.fit_roughness_cap = roughnessCapOf(in.at("fit_roughness_cap"));
  // A setting of two names: true for `on`, false for `off`, anything else refused naming both.
  auto eitherOf = [](const JsonReader& value, const std::string& off, const std::string& on) {
    const std::string name = value.asString();
    if (name != off && name != on) value.fail("must be \"" + off + "\" or \"" + on + "\"");
    return name == on;
  };
  auto occupiedOf = [&](const JsonReader& value) { return eitherOf(value, "signed", "occupied"); };
  if (in.has("fit_volume")) manifest.fit_occupied_volume = occupiedOf(in.at("fit_volume"));
  auto everyFrameOf = [&](const JsonReader& value) { return eitherOf(value, "fitted-poses", "every-frame"); };
  if (in.has("fit_regions")) manifest.fit_every_frame_regions = everyFrameOf(in.at("fit_regions"));
  if (in.has("stats")) manifest.stats = in.at("stats").asBool();
  if (in.has("packed")) manifest.packed = in.at("packed").asBool();
  auto outOf = [](const JsonReader& value) {
    std::string out = value.asString();
    if (out.empty()) value.fail("must name the output folder (it is empty)");
    return out;
  };
  manifest.out = resolve(manifest.directory, in.has("out") ? outOf(in.at("out")) : std::string("build"));
  JsonReader characters = in.at("characters");
  if (characters.arraySize() == 0) characters.fail("must list at least one character");
  std::set<std::string> names;
  for (size_t i = 0; i < characters.arraySize(); ++i) {
    JsonReader item = characters.at(i);
    item.allowKeys({"name", "input", "muscles_from", "muscles", "preset", "influences", "gltf_weights", "rom",
                    "muscle_motion", "helper_joints", "response", "vrm", "map", "regions", "jiggle", "hits",
                    "vrm_springs_only", "fps", "fit_poses", "fit_smoothness", "fit_roughness_cap", "fit_volume", "fit_regions", "stats", "packed"});
    BuildCharacter c;
    c.pointer = item.pointer();
    c.name = item.at("name").asString();
    if (c.name.empty() || c.name.find_first_of("/\\ \t:$") != std::string::npos || c.name[0] == '.')
      item.at("name").fail("must be a plain file name (no slashes, spaces, ':' or '$', not starting with '.')");
    checkNameText(item.at("name"), c.name);
    if (!names.insert(c.name).second) item.at("name").fail("duplicate character name '" + c.name + "'");
    c.input = resolve(manifest.directory, item.at("input").asString());
    if (item.has("muscles_from")) {
      c.muscles_from = item.at("muscles_from").asString();
      checkNameText(item.at("muscles_from"), c.muscles_from);
    }
    if (item.has("muscles")) c.muscles = resolve(manifest.directory, item.at("muscles").asString());
    if (!c.muscles.empty() && !c.muscles_from.empty())
      item.fail("give either muscles or muscles_from, not both");
    if (c.muscles_from == c.name && !c.name.empty()) item.at("muscles_from").fail("a character cannot retarget from itself");
    c.preset = item.has("preset") ? presetPath(item.at("preset")) : manifest.preset;
    c.influences = item.has("influences") ? influencesOf(item.at("influences")) : manifest.influences;
    c.gltf_weights = item.has("gltf_weights") ? gltfWeightsOf(item.at("gltf_weights")) : manifest.gltf_weights;
    c.rom = item.has("rom") ? romOf(item.at("rom")) : manifest.rom;
    c.muscle_motion = item.has("muscle_motion") ? motionOf(item.at("muscle_motion")) : manifest.muscle_motion;
    c.helper_joints = item.has("helper_joints") ? item.at("helper_joints").asBool() : manifest.helper_joints;
    c.response = item.has("response") ? responseOf(item.at("response")) : manifest.response;
    c.vrm = item.has("vrm") ? vrmOf(item.at("vrm")) : manifest.vrm;
    c.map = item.has("map") ? mapOf(item.at("map")) : manifest.map;
    c.regions = item.has("regions") ? shippedOrFile(item.at("regions"), "regions") : manifest.regions;
    c.jiggle = item.has("jiggle") ? shippedOrFile(item.at("jiggle"), "jiggle") : manifest.jiggle;
    c.hits = item.has("hits") ? hitsOf(item.at("hits")) : manifest.hits;
    c.vrm_springs_only = item.has("vrm_springs_only") ? item.at("vrm_springs_only").asBool() : manifest.vrm_springs_only;
    c.fps = item.has("fps") ? fpsOf(item.at("fps")) : manifest.fps;
    c.fit_poses = item.has("fit_poses") ? fitPosesOf(item.at("fit_poses")) : manifest.fit_poses;
    c.fit_smoothness = item.has("fit_smoothness") ? smoothnessOf(item.at("fit_smoothness")) : manifest.fit_smoothness;
    c.fit_roughness_cap = item.has("fit_roughness_cap") ? roughnessCapOf(item.at("fit_roughness_cap")) : manifest.fit_roughness_cap;
    c.fit_occupied_volume = item.has("fit_volume") ? occupiedOf(item.at("fit_volume")) : manifest.fit_occupied_volume;
    c.fit_every_frame_regions = item.has("fit_regions") ? everyFrameOf(item.at("fit_regions")) : manifest.fit_every_frame_regions;
    c.stats = item.has("stats") ? item.at("stats").asBool() : manifest.stats;
    c.packed = item.has("packed") ? item.at("packed").asBool() : manifest.packed;
    // Hits kick jiggle joints, and spring bones are jiggles: neither means anything without a jiggle.
    if (c.jiggle.empty() && !c.hits.empty()) item.fail("gives hits but no jiggle: hits kick jiggle joints");
    if (c.jiggle.empty() && c.vrm_springs_only) item.fail("sets vrm_springs_only but gives no jiggle");
    manifest.characters.push_back(std::move(c));
  }
  buildOrder(manifest);  // reports unknown and cyclic muscles_from now, before any work
  return manifest;
}

std::string contentHash(const std::vector<std::string>& files, const std::string& extra) {
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](const std::string& bytes) {
    for (unsigned char c : bytes) {
      hash ^= c;
      hash *= 1099511628211ull;
    }
    // Separate fields so that moving bytes between them changes the hash.
    hash ^= bytes.size();
    hash *= 1099511628211ull;
  };
  std::vector<std::string> all;
  for (const std::string& file : files) {
    all.push_back(file);
    for (const std::string& referenced : referencedFiles(file)) all.push_back(referenced);
  }
  for (const std::string& file : all) mix(readFile(file));
  mix(extra);
  std::ostringstream hex;
  hex << std::hex << std::setw(16) << std::setfill('0') << hash;
  return hex.str();
}

}  // namespace rigbake
