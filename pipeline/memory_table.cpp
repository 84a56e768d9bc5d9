// Skin-data memory per vertex. Sources: glTF 2.0 3.7.3.3 (JOINTS_n/WEIGHTS_n are VEC4 sets; FLOAT or
// normalized UNSIGNED_BYTE/UNSIGNED_SHORT weights, UNSIGNED_BYTE/UNSIGNED_SHORT joints) and the God of War
// Ragnarök talk, "Increase Bone Influences per Vertex" (R10G10B10A2 weight word with 8/16-bit indices for
// 4 influences; 32-bit weight words and 32-bit indices for 7/10). The packed sizes come from the same
// functions the packer uses, so the table cannot drift from the bytes the bake writes.
#include "pipeline/memory_table.h"

#include "core/error.h"
#include "pipeline/pack_influences.h"

namespace rigbake {

int gltfSkinBytesPerVertex(int slots, int weight_component_bytes, int joint_component_bytes) {
  if (slots <= 0 || slots % 4 != 0) fail(errc::INTERNAL, "", "glTF skin slots come in sets of 4");
  return slots * (weight_component_bytes + joint_component_bytes);
}

int packedSkinBytesPerVertex(int influences, int index_bytes) {
  if (!isPackedInfluenceCount(influences)) fail(errc::INTERNAL, "", "packed layouts hold 4, 7 or 10 influences");
  if (index_bytes == 4) return packedWeightWords(influences) * 4 + influences * 4;
  return packedWeightWords(influences) * 4 + packedIndexStride(influences, index_bytes);
}

std::vector<SkinLayoutSize> skinMemoryTable(std::int64_t vertex_count) {
  if (vertex_count < 0) fail(errc::INTERNAL, "", "negative vertex count");
  std::vector<SkinLayoutSize> rows;
  auto add_gltf = [&](const std::string& weights_name, int weight_component, const std::string& joints_name,
                      int joint_component) {
    for (int slots : {4, 8, 12}) {
      SkinLayoutSize row;
      row.id = "gltf-" + weights_name + "w-" + joints_name + "j-" + std::to_string(slots);
      row.kind = SkinLayoutKind::kGltfStandard;
      row.influences = slots;
      row.weight_bytes = slots * weight_component;
      row.joint_bytes = slots * joint_component;
      row.bytes_per_vertex = gltfSkinBytesPerVertex(slots, weight_component, joint_component);
      rows.push_back(row);
    }
  };
  add_gltf("f32", 4, "u16", 2);
  add_gltf("u16n", 2, "u8", 1);
  add_gltf("u16n", 2, "u16", 2);
  add_gltf("u8n", 1, "u8", 1);
  for (int influences : {4, 7, 10}) {
    for (int index_bytes : {1, 2}) {
      SkinLayoutSize row;
      row.id = "packed-" + std::to_string(influences) + "-u" + std::to_string(8 * index_bytes) + "j";
      row.kind = SkinLayoutKind::kPacked;
      row.influences = influences;
      row.weight_bytes = packedWeightWords(influences) * 4;
      row.joint_bytes = packedIndexStride(influences, index_bytes);
      row.bytes_per_vertex = packedSkinBytesPerVertex(influences, index_bytes);
      rows.push_back(row);
    }
  }
  for (int influences : {7, 10}) {
    SkinLayoutSize row;
    row.id = "talk-" + std::to_string(influences) + "-u32j";
    row.kind = SkinLayoutKind::kTalkPacked32;
    row.influences = influences;
    row.weight_bytes = packedWeightWords(influences) * 4;
    row.joint_bytes = influences * 4;
    row.bytes_per_vertex = packedSkinBytesPerVertex(influences, 4);
    rows.push_back(row);
  }
  for (SkinLayoutSize& row : rows) row.total_bytes = static_cast<std::int64_t>(row.bytes_per_vertex) * vertex_count;
  return rows;
}

}  // namespace rigbake
