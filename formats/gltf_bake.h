// Writes a bake into the loaded glTF: new muscle joint nodes in the skeleton hierarchy and in every
// skin (with inverse bind matrices), animation channels for them in every clip, and the pruned,
// quantized influences as JOINTS_n/WEIGHTS_n plus the packed carrier attributes.
#pragma once

#include "anatomy/muscle_set.h"
#include "formats/gltf_document.h"
#include "pipeline/bake.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

// A copy of the document's model with the bake applied (bake.muscles name the joints); write it
// with writeGltf().
tinygltf::Model bakedModel(const GltfDocument& document, const Character& character, const BakeResult& bake);

}  // namespace rigbake
