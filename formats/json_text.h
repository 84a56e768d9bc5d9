// The JSON text rigbake writes (files and --json output), in one place.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace rigbake {

// `value` indented by 2. A string may hold bytes that are not UTF-8 (a path as the file system spells
// it, which rigbake echoes as "input"/"output"): such bytes are written as U+FFFD instead of making the
// writer throw after the work is done, so that a bake of "n\xFF.glb" still gets its stats file.
// A template over nlohmann's JSON types: report.json is an ordered_json whose fields keep the order
// docs/validate.md gives, which a conversion to nlohmann::json would sort.
template <typename Json>
std::string jsonText(const Json& value) {
  return value.dump(2, ' ', false, Json::error_handler_t::replace);
}

}  // namespace rigbake
