// Packed skin influences, after the God of War Ragnarök talk (Tenghao Wang, "Joint-Based Skin
// Deformation in God of War Ragnarök", section "Increase Bone Influences per Vertex"):
//   God of War, 4 influences: weights as one 32Bit_R10G10B10A2_Unorm, indices 8Bit_Uint or 16Bit_Uint,
//     weight precision 0.001, final weight reconstructed in the shader.
//   God of War Ragnarök, 7/10 influences: weights as raw 32Bit_Uint, indices 32Bit_Uint, precision
//     0.001, final weight reconstructed in the shader.
// 0.001 steps need 10 bits (1000 < 1024), so three weights fill the R, G, B fields of one word and the
// 2-bit A field is left 0 (reserved); 7 and 10 influences use the same 10-bit fields in 2 and 3 words.
// Indices are 8 or 16 bits rather than the talk's 32 for 7/10 (the brief's "8/16-bit indices"): a
// humanoid skin rarely exceeds 256 joints, and the width is chosen from the joint count.
// Byte layout and the glTF carrier: docs/packed-influences.md.
#include "pipeline/pack_influences.h"

#include <algorithm>

#include "core/error.h"

namespace rigbake {

namespace {

constexpr std::uint32_t kWeightFieldMask = (1u << kPackedWeightBits) - 1u;
// Bits 30-31 of every word: the talk's A2 field, reserved (0) in layout version 1.
constexpr std::uint32_t kReservedBitsMask = 0xC0000000u;

void requireLayout(int influences, int index_bytes) {
  if (!isPackedInfluenceCount(influences))
    fail(errc::INTERNAL, "", "packed influences are 4, 7 or 10 per vertex, not " + std::to_string(influences));
  if (index_bytes != 1 && index_bytes != 2)
    fail(errc::INTERNAL, "", "packed joint indices are 1 or 2 bytes, not " + std::to_string(index_bytes));
}

int storedWeight(const PackedInfluences& packed, int vertex, int slot) {
  std::uint32_t word = packed.weight_words[static_cast<size_t>(vertex) * packedWeightWords(packed.influences) +
                                           slot / kPackedWeightsPerWord];
  return static_cast<int>((word >> (kPackedWeightBits * (slot % kPackedWeightsPerWord))) & kWeightFieldMask);
}

int storedIndex(const PackedInfluences& packed, int vertex, int slot) {
  size_t offset = static_cast<size_t>(vertex) * packedIndexStride(packed.influences, packed.index_bytes) +
                  static_cast<size_t>(slot) * packed.index_bytes;
  int index = packed.indices[offset];
  if (packed.index_bytes == 2) index |= packed.indices[offset + 1] << 8;
  return index;
}

// Splits each vertex's `stride`-byte record into attributes of at most `chunk` bytes, copying bytes
// unchanged (both sides are little endian), so the attribute data is the packed data, de-interleaved.
void appendChunks(const std::vector<std::uint8_t>& records, int vertices, int stride, int chunk, int component_bytes,
                  const std::string& prefix, std::vector<VertexAttributeData>* out) {
  int index = 0;
  for (int begin = 0; begin < stride; begin += chunk, ++index) {
    int size = std::min(chunk, stride - begin);
    int components = size / component_bytes;
    VertexAttributeData attribute;
    attribute.semantic = prefix + std::to_string(index);
    attribute.accessor.component_type = component_bytes == 1 ? kGltfUnsignedByte : kGltfUnsignedShort;
    attribute.accessor.type = components == 4 ? "VEC4" : components == 2 ? "VEC2" : "SCALAR";
    attribute.accessor.count = vertices;
    attribute.accessor.normalized = false;
    attribute.bytes.reserve(static_cast<size_t>(vertices) * size);
    for (int v = 0; v < vertices; ++v) {
      auto first = records.begin() + static_cast<std::ptrdiff_t>(v) * stride + begin;
      attribute.bytes.insert(attribute.bytes.end(), first, first + size);
    }
    out->push_back(std::move(attribute));
  }
}

}  // namespace

bool isPackedInfluenceCount(int influences) { return influences == 4 || influences == 7 || influences == 10; }

int packedWeightWords(int influences) {
  return (influences - 1 + kPackedWeightsPerWord - 1) / kPackedWeightsPerWord;
}

int packedIndexStride(int influences, int index_bytes) { return (influences * index_bytes + 3) / 4 * 4; }

int packedIndexBytesFor(int joint_count) {
  if (joint_count < 1 || joint_count > 65536)
    fail(errc::INTERNAL, "", "packed joint indices are at most 16 bits; joint count " + std::to_string(joint_count));
  return joint_count <= 256 ? 1 : 2;
}

PackedInfluences packInfluences(const QuantizedInfluences& quantized, int joint_count, int index_bytes) {
  const int n = quantized.slots_per_vertex;
  requireLayout(n, index_bytes);
  if (quantized.full_scale != kMilliScale)
    fail(errc::INTERNAL, "", "packed weights are in units of 1/1000, not 1/" + std::to_string(quantized.full_scale));
  if (joint_count < 1 || joint_count > (index_bytes == 1 ? 256 : 65536))
    fail(errc::INTERNAL, "", std::to_string(joint_count) + " joints do not fit " + std::to_string(8 * index_bytes) +
                             "-bit indices");
  if (quantized.weights.size() != quantized.joints.size() || quantized.joints.size() % n != 0)
    fail(errc::INTERNAL, "", "packInfluences: joints and weights do not hold whole vertices");
  PackedInfluences packed;
  packed.influences = n;
  packed.index_bytes = index_bytes;
  packed.joint_count = joint_count;
  packed.vertex_count = quantized.vertexCount();
  const int words = packedWeightWords(n);
  const int stride = packedIndexStride(n, index_bytes);
  packed.weight_words.assign(static_cast<size_t>(packed.vertex_count) * words, 0u);
  packed.indices.assign(static_cast<size_t>(packed.vertex_count) * stride, 0u);
  for (int v = 0; v < packed.vertex_count; ++v) {
    size_t base = static_cast<size_t>(v) * n;
    int sum = 0;
    for (int k = 0; k < n; ++k) {
      int joint = quantized.joints[base + k];
      int weight = quantized.weights[base + k];
      sum += weight;
      if (joint < 0 || joint >= joint_count)
        fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " names joint " + std::to_string(joint) + " of " +
                                 std::to_string(joint_count));
      if (k < n - 1) {
        packed.weight_words[static_cast<size_t>(v) * words + k / kPackedWeightsPerWord] |=
            static_cast<std::uint32_t>(weight) << (kPackedWeightBits * (k % kPackedWeightsPerWord));
      }
      size_t offset = static_cast<size_t>(v) * stride + static_cast<size_t>(k) * index_bytes;
      packed.indices[offset] = static_cast<std::uint8_t>(joint & 0xff);
      if (index_bytes == 2) packed.indices[offset + 1] = static_cast<std::uint8_t>((joint >> 8) & 0xff);
    }
    // The decoder rebuilds slot N-1 as 1000 minus the rest, which is this vertex's slot only when the
    // sum is exact; each weight is at most 1000 < 1024, so it fits its field.
    if (sum != kMilliScale)
      fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " weights sum to " + std::to_string(sum) + ", not 1000");
  }
  return packed;
}

