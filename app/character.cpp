#include "app/character.h"

#include <fstream>

#include "core/error.h"
#include "formats/preset_json.h"

namespace rigbake::app {
namespace {
bool exists(const std::string& path) { return std::ifstream(path).good(); }
}  // namespace

Presets loadPresets(const std::string& directory) {
  Presets presets;
  presets.directory = directory;
  presets.maps = readNamingMaps(directory + "/skeletons");
  presets.rules = readLandmarkRules(directory + "/landmarks.json");
  return presets;
}

std::string presetFile(const std::string& directory, const std::string& kind, const std::string& name_or_path) {
  if (exists(name_or_path)) return name_or_path;
  const std::string shipped = directory + "/" + kind + "/" + name_or_path + ".json";
  if (exists(shipped)) return shipped;
  fail(errc::IO_FILE_NOT_FOUND, name_or_path,
       "no such preset file, and no shipped preset of that name in " + directory + "/" + kind + "/");
}

NamingMap namingMapOf(const Presets& presets, const std::string& map) {
  if (exists(map)) return readNamingMap(map);
  for (const NamingMap& shipped : presets.maps)
    if (shipped.name == map) return shipped;
  fail(errc::MAP_NOT_FOUND, map,
       "neither a naming map file nor the name of a shipped map in " + presets.directory + "/skeletons");
}

namespace {

LandmarkSet resolveWith(const Character& character, const Presets& presets, const NamingMap* forced) {
  LandmarkInputs inputs;
  inputs.maps = &presets.maps;
  inputs.rules = &presets.rules;
  inputs.forced_map = forced;
  return resolveLandmarks(character, inputs);
}

}  // namespace

LandmarkSet resolveCharacterLandmarks(const Character& character, const Presets& presets, const std::string& map) {
  if (map.empty()) return resolveWith(character, presets, nullptr);
  const NamingMap forced = namingMapOf(presets, map);
  return resolveWith(character, presets, &forced);
}

ResolvedCharacter loadCharacter(const CharacterSource& source, const Presets& presets, const NoteReport& notes) {
  NamingMap forced;
  if (!source.map.empty()) forced = namingMapOf(presets, source.map);
  ResolvedCharacter resolved;
  resolved.loaded = rigbake::loadCharacter(source.path, source.load);
  if (notes)
    for (const std::string& note : resolved.loaded.notes) notes(note);
  resolved.landmarks = resolveWith(resolved.loaded.character, presets, source.map.empty() ? nullptr : &forced);
  return resolved;
}

}  // namespace rigbake::app
