// Decoding of compressed glTF on load, so that everything after the loader (and every writer) sees
// plain accessors: EXT_meshopt_compression (compressed buffer views, decoded with meshoptimizer) and
// KHR_draco_mesh_compression (compressed primitives, decoded with Draco). KHR_mesh_quantization
// needs no decoding: its integer accessors are plain glTF accessors that readAccessor dequantizes.
// Outputs are written uncompressed: both extensions leave extensionsUsed and extensionsRequired.
#pragma once

#include <string>

namespace tinygltf {
class Model;
}

namespace rigbake {

// tinygltf 2.7 (Debian's build, without its own Draco support) cannot parse two things compressed
// files contain: a Draco primitive's indices accessor, which has no bufferView ("accessor[N] invalid
// bufferView"), and an EXT_meshopt_compression fallback buffer without a uri (a .gltf fails to load
// it; a GLB gives it a copy of the BIN chunk, or fails when the BIN chunk is shorter). When the
// file's JSON mentions either extension, this rewrites it (GLB or JSON glTF, `bytes` in place) so
// tinygltf parses it: a Draco primitive's `indices` moves into its extension object, and fallback
// buffers without a uri are dropped, with the buffer views that referenced them pointing at their
// compressed bytes. decompressGltf undoes both. Files without compression are not touched.
void prepareCompressedGltf(std::string* bytes);

// Decodes every compressed buffer view and primitive of `model` in place (after
// prepareCompressedGltf and tinygltf's parse) and removes both extensions from it. Decoded data goes
// into one new buffer; views and accessors keep their indices. `where` names the file in errors:
// GLTF_PARSE_FAILED when compressed data does not decode, GLTF_ACCESSOR_INVALID when the decoded
// data does not fit its accessors.
void decompressGltf(tinygltf::Model* model, const std::string& where);

}  // namespace rigbake
