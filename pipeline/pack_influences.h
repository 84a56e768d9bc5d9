// The packed skin-influence buffers of the God of War talk, exactly as docs/packed-influences.md lays
// them out (layout version 1): per vertex, ceil((N - 1) / 3) 32-bit words holding N - 1 weights of 10 bits
// in units of 1/1000 (the last weight is rebuilt by the decoder as 1000 minus the others), then N joint
// indices of 8 or 16 bits padded to a multiple of 4 bytes. formats/shaders/unpack_influences.glsl
// decodes the same layout on the GPU.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

constexpr int kPackedLayoutVersion = 1;
constexpr int kPackedWeightBits = 10;
constexpr int kPackedWeightsPerWord = 3;

// Per-vertex packed influences. weight_words holds packedWeightWords(influences) words per vertex
// (host integers; files and glTF buffers store them little endian). indices holds one record of
// packedIndexStride(influences, index_bytes) bytes per vertex: slot k's index at byte k * index_bytes,
// little endian, the padding bytes 0.
struct PackedInfluences {
  int influences = 0;   // N: 4, 7 or 10
  int index_bytes = 0;  // 1 or 2
  int joint_count = 0;  // every index is below it
  int vertex_count = 0;
  std::vector<std::uint32_t> weight_words;
  std::vector<std::uint8_t> indices;
};

// The influence counts the talk's formats define, and a test for them.
constexpr int kPackedInfluenceCounts[] = {4, 7, 10};
bool isPackedInfluenceCount(int influences);
// ceil((N - 1) / 3): 1, 2, 3 words for N = 4, 7, 10.
int packedWeightWords(int influences);
// N * index_bytes rounded up to 4: 4, 8, 12 bytes (8-bit) and 8, 16, 20 bytes (16-bit).
int packedIndexStride(int influences, int index_bytes);
// 1 when every index fits 8 bits (at most 256 joints), else 2; throws INTERNAL above 65536 joints.
int packedIndexBytesFor(int joint_count);

// Packs 0.001-quantized influences (full_scale 1000, exactly `influences` slots per vertex, canonical
// order as quantizeInfluences() gives). Slots 0 .. N-2 are stored; slot N-1 is the one the decoder
// rebuilds, the smallest weight. Throws INTERNAL on input outside that contract (wrong scale or slot
// count, a joint at or above joint_count, an index width that cannot hold joint_count - 1).
PackedInfluences packInfluences(const QuantizedInfluences& quantized, int joint_count, int index_bytes);

// An empty string when `packed` obeys layout version 1, else the first problem with its vertex:
// array sizes, reserved bits (30-31 of every word) not 0, stored weights summing above 1000, an index
// at or above joint_count, padding bytes not 0. formats/packed_file.cpp reports it for a bad file.
std::string packedInfluencesProblem(const PackedInfluences& packed);

// Decodes every vertex back to 0.001 weights (full_scale 1000, `influences` slots), rebuilding slot N-1
// as 1000 minus the stored weights, as the shader does. decode(pack(q)) == q for canonical q.
// Throws INTERNAL when packedInfluencesProblem() is not empty.
QuantizedInfluences unpackInfluences(const PackedInfluences& packed);

// The same buffers as glTF-legal custom vertex attributes, for a writer to put on the baked primitive.
// glTF 2.0 (3.7.2.1) requires application-specific semantics to start with "_" and forbids
// UNSIGNED_INT for them, so each 32-bit word travels as two UNSIGNED_SHORT components (low half
// first, i.e. the word's little-endian bytes unchanged), at most VEC4 per attribute:
//   _RIGBAKE_PACKED_WEIGHTS_0  words 0-1 (VEC2 when N = 4, else VEC4)
//   _RIGBAKE_PACKED_WEIGHTS_1  word 2 (VEC2, N = 10 only)
//   _RIGBAKE_PACKED_JOINTS_m   the index record split into 4-byte (8-bit: VEC4 UNSIGNED_BYTE) or
//                              8-byte (16-bit: VEC4 UNSIGNED_SHORT, a 4-byte tail VEC2) pieces.
// None is normalized. Each element is a multiple of 4 bytes, so the sizes add up to exactly the
// packed bytes per vertex.
std::vector<VertexAttributeData> packedGltfAttributes(const PackedInfluences& packed);

}  // namespace rigbake
