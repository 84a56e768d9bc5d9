// Writes a tinygltf model as .glb/.vrm (binary) or .gltf (JSON with the buffer embedded as base64),
// byte-deterministically and atomically. Works on models built by rigbake and on models the loader
// read (formats/gltf_read keeps images as their encoded bytes): all buffers are merged into one, and
// images given by an external file or a data: URI are moved into buffer views, so the output stands
// alone wherever it is written.
#pragma once

#include <string>

namespace tinygltf {
class Model;
}

namespace rigbake {

struct GltfDocument;  // formats/gltf_document.h

// The bytes of the file. `binary` selects GLB. Throws Error GLTF_PARSE_FAILED (with a JSON pointer)
// when a buffer view lies outside its buffer, and INTERNAL when an image holds decoded pixels instead
// of its encoded file bytes.
// Takes the model by value: move a model in that is not needed afterwards, so its buffers are not
// copied (the GLB is assembled straight from them).
std::string serializeGltf(tinygltf::Model model, bool binary);

// Binary when `path` ends in .glb or .vrm (any case), JSON otherwise. Throws IO_WRITE_FAILED; a
// failed write leaves no file behind.
void writeGltf(tinygltf::Model model, const std::string& path);

// True for paths that writeGltf writes as GLB.
bool isBinaryGltfPath(const std::string& path);

// A loaded file as one GLB: the file's own bytes when `path` is a GLB or VRM (compressed or not: the
// `rigbake view` page decodes EXT_meshopt_compression and KHR_draco_mesh_compression itself), else the
// document serialized (a .gltf with its buffers and images beside it becomes one self-contained GLB).
std::string glbOf(const std::string& path, const GltfDocument& document);

// True when the GLB's JSON chunk names `extension` (e.g. in extensionsUsed).
bool glbUsesExtension(const std::string& glb, const std::string& extension);

}  // namespace rigbake
