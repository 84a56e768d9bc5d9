// Writes clips made by rigbake (the range-of-motion clips of pipeline/rom.h) into the loaded glTF as
// ordinary animations, after the file's own, which stay as they were.
#pragma once

#include <string>
#include <vector>

#include "anatomy/character.h"
#include "formats/gltf_document.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

// A copy of the document's model with one animation per clip (named clip.name), in order: per track a
// sampler (its interpolation, float keys; tracks with equal times share one input accessor) and a
// channel on the joint's node. Write it with writeGltf(). Clips marked measure_only are not written.
tinygltf::Model modelWithClips(const GltfDocument& document, const Character& character,
                               const std::vector<Clip>& clips);

// modelWithClips() as the bytes of a file: GLB when `binary`, glTF JSON otherwise (formats/gltf_write.h).
std::string gltfWithClips(const GltfDocument& document, const Character& character, const std::vector<Clip>& clips,
                          bool binary);

}  // namespace rigbake
