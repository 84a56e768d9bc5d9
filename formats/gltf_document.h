// A loaded glTF/GLB/VRM file: the plain Character the stages work on, plus the parsed document kept
// opaque so a writer can add to it without losing what rigbake does not model (materials, textures,
// extensions, rigid meshes).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "anatomy/character.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

struct GltfDocument;  // wraps tinygltf::Model; defined in formats/gltf_read.cpp

struct LoadedCharacter {
  Character character;
  std::shared_ptr<GltfDocument> document;
  // What loading left out, one sentence each, for the CLI to print (an FBX mesh of lines); empty for glTF.
  std::vector<std::string> notes;
};

// Which VRM the loaded document is to be: as it is, or (bake --vrm) a VRM 0.x or 1.0. A VRM 0.x asked
// to be 1.0 is converted before the Character is built (formats/vrm0_to_vrm1.h), so the Character
// and every writer see a VRM 1.0; any other change of version is refused.
enum class VrmTarget { kAsIs, kVrm0, kVrm1 };

struct LoadOptions {
  VrmTarget vrm = VrmTarget::kAsIs;
};

// Reads .glb, .gltf (external or embedded buffers) and .vrm (0.x and 1.0), and .fbx (any case) through
// formats/fbx_to_gltf.h: the document is then the glTF model converted from it. Throws Error with
// FBX_PARSE_FAILED for an FBX that Assimp cannot read, otherwise with
// IO_FILE_NOT_FOUND, GLTF_PARSE_FAILED, GLTF_EXTENSION_UNSUPPORTED (extensionsRequired names an
// extension formats/gltf_extensions.h does not list), GLTF_NO_SKIN, GLTF_SKIN_INVALID or
// GLTF_ACCESSOR_INVALID; with options.vrm, VRM_CONVERSION_UNSUPPORTED when the input is not a VRM or is
// a VRM 1.0 asked to be 0.x.
LoadedCharacter loadCharacter(const std::string& path, const LoadOptions& options = {});

// Access for formats/ writers only.
tinygltf::Model& modelOf(GltfDocument& document);
const tinygltf::Model& modelOf(const GltfDocument& document);

}  // namespace rigbake
