// ROM presets (presets/rom/*.json, schema presets/schemas/rom_preset.schema.json), read strictly: an
// unknown key is PRESET_INVALID with its JSON pointer. docs/rom.md describes the format.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "pipeline/rom.h"

namespace rigbake {

// Throws IO_FILE_NOT_FOUND, JSON_PARSE_FAILED, PRESET_INVALID or PRESET_LANDMARK_UNKNOWN (with the
// JSON pointer). Landmarks are resolved later, against a character, by buildRom().
RomPreset readRomPreset(const std::string& path);
RomPreset parseRomPreset(const nlohmann::json& json, const std::string& file);

// The ROM clips built on a character, for `rom --json` and `bake --stats`: per clip its name, animation,
// duration, keys, range and peak, per side the axis, the rest angle and the joints keyed; and the
// skipped clips.
nlohmann::json romJson(const RomResult& rom, const Skeleton& skeleton);

}  // namespace rigbake
