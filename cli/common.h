// What several subcommands share: finding the presets, loading a character and resolving its
// landmarks from flags.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "anatomy/landmarks.h"
#include "anatomy/presets.h"
#include "formats/gltf_document.h"

namespace rigbake::cli {

struct PresetOptions {
  std::string presets_dir;  // --presets; default: $RIGBAKE_PRESETS or the source tree's presets/
  std::string map;          // --map: a naming map file, or the name of a shipped map
};

void addPresetOptions(CLI::App* command, PresetOptions* options);
std::string presetsDirectory(const PresetOptions& options);

// A preset file by path, or by name under presets/KIND/ (muscles, jiggle); IO_FILE_NOT_FOUND otherwise.
std::string presetFile(const PresetOptions& options, const std::string& kind, const std::string& name_or_path);

// A muscle preset by file path, or by name under presets/muscles/.
MusclePreset loadMusclePreset(const PresetOptions& options, const std::string& name_or_path);

struct ResolvedCharacter {
  LoadedCharacter loaded;
  LandmarkSet landmarks;
};

ResolvedCharacter loadAndResolve(const std::string& path, const PresetOptions& options);

// "a/b/hero.glb" -> "hero.glb": outputs name inputs without directories so they do not depend on
// where the tool ran.
std::string fileNameOf(const std::string& path);

}  // namespace rigbake::cli
