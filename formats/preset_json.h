// Strict parsers for the anatomy presets under presets/ (schemas in presets/schemas/). Every error is
// PRESET_INVALID (or JSON_PARSE_FAILED / IO_FILE_NOT_FOUND) naming the file and JSON pointer.
#pragma once

#include <string>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy/presets.h"

namespace rigbake {

NamingMap readNamingMap(const std::string& path);
// Every presets/skeletons/*.json in a directory, sorted by file name (detection ties break by it).
std::vector<NamingMap> readNamingMaps(const std::string& directory);
LandmarkRules readLandmarkRules(const std::string& path);
MusclePreset readMusclePreset(const std::string& path);
// presets/regions/*.json: body regions for the deformation-quality figures.
RegionPreset readRegionPreset(const std::string& path);

}  // namespace rigbake
