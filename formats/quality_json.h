// The deformation-quality figures (pipeline/deformation_quality.h) as JSON, shared by `bake --stats`
// and `validate`'s report.json (docs/output-contract.md). Volume changes in percent of the bind
// volume, skin moves in millimetres.
#pragma once

#include <nlohmann/json.hpp>

#include "pipeline/deformation_quality.h"
#include "pipeline/skin_place.h"

namespace rigbake {

nlohmann::json deformationQualityJson(const DeformationQuality& quality);

// Where to find a skin place (pipeline/skin_place.h): `mesh`, `gltf_mesh`, `primitive`, `vertex` and
// `bind_position`, the fields every place in the stats and report.json carries.
nlohmann::json skinPlaceJson(const SkinPlace& place);

}  // namespace rigbake
