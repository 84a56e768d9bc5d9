// The `rigbake validate --config FILE` format: per check code, a threshold and/or a severity that
// replace the defaults of pipeline/check_registry.h. Parsed strictly (formats/json_reader.h): an unknown key or
// code is an error naming its JSON pointer, so a typo cannot silently keep a default. docs/validate.md
// documents it:
//   {"checks": {"LOCATOR_NEAR_SURFACE": {"threshold": 0.15}, "LOCATOR_SYMMETRY": {"severity": "error"}}}
#pragma once

#include <string>

#include "pipeline/check_registry.h"

namespace rigbake {

// Throws IO_FILE_NOT_FOUND, JSON_PARSE_FAILED or VALIDATE_CONFIG_INVALID (with the JSON pointer).
ValidationConfig readValidationConfig(const std::string& path);

}  // namespace rigbake
