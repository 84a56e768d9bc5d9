// gltfWithClips() apart from formats/gltf_clips.cpp, so that the fuzz targets, which link the clip
// writer but not the glTF serializer (fuzz/CMakeLists.txt), need no more of formats/.
#include <tiny_gltf.h>

#include "formats/gltf_clips.h"
#include "formats/gltf_write.h"

namespace rigbake {

std::string gltfWithClips(const GltfDocument& document, const Character& character, const std::vector<Clip>& clips,
                          bool binary) {
  return serializeGltf(modelWithClips(document, character, clips), binary);
}

}  // namespace rigbake
