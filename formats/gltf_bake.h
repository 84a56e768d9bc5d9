// Writes a bake into the loaded glTF: new muscle joint nodes in the skeleton hierarchy and in every
// skin (with inverse bind matrices), animation channels for them in every clip, and the pruned,
// quantized influences as JOINTS_n/WEIGHTS_n plus the packed carrier attributes.
#pragma once

#include "anatomy/muscle_set.h"
#include "formats/gltf_document.h"
#include <string>

#include "pipeline/bake.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

// A copy of the document's model with the bake applied (bake.muscles name the joints); write it
// with writeGltf().
tinygltf::Model bakedModel(const GltfDocument& document, const Character& character, const BakeResult& bake);

// The baked file as bytes, with what the bake command reports about it.
struct BakedFile {
  std::string bytes;
  long long animation_bytes = 0;        // buffer bytes of every animation sampler's input and output
  long long input_animation_bytes = 0;  // the same in the input document
  bool vrm = false;
  int vrm_constrained_muscles = 0;      // muscles whose base and tip carry VRMC_node_constraint (VRM 1.0)
};

bool isVrmDocument(const GltfDocument& document);

// bakedModel(), plus `springs` as VRM spring bones when the document is a VRM (VRM runtimes simulate
// them live; docs/jiggle.md) and, for VRM 1.0 with helper joints, the base and tip aim constraints as
// VRMC_node_constraint (docs/extensions.md), serialized as GLB (binary) or glTF JSON.
BakedFile writeBakedFile(const GltfDocument& document, const Character& character, const BakeResult& bake,
                         bool binary, const std::vector<JiggleSetup>& springs);

}  // namespace rigbake
