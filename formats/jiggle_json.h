// Jiggle presets (presets/jiggle/*.json, schema presets/schemas/jiggle_preset.schema.json) and hit
// files (`--hits`), read strictly: an unknown key is an error with its JSON pointer. docs/jiggle.md
// describes both formats.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/jiggle.h"

namespace rigbake {

// Throws IO_FILE_NOT_FOUND, JSON_PARSE_FAILED, PRESET_INVALID (with the JSON pointer) or
// PRESET_LANDMARK_UNKNOWN. Names are resolved later, against a character, by resolveJiggles().
JigglePreset readJigglePreset(const std::string& path);
JigglePreset parseJigglePreset(const nlohmann::json& json, const std::string& file);

// Throws IO_FILE_NOT_FOUND, JSON_PARSE_FAILED or HITS_INVALID (with the JSON pointer). Hit parts are
// checked against the jiggles by checkHits().
std::vector<HitImpulse> readHits(const std::string& path);
std::vector<HitImpulse> parseHits(const nlohmann::json& json, const std::string& file);

}  // namespace rigbake
