// Reads the batch build manifest (docs/build.md, presets/schemas/build_manifest.schema.json).
#pragma once

#include <string>

#include "pipeline/build_plan.h"

namespace rigbake {

// Relative paths are resolved against the manifest's directory. `default_preset_dir` resolves a
// preset given by name (e.g. "gow_biped"). Throws MANIFEST_INVALID, JSON_PARSE_FAILED or
// IO_FILE_NOT_FOUND.
BuildManifest readBuildManifest(const std::string& path, const std::string& default_preset_dir);

// FNV-1a 64-bit hash of a file's bytes, of the files a glTF refers to by relative uri, and of `extra`:
// the incremental build compares these, not timestamps. Returns a hex string.
std::string contentHash(const std::vector<std::string>& files, const std::string& extra);

}  // namespace rigbake