std::string packedInfluencesProblem(const PackedInfluences& packed) {
  if (!isPackedInfluenceCount(packed.influences))
    return "influence count " + std::to_string(packed.influences) + " is not 4, 7 or 10";
  if (packed.index_bytes != 1 && packed.index_bytes != 2)
    return "index width " + std::to_string(packed.index_bytes) + " bytes is not 1 or 2";
  if (packed.joint_count < 1 || packed.joint_count > (packed.index_bytes == 1 ? 256 : 65536))
    return "joint count " + std::to_string(packed.joint_count) + " does not fit " +
           std::to_string(8 * packed.index_bytes) + "-bit indices";
  if (packed.vertex_count < 0) return "negative vertex count";
  const int n = packed.influences;
  const int words = packedWeightWords(n);
  const int stride = packedIndexStride(n, packed.index_bytes);
  if (packed.weight_words.size() != static_cast<size_t>(packed.vertex_count) * words)
    return "weight words hold " + std::to_string(packed.weight_words.size()) + " words, expected " +
           std::to_string(static_cast<size_t>(packed.vertex_count) * words);
  if (packed.indices.size() != static_cast<size_t>(packed.vertex_count) * stride)
    return "index records hold " + std::to_string(packed.indices.size()) + " bytes, expected " +
           std::to_string(static_cast<size_t>(packed.vertex_count) * stride);
  for (int v = 0; v < packed.vertex_count; ++v) {
    const std::string where = "vertex " + std::to_string(v) + ": ";
    for (int w = 0; w < words; ++w) {
      if (packed.weight_words[static_cast<size_t>(v) * words + w] & kReservedBitsMask)
        return where + "reserved bits 30-31 of weight word " + std::to_string(w) + " are not 0";
    }
    // N - 1 = 3, 6, 9 stored weights fill every field of every word, and any 10-bit field is a legal
    // weight on its own: only their sum can be out of range.
    int sum = 0;
    for (int k = 0; k < n - 1; ++k) sum += storedWeight(packed, v, k);
    if (sum > kMilliScale) return where + "stored weights sum to " + std::to_string(sum) + ", above 1000";
    for (int k = 0; k < n; ++k) {
      int index = storedIndex(packed, v, k);
      if (index >= packed.joint_count)
        return where + "slot " + std::to_string(k) + " names joint " + std::to_string(index) + " of " +
               std::to_string(packed.joint_count);
    }
    for (int b = n * packed.index_bytes; b < stride; ++b) {
      if (packed.indices[static_cast<size_t>(v) * stride + b] != 0)
        return where + "padding byte " + std::to_string(b) + " of the index record is not 0";
    }
  }
  return "";
}

