// The procedural mannequin as a glTF model: one node per joint (node index = joint index), a "Body"
// node with the skinned mesh, one skin, one animation per clip, and for the VRM variants the VRM 0.x
// ("VRM") or VRM 1.0 ("VRMC_vrm") extension that maps humanoid bones to nodes.
#pragma once

#include <string>

#include "sample/sample_character.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

tinygltf::Model sampleToGltf(const SampleCharacter& character);

// sampleToGltf, then formats/gltf_write's writeGltf (GLB for .glb/.vrm, JSON glTF otherwise).
void writeSampleGltf(const SampleCharacter& character, const std::string& path);

}  // namespace rigbake
