// The deformation-quality figures (pipeline/deformation_quality.h) as JSON, shared by `bake --stats`
// and `validate`'s report.json (docs/output-contract.md). Volume changes in percent of the bind
// volume, skin moves in millimetres.
#pragma once

#include <nlohmann/json.hpp>

#include "pipeline/deformation_quality.h"

namespace rigbake {

nlohmann::json deformationQualityJson(const DeformationQuality& quality);

}  // namespace rigbake
