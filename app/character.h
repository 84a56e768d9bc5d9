// What every job starts from: the presets directory read once (naming maps, landmark rules) and a
// character loaded and its landmarks resolved. app/ is the layer the command line, `build`, the
// benches and the tests call for whole jobs (load, stages, bytes out); it never prints and names no
// flag: a bad option is an InvalidOption naming its field (core/error.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "anatomy/landmarks.h"
#include "anatomy/presets.h"
#include "formats/gltf_document.h"

namespace rigbake::app {

// The presets several jobs share, read-only: build's characters bake in parallel from one copy.
struct Presets {
  std::string directory;
  std::vector<NamingMap> maps;  // DIRECTORY/skeletons/*.json
  LandmarkRules rules;          // DIRECTORY/landmarks.json
};

// Throws IO_FILE_NOT_FOUND, JSON_PARSE_FAILED or PRESET_INVALID for a broken presets directory.
Presets loadPresets(const std::string& directory);

// A preset file by path, or by name under DIRECTORY/KIND/ (the presets directory) (muscles, jiggle, rom, regions);
// IO_FILE_NOT_FOUND otherwise.
std::string presetFile(const std::string& directory, const std::string& kind, const std::string& name_or_path);

// A character file and how to read it.
struct CharacterSource {
  std::string path;  // .glb, .gltf, .vrm or .fbx
  LoadOptions load;  // the VRM version to turn it into
  // A naming map forced on the skeleton: a map file, or the name of a shipped map; empty: detect one,
  // then fall back on the skeleton's structure.
  std::string map;
};

// Told of each note as loading makes it (what an FBX or a VRM conversion left out, one sentence), so a
// command line can print it before whatever comes next, a later failure included.
using NoteReport = std::function<void(const std::string& note)>;

struct ResolvedCharacter {
  LoadedCharacter loaded;  // its notes (what an FBX or VRM conversion left out) are the caller's to print
  LandmarkSet landmarks;
};

// The naming map `map` names (see CharacterSource::map); MAP_NOT_FOUND when it names none.
NamingMap namingMapOf(const Presets& presets, const std::string& map);

// The character's landmarks; throws LANDMARK_UNRESOLVED (and what resolveLandmarks throws).
LandmarkSet resolveCharacterLandmarks(const Character& character, const Presets& presets, const std::string& map = "");

// Reads the file, tells `notes` of its notes, then resolves its landmarks. The map is checked first, so a
// misspelt map name fails before a large file is parsed.
ResolvedCharacter loadCharacter(const CharacterSource& source, const Presets& presets, const NoteReport& notes = {});

}  // namespace rigbake::app
