// FBX input: an FBX file read by Assimp and converted, once, into a glTF 2.0 model in memory, so that
// the glTF reader builds the same Character from it and every writer adds to it as to a loaded glTF.
#pragma once

#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rigbake {

// True when the path ends in ".fbx", whatever the case.
bool isFbxPath(const std::string& path);

// What the conversion left out, one sentence each (e.g. a mesh made only of lines), for the CLI to
// print; empty when everything was converted.
struct FbxConversion {
  std::vector<std::string> notes;
};

// Reads `path` (FBX 7.x, binary or ASCII) and fills `model` with a glTF 2.0 scene in metres, +Y
// up: one node per FBX node (names made unique), skinned meshes with their inverse bind matrices,
// JOINTS_n/WEIGHTS_n (normalised, 4 per set), clips in seconds, one material per FBX material (its
// diffuse colour). See docs/fbx.md. Throws Error IO_FILE_NOT_FOUND or FBX_PARSE_FAILED.
FbxConversion convertFbxToGltf(const std::string& path, tinygltf::Model* model);

}  // namespace rigbake