QuantizedInfluences unpackInfluences(const PackedInfluences& packed) {
  std::string problem = packedInfluencesProblem(packed);
  if (!problem.empty()) fail(errc::INTERNAL, "", "unpackInfluences: " + problem);
  const int n = packed.influences;
  QuantizedInfluences out;
  out.slots_per_vertex = n;
  out.full_scale = kMilliScale;
  out.joints.resize(static_cast<size_t>(packed.vertex_count) * n);
  out.weights.resize(static_cast<size_t>(packed.vertex_count) * n);
  for (int v = 0; v < packed.vertex_count; ++v) {
    size_t base = static_cast<size_t>(v) * n;
    int sum = 0;
    for (int k = 0; k < n; ++k) {
      int weight = k < n - 1 ? storedWeight(packed, v, k) : kMilliScale - sum;
      sum += weight;
      out.weights[base + k] = static_cast<std::uint16_t>(weight);
      out.joints[base + k] = storedIndex(packed, v, k);
    }
  }
  return out;
}

std::vector<VertexAttributeData> packedGltfAttributes(const PackedInfluences& packed) {
  std::string problem = packedInfluencesProblem(packed);
  if (!problem.empty()) fail(errc::INTERNAL, "", "packedGltfAttributes: " + problem);
  const int words = packedWeightWords(packed.influences);
  std::vector<std::uint8_t> weight_bytes;
  weight_bytes.reserve(packed.weight_words.size() * 4);
  for (std::uint32_t word : packed.weight_words) {
    for (int b = 0; b < 4; ++b) weight_bytes.push_back(static_cast<std::uint8_t>((word >> (8 * b)) & 0xffu));
  }
  std::vector<VertexAttributeData> attributes;
  // VEC4 UNSIGNED_SHORT is the widest legal element: two words per weight attribute.
  appendChunks(weight_bytes, packed.vertex_count, 4 * words, 8, 2, "_RIGBAKE_PACKED_WEIGHTS_", &attributes);
  appendChunks(packed.indices, packed.vertex_count, packedIndexStride(packed.influences, packed.index_bytes),
               4 * packed.index_bytes, packed.index_bytes, "_RIGBAKE_PACKED_JOINTS_", &attributes);
  return attributes;
}

}  // namespace rigbake
