// Skin-data memory per vertex for the layouts the bake can emit, next to the packed layouts of the
// God of War Ragnarök talk ("Performance and Memory Difference" compared 4, 7 and 10 influences).
// `rigbake bake --stats` prints the table; nothing here allocates vertex data.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rigbake {

enum class SkinLayoutKind {
  kGltfStandard,  // JOINTS_n + WEIGHTS_n, 4 slots per set
  kPacked,        // docs/packed-influences.md: 10-bit weight words + 8/16-bit index records
  kTalkPacked32,  // the talk's Ragnarök 7/10 layout: the same weight words, 32-bit indices
};

struct SkinLayoutSize {
  std::string id;  // stable, e.g. "gltf-f32w-u16j-8", "packed-10-u8j"; tests and --stats JSON key on it
  SkinLayoutKind kind = SkinLayoutKind::kGltfStandard;
  int influences = 0;    // most influences per vertex the layout carries (glTF: its slot count)
  int weight_bytes = 0;  // per vertex
  int joint_bytes = 0;   // per vertex, padding included
  int bytes_per_vertex = 0;
  std::int64_t total_bytes = 0;  // bytes_per_vertex * vertex count
};

// glTF JOINTS_n/WEIGHTS_n for `slots` (a multiple of 4) with weight components of weight_component_bytes
// (4 FLOAT, 2 normalized UNSIGNED_SHORT, 1 normalized UNSIGNED_BYTE) and 1- or 2-byte joints.
int gltfSkinBytesPerVertex(int slots, int weight_component_bytes, int joint_component_bytes);
// packedWeightWords(influences) * 4 + packedIndexStride(influences, index_bytes); index_bytes 4 gives
// the talk's 32-bit indices.
int packedSkinBytesPerVertex(int influences, int index_bytes);

// Every row, in a fixed order: glTF FLOAT weights + u16 joints (4/8/12 slots); normalized u16 weights
// with u8 and with u16 joints (4/8/12); normalized u8 weights + u8 joints (4/8/12); packed 4/7/10 with
// 8- and 16-bit indices; the talk's 7/10 with 32-bit indices.
std::vector<SkinLayoutSize> skinMemoryTable(std::int64_t vertex_count);

}  // namespace rigbake
