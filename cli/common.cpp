#include "cli/common.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"

namespace rigbake::cli {

void addPresetOptions(CLI::App* command, PresetOptions* options) {
  command->add_option("--presets", options->presets_dir,
                      "Directory of presets (skeletons/, muscles/, landmarks.json); default: $RIGBAKE_PRESETS or the "
                      "presets/ shipped with rigbake");
  command->add_option("--map", options->map,
                      "Skeleton naming map: a JSON file (see docs/presets.md) or a shipped map name (gow, mixamo, "
                      "unreal, vrm_humanoid, blender, quaternius). Default: auto-detect, then structure");
}

std::string presetsDirectory(const PresetOptions& options) {
  if (!options.presets_dir.empty()) return options.presets_dir;
  if (const char* env = std::getenv("RIGBAKE_PRESETS")) return env;
  return RIGBAKE_DEFAULT_PRESET_DIR;
}

namespace {
bool exists(const std::string& path) { return std::ifstream(path).good(); }
}  // namespace

std::string presetFile(const PresetOptions& options, const std::string& kind, const std::string& name_or_path) {
  if (exists(name_or_path)) return name_or_path;
  std::string shipped = presetsDirectory(options) + "/" + kind + "/" + name_or_path + ".json";
  if (exists(shipped)) return shipped;
  fail(errc::IO_FILE_NOT_FOUND, name_or_path, "no such preset file, and no shipped preset of that name in " +
                                              presetsDirectory(options) + "/" + kind + "/");
}

MusclePreset loadMusclePreset(const PresetOptions& options, const std::string& name_or_path) {
  return readMusclePreset(presetFile(options, "muscles", name_or_path));
}

RomPreset loadRomPreset(const PresetOptions& options, const std::string& name_or_path) {
  return readRomPreset(presetFile(options, "rom", name_or_path));
}

std::vector<std::string> splitClipNames(const std::string& list, const std::string& option) {
  std::vector<std::string> names;
  if (list.empty()) return names;
  const std::string text = list + ",";
  for (size_t start = 0, comma; (comma = text.find(',', start)) != std::string::npos; start = comma + 1) {
    const std::string name = text.substr(start, comma - start);
    if (name.empty()) fail(errc::USAGE, option, "has an empty clip name in '" + list + "'");
    names.push_back(name);
  }
  return names;
}

namespace {
// Six decimals: the axes are for reading, and the file's floats hold about seven digits anyway.
double rounded(double value) { return std::round(value * 1e6) / 1e6 + 0.0; }
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
                       {"axis", {rounded(sweep.axis.x()), rounded(sweep.axis.y()), rounded(sweep.axis.z())}},
                       {"rest_deg", rounded(sweep.zero_deg)},
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

ResolvedCharacter loadAndResolve(const std::string& path, const PresetOptions& options, const LoadOptions& load) {
  const std::string dir = presetsDirectory(options);
  std::vector<NamingMap> maps = readNamingMaps(dir + "/skeletons");
  LandmarkRules rules = readLandmarkRules(dir + "/landmarks.json");
  NamingMap forced;
  LandmarkInputs inputs;
  inputs.maps = &maps;
  inputs.rules = &rules;
  if (!options.map.empty()) {
    if (exists(options.map)) {
      forced = readNamingMap(options.map);
    } else {
      bool found = false;
      for (const NamingMap& map : maps) {
        if (map.name == options.map) {
          forced = map;
          found = true;
        }
      }
      if (!found) fail(errc::MAP_NOT_FOUND, options.map, "neither a naming map file nor the name of a shipped map in " + dir + "/skeletons");
    }
    inputs.forced_map = &forced;
  }
  ResolvedCharacter resolved;
  resolved.loaded = loadCharacter(path, load);
  // What an FBX or a VRM 0.x -> 1.0 conversion did and left out (formats/fbx_to_gltf.h,
  // formats/vrm0_to_vrm1.h); a glTF input loaded as it is has no notes.
  for (const std::string& note : resolved.loaded.notes) std::cerr << printableLine("note " + path + ": " + note) << "\n";
  resolved.landmarks = resolveLandmarks(resolved.loaded.character, inputs);
  return resolved;
}

void checkOutputOptions(std::initializer_list<OutputOption> outputs, bool json_on_stdout) {
  const char* on_stdout = json_on_stdout ? "--json" : nullptr;
  for (const OutputOption& output : outputs) {
    if (output.path.empty()) {
      if (output.required) fail(errc::USAGE, output.option, "names no file (an empty path)");
      continue;
    }
    if (output.path == kStandardOutput) {
      if (!output.to_stdout)
        fail(errc::USAGE, output.option, "'-' (standard output) is only for JSON outputs; name a file (./- for one named '-')");
      if (on_stdout != nullptr)
        fail(errc::USAGE, output.option, std::string("'-' and ") + on_stdout + " would both print on standard output");
      on_stdout = output.option;
    }
    checkOutputPath(output.path);
  }
}

std::string fileNameOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace rigbake::cli
