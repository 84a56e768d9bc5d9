#include "cli/common.h"

#include <cstdlib>
#include <fstream>

#include "anatomy/error.h"
#include "formats/preset_json.h"

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
  fail("IO_FILE_NOT_FOUND", name_or_path, "no such preset file, and no shipped preset of that name in " +
                                              presetsDirectory(options) + "/" + kind + "/");
}

MusclePreset loadMusclePreset(const PresetOptions& options, const std::string& name_or_path) {
  return readMusclePreset(presetFile(options, "muscles", name_or_path));
}

ResolvedCharacter loadAndResolve(const std::string& path, const PresetOptions& options) {
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
      if (!found) fail("MAP_NOT_FOUND", options.map, "neither a naming map file nor the name of a shipped map in " + dir + "/skeletons");
    }
    inputs.forced_map = &forced;
  }
  ResolvedCharacter resolved;
  resolved.loaded = loadCharacter(path);
  resolved.landmarks = resolveLandmarks(resolved.loaded.character, inputs);
  return resolved;
}

std::string fileNameOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace rigbake::cli
