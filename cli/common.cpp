#include "cli/common.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"
#include "app/character.h"

namespace rigbake::cli {

namespace {

// The names of the naming maps shipped beside rigbake (RIGBAKE_DEFAULT_PRESET_DIR/skeletons/*.json),
// comma-separated and sorted, for --help: a map added as data shows up without a word of C++. Read once
// per run, though seven subcommands print it.
const std::string& shippedNamingMapNames() {
  static const std::string joined = [] {
    std::vector<std::string> names;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(RIGBAKE_DEFAULT_PRESET_DIR) + "/skeletons", error))
      if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
    std::sort(names.begin(), names.end());
    std::string list;
    for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
    return list;
  }();
  return joined;
}

}  // namespace

void addPresetOptions(CLI::App* command, PresetOptions* options) {
  command->add_option("--presets", options->presets_dir,
                      "Directory of presets (skeletons/, muscles/, landmarks.json); default: $RIGBAKE_PRESETS or the "
                      "presets/ shipped with rigbake");
  command->add_option("--map", options->map,
                      "Skeleton naming map: a JSON file (see docs/presets.md) or a shipped map name (" +
                          shippedNamingMapNames() + "). Default: auto-detect, then structure");
}

std::string presetsDirectory(const PresetOptions& options) {
  if (!options.presets_dir.empty()) return options.presets_dir;
  if (const char* env = std::getenv("RIGBAKE_PRESETS")) return env;
  return RIGBAKE_DEFAULT_PRESET_DIR;
}

std::string presetFile(const PresetOptions& options, const std::string& kind, const std::string& name_or_path) {
  return app::presetFile(presetsDirectory(options), kind, name_or_path);
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

app::NoteReport printNotesOf(const std::string& path) {
  return [path](const std::string& note) { std::cerr << printableLine("note " + path + ": " + note) << "\n"; };
}

ResolvedCharacter loadAndResolve(const std::string& path, const PresetOptions& options, const LoadOptions& load) {
  app::CharacterSource source;
  source.path = path;
  source.load = load;
  source.map = options.map;
  return withFlagNames({{"map", options.map_flag}},
                       [&] { return app::loadCharacter(source, app::loadPresets(presetsDirectory(options)), printNotesOf(path)); });
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

}  // namespace rigbake::cli
