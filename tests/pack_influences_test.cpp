#include "pipeline/pack_influences.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "external_tools.h"
#include "formats/atomic_file.h"
#include "formats/packed_file.h"
#include "influence_fixtures.h"
#include "pipeline/memory_table.h"

using namespace rigbake;

namespace {


std::string errorCodeOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.code();
  }
  return "";
}

// The worked example of docs/packed-influences.md: 7 influences, 8-bit indices.
QuantizedInfluences workedExample() {
  QuantizedInfluences q;
  q.slots_per_vertex = 7;
  q.joints = {12, 3, 13, 4, 11, 2, 14};
  q.weights = {412, 250, 141, 97, 60, 28, 12};
  return q;
}

bool samePacked(const PackedInfluences& a, const PackedInfluences& b) {
  return a.influences == b.influences && a.index_bytes == b.index_bytes && a.joint_count == b.joint_count &&
         a.vertex_count == b.vertex_count && a.weight_words == b.weight_words && a.indices == b.indices;
}

// Real joints spread over a 300-joint index space, so 16-bit indices carry values above 255.
QuantizedInfluences spreadJoints(QuantizedInfluences q) {
  for (size_t i = 0; i < q.joints.size(); ++i) {
    if (q.weights[i] > 0) q.joints[i] = q.joints[i] * 5 + 47;
  }
  return q;
}

std::string temporaryDirectory() {
  std::string pattern = "/tmp/rigbake-pack-test-XXXXXX";
  char* made = mkdtemp(pattern.data());
  REQUIRE(made != nullptr);
  return pattern;
}

}  // namespace

TEST_CASE("layout sizes follow the talk: 10-bit weights three to a word, indices padded to 4 bytes") {
  CHECK(packedWeightWords(4) == 1);
  CHECK(packedWeightWords(7) == 2);
  CHECK(packedWeightWords(10) == 3);
  CHECK(packedIndexStride(4, 1) == 4);
  CHECK(packedIndexStride(7, 1) == 8);
  CHECK(packedIndexStride(10, 1) == 12);
  CHECK(packedIndexStride(4, 2) == 8);
  CHECK(packedIndexStride(7, 2) == 16);
  CHECK(packedIndexStride(10, 2) == 20);
  CHECK(packedIndexBytesFor(1) == 1);
  CHECK(packedIndexBytesFor(256) == 1);
  CHECK(packedIndexBytesFor(257) == 2);
  CHECK(packedIndexBytesFor(65536) == 2);
  CHECK(errorCodeOf([] { packedIndexBytesFor(65537); }) == "INTERNAL");
}

TEST_CASE("the worked example packs to the documented bits") {
  PackedInfluences packed = packInfluences(workedExample(), 15, 1);
  // word 0 = 412 | 250 << 10 | 141 << 20, word 1 = 97 | 60 << 10 | 28 << 20; weight 12 is rebuilt.
  CHECK(packed.weight_words == std::vector<std::uint32_t>{0x08D3E99Cu, 0x01C0F061u});
  CHECK(packed.indices == std::vector<std::uint8_t>{12, 3, 13, 4, 11, 2, 14, 0});
  QuantizedInfluences back = unpackInfluences(packed);
  CHECK(back.joints == workedExample().joints);
  CHECK(back.weights == workedExample().weights);

  QuantizedInfluences four;
  four.slots_per_vertex = 4;
  four.joints = {7, 8, 2, 9};
  four.weights = {500, 300, 150, 50};
  PackedInfluences packed4 = packInfluences(four, 300, 2);
  CHECK(packed4.weight_words == std::vector<std::uint32_t>{0x0964B1F4u});
  CHECK(packed4.indices == std::vector<std::uint8_t>{7, 0, 8, 0, 2, 0, 9, 0});
}

TEST_CASE("pack rejects input outside its contract") {
  QuantizedInfluences q = workedExample();
  CHECK(errorCodeOf([&] { packInfluences(q, 14, 1); }) == "INTERNAL");   // joint 14 of 14
  CHECK(errorCodeOf([&] { packInfluences(q, 300, 1); }) == "INTERNAL");  // 300 joints in 8 bits
  CHECK(errorCodeOf([&] { packInfluences(q, 15, 3); }) == "INTERNAL");
  QuantizedInfluences eight = q;
  eight.slots_per_vertex = 8;
  eight.joints.push_back(0);
  eight.weights.push_back(0);
  CHECK(errorCodeOf([&] { packInfluences(eight, 15, 1); }) == "INTERNAL");
  QuantizedInfluences bytes = requantizeInfluences(q, kUnsignedByteScale);
  CHECK(errorCodeOf([&] { packInfluences(bytes, 15, 1); }) == "INTERNAL");
  QuantizedInfluences short_sum = q;
  short_sum.weights[0] -= 1;
  CHECK(errorCodeOf([&] { packInfluences(short_sum, 15, 1); }) == "INTERNAL");
}

TEST_CASE("decode(pack(w)) is the 0.001 weights exactly, on every vertex, at 4, 7, 10 and both index widths", "[shared:asset-influences]") {
  int parts_checked = 0;
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    for (const test::PartInfluences& part : asset.parts) {
      for (const InfluenceSet* input : {&part.real, &part.wide}) {
        for (int budget : kPackedInfluenceCounts) {
          QuantizedInfluences q = quantizeInfluences(pruneInfluences(*input, budget));
          for (int index_bytes : {1, 2}) {
            INFO(part.name << (input == &part.wide ? " (widened)" : "") << " N=" << budget << " index bytes "
                           << index_bytes);
            QuantizedInfluences source = index_bytes == 2 ? spreadJoints(q) : q;
            const int joint_count = index_bytes == 2 ? 300 : asset.skeleton.size();
            PackedInfluences packed = packInfluences(source, joint_count, index_bytes);
            CHECK(packedInfluencesProblem(packed).empty());
            CHECK(packed.vertex_count == q.vertexCount());
            CHECK(packed.weight_words.size() ==
                  static_cast<size_t>(q.vertexCount()) * packedWeightWords(budget));
            CHECK(packed.indices.size() ==
                  static_cast<size_t>(q.vertexCount()) * packedIndexStride(budget, index_bytes));
            QuantizedInfluences back = unpackInfluences(packed);
            CHECK(back.slots_per_vertex == budget);
            CHECK(back.full_scale == 1000);
            // Whole-array equality: every joint and every weight of every vertex, rebuilt last slot included.
            CHECK(back.joints == source.joints);
            CHECK(back.weights == source.weights);
            ++parts_checked;
          }
        }
      }
    }
  }
  if (!test::assetInfluences().empty()) CHECK(parts_checked > 0);
}

TEST_CASE("the glTF carrier is legal custom attributes that hold the packed bytes unchanged", "[shared:asset-influences]") {
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    for (const test::PartInfluences& part : asset.parts) {
      for (int budget : kPackedInfluenceCounts) {
        QuantizedInfluences q = quantizeInfluences(pruneInfluences(part.wide, budget));
        for (int index_bytes : {1, 2}) {
          INFO(part.name << " N=" << budget << " index bytes " << index_bytes);
          QuantizedInfluences source = index_bytes == 2 ? spreadJoints(q) : q;
          PackedInfluences packed = packInfluences(source, index_bytes == 2 ? 300 : asset.skeleton.size(), index_bytes);
          std::vector<VertexAttributeData> attributes = packedGltfAttributes(packed);
          const int vertices = packed.vertex_count;
          std::vector<std::vector<std::uint8_t>> weight_chunks, joint_chunks;
          size_t element_bytes_total = 0;
          for (const VertexAttributeData& attribute : attributes) {
            const AccessorDescription& accessor = attribute.accessor;
            // glTF 2.0 3.7.2.1: an application-specific semantic starts with "_" and is never UNSIGNED_INT.
            CHECK(attribute.semantic.rfind("_RIGBAKE_PACKED_", 0) == 0);
            CHECK((accessor.component_type == kGltfUnsignedByte || accessor.component_type == kGltfUnsignedShort));
            CHECK_FALSE(accessor.normalized);
            CHECK(accessor.count == vertices);
            int components = accessor.type == "VEC4" ? 4 : accessor.type == "VEC2" ? 2 : 0;
            REQUIRE(components > 0);
            int element = components * (accessor.component_type == kGltfUnsignedByte ? 1 : 2);
            CHECK(element % 4 == 0);  // vertex attributes are 4-byte aligned
            CHECK(attribute.bytes.size() == static_cast<size_t>(vertices) * element);
            element_bytes_total += element;
            if (attribute.semantic.rfind("_RIGBAKE_PACKED_WEIGHTS_", 0) == 0) {
              CHECK(accessor.component_type == kGltfUnsignedShort);
              CHECK(attribute.semantic == "_RIGBAKE_PACKED_WEIGHTS_" + std::to_string(weight_chunks.size()));
              weight_chunks.push_back(attribute.bytes);
            } else {
              CHECK(attribute.semantic == "_RIGBAKE_PACKED_JOINTS_" + std::to_string(joint_chunks.size()));
              CHECK(accessor.component_type == (index_bytes == 1 ? kGltfUnsignedByte : kGltfUnsignedShort));
              joint_chunks.push_back(attribute.bytes);
            }
          }
          CHECK(weight_chunks.size() == (budget == 10 ? 2u : 1u));
          CHECK(joint_chunks.size() == static_cast<size_t>(index_bytes == 1 ? packedIndexStride(budget, 1) / 4
                                                                            : (packedIndexStride(budget, 2) + 7) / 8));
          CHECK(element_bytes_total == static_cast<size_t>(packedSkinBytesPerVertex(budget, index_bytes)));
          // Interleave the chunks back per vertex: the u16 pairs rebuild every word, the index pieces
          // every record.
          std::vector<std::uint32_t> words;
          std::vector<std::uint8_t> records;
          for (int v = 0; v < vertices; ++v) {
            for (const std::vector<std::uint8_t>& chunk : weight_chunks) {
              size_t element = chunk.size() / vertices;
              for (size_t w = 0; w < element / 4; ++w) {
                const std::uint8_t* b = &chunk[v * element + 4 * w];
                std::uint32_t low = b[0] | (b[1] << 8), high = b[2] | (b[3] << 8);
                words.push_back(low | (high << 16));
              }
            }
            for (const std::vector<std::uint8_t>& chunk : joint_chunks) {
              size_t element = chunk.size() / vertices;
              records.insert(records.end(), chunk.begin() + v * element, chunk.begin() + (v + 1) * element);
            }
          }
          CHECK(words == packed.weight_words);
          CHECK(records == packed.indices);
        }
      }
    }
  }
}

TEST_CASE("the packed file round-trips, is deterministic and refuses damaged bytes", "[shared:asset-influences]") {
  std::vector<PackedInfluences> parts;
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    if (asset.asset != "Quaternius_ModularWomen_Soldier.glb") continue;
    for (const test::PartInfluences& part : asset.parts)
      parts.push_back(packInfluences(quantizeInfluences(pruneInfluences(part.wide, 10)), asset.skeleton.size(), 1));
  }
  if (parts.empty()) {
    // Outside CI without the assets: the worked example still exercises the format.
    parts.push_back(packInfluences(workedExample(), 15, 1));
    parts.push_back(packInfluences(workedExample(), 15, 1));
  }
  const std::string bytes = encodePackedFile(parts);
  CHECK(encodePackedFile(parts) == bytes);
  std::vector<PackedInfluences> back = decodePackedFile(bytes, "memory");
  REQUIRE(back.size() == parts.size());
  for (size_t p = 0; p < parts.size(); ++p) CHECK(samePacked(back[p], parts[p]));

  const std::string dir = temporaryDirectory();
  const std::string path = dir + "/influences.rbpi";
  writePackedFile(path, parts);
  CHECK(readFile(path) == bytes);
  std::vector<PackedInfluences> from_disk = readPackedFile(path);
  REQUIRE(from_disk.size() == parts.size());
  for (size_t p = 0; p < parts.size(); ++p) CHECK(samePacked(from_disk[p], parts[p]));
  std::remove(path.c_str());
  // A failed write leaves nothing behind.
  CHECK(errorCodeOf([&] { writePackedFile(dir + "/missing/influences.rbpi", parts); }) == "IO_WRITE_FAILED");
  CHECK_FALSE(test::fileExists(dir + "/missing/influences.rbpi"));
  rmdir(dir.c_str());

  // A small file: every truncation fails cleanly.
  std::vector<PackedInfluences> small = {packInfluences(workedExample(), 15, 1)};
  const std::string small_bytes = encodePackedFile(small);
  CHECK(small_bytes.size() == 32u + 4u + 8u + 8u);
  for (size_t length = 0; length < small_bytes.size(); ++length) {
    INFO("truncated to " << length);
    CHECK(errorCodeOf([&] { decodePackedFile(small_bytes.substr(0, length), "cut"); }) == "PACKED_FILE_INVALID");
  }
  CHECK(errorCodeOf([&] { decodePackedFile(small_bytes + std::string(4, '\0'), "long"); }) == "PACKED_FILE_INVALID");
  auto damaged = [&](size_t offset, unsigned char value) {
    std::string copy = small_bytes;
    copy[offset] = static_cast<char>(value);
    return errorCodeOf([&] { decodePackedFile(copy, "damaged"); });
  };
  CHECK(damaged(0, 'X') == "PACKED_FILE_INVALID");   // magic
  CHECK(damaged(4, 2) == "PACKED_FILE_INVALID");     // version
  CHECK(damaged(6, 5) == "PACKED_FILE_INVALID");     // influence count
  CHECK(damaged(7, 4) == "PACKED_FILE_INVALID");     // index width
  CHECK(damaged(8, 12) == "PACKED_FILE_INVALID");    // joint count below the largest index (14)
  CHECK(damaged(28, 1) == "PACKED_FILE_INVALID");    // reserved header field
  CHECK(damaged(39, 0x48) == "PACKED_FILE_INVALID");  // reserved bits 30-31 of word 0
  CHECK(damaged(36, 0xFF) == "PACKED_FILE_INVALID");  // stored weights above 1000
  CHECK(damaged(51, 1) == "PACKED_FILE_INVALID");    // padding byte of the index record
  CHECK(damaged(44, 15) == "PACKED_FILE_INVALID");   // index 15 of 15 joints
  CHECK(damaged(45, 0) == "");                       // index 0 is a legal joint
  CHECK(errorCodeOf([&] { encodePackedFile({}); }) == "INTERNAL");
  std::vector<PackedInfluences> mixed = {small[0], packInfluences(workedExample(), 16, 1)};
  CHECK(errorCodeOf([&] { encodePackedFile(mixed); }) == "INTERNAL");
}

TEST_CASE("the header is laid out as docs/packed-influences.md says") {
  std::vector<PackedInfluences> parts = {packInfluences(workedExample(), 15, 1)};
  const std::string bytes = encodePackedFile(parts);
  auto u8 = [&](size_t offset) { return static_cast<unsigned>(static_cast<unsigned char>(bytes[offset])); };
  auto u32 = [&](size_t offset) { return u8(offset) | u8(offset + 1) << 8 | u8(offset + 2) << 16 | u8(offset + 3) << 24; };
  CHECK(bytes.substr(0, 4) == "RBPI");
  CHECK((u8(4) | u8(5) << 8) == 1u);  // version
  CHECK(u8(6) == 7u);                  // influences
  CHECK(u8(7) == 1u);                  // index bytes
  CHECK(u32(8) == 15u);                // joint count
  CHECK(u32(12) == 1u);                // part count
  CHECK(u32(16) == 1u);                // vertex count
  CHECK(u32(20) == 2u);                // weight words per vertex
  CHECK(u32(24) == 8u);                // index stride
  CHECK(u32(28) == 0u);                // reserved
  CHECK(u32(32) == 1u);                // part 0 vertex count
  CHECK(u32(36) == 0x08D3E99Cu);       // weight section
  CHECK(u32(40) == 0x01C0F061u);
  CHECK(bytes.substr(44) == std::string("\x0C\x03\x0D\x04\x0B\x02\x0E\x00", 8));
}

TEST_CASE("memory table bytes per vertex, derived by hand") {
  // glTF: slots * (weight component + joint component). Packed: 4 * ceil((N-1)/3) weight bytes plus
  // N indices rounded up to 4 bytes. The talk's 7/10: the same words plus 4-byte indices.
  const std::map<std::string, int> expected = {
      {"gltf-f32w-u16j-4", 24},  {"gltf-f32w-u16j-8", 48},  {"gltf-f32w-u16j-12", 72},
      {"gltf-u16nw-u8j-4", 12},  {"gltf-u16nw-u8j-8", 24},  {"gltf-u16nw-u8j-12", 36},
      {"gltf-u16nw-u16j-4", 16}, {"gltf-u16nw-u16j-8", 32}, {"gltf-u16nw-u16j-12", 48},
      {"gltf-u8nw-u8j-4", 8},    {"gltf-u8nw-u8j-8", 16},   {"gltf-u8nw-u8j-12", 24},
      {"packed-4-u8j", 8},       {"packed-4-u16j", 12},     {"packed-7-u8j", 16},
      {"packed-7-u16j", 24},     {"packed-10-u8j", 24},     {"packed-10-u16j", 32},
      {"talk-7-u32j", 36},       {"talk-10-u32j", 52},
  };
  const std::int64_t vertices = 36431;
  std::vector<SkinLayoutSize> table = skinMemoryTable(vertices);
  REQUIRE(table.size() == expected.size());
  for (const SkinLayoutSize& row : table) {
    INFO(row.id);
    REQUIRE(expected.count(row.id) == 1);
    CHECK(row.bytes_per_vertex == expected.at(row.id));
    CHECK(row.weight_bytes + row.joint_bytes == row.bytes_per_vertex);
    CHECK(row.total_bytes == expected.at(row.id) * vertices);
  }
  CHECK(table.front().id == "gltf-f32w-u16j-4");
  CHECK(table.back().id == "talk-10-u32j");
  // The table agrees with the bytes the bake really produces for a vertex.
  QuantizedInfluences q = workedExample();
  for (int index_bytes : {1, 2}) {
    PackedInfluences packed = packInfluences(q, 15, index_bytes);
    CHECK(static_cast<int>(packed.weight_words.size() * 4 + packed.indices.size()) ==
          packedSkinBytesPerVertex(7, index_bytes));
  }
  size_t standard_bytes = 0;
  for (const VertexAttributeData& attribute : standardSkinAttributes(q, 15, WeightStorage::kUnsignedShort))
    standard_bytes += attribute.bytes.size();
  CHECK(static_cast<int>(standard_bytes) == gltfSkinBytesPerVertex(8, 2, 1));
}

namespace {

// A minimal skinned glTF around one mesh part's vertices (drawn as points, so no index buffer), its
// skeleton as the skin, and `attributes` on the primitive: what a writer would emit, for the Khronos
// validator to judge the accessor data.
void writeSkinnedGltf(const std::string& dir, const Skeleton& skeleton, const std::vector<Eigen::Vector3d>& positions,
                      const std::vector<VertexAttributeData>& attributes) {
  using nlohmann::json;
  std::string bin;
  json accessors = json::array(), views = json::array(), primitive_attributes = json::object();
  auto add_view = [&](const std::string& bytes) {
    while (bin.size() % 4 != 0) bin.push_back('\0');
    views.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}, {"target", 34962}});
    bin += bytes;
    return views.size() - 1;
  };
  std::string position_bytes;
  Eigen::Vector3f low = Eigen::Vector3f::Constant(1e30f), high = Eigen::Vector3f::Constant(-1e30f);
  for (const Eigen::Vector3d& p : positions) {
    Eigen::Vector3f f = p.cast<float>();
    low = low.cwiseMin(f);
    high = high.cwiseMax(f);
    position_bytes.append(reinterpret_cast<const char*>(f.data()), 12);
  }
  accessors.push_back({{"bufferView", add_view(position_bytes)}, {"componentType", 5126}, {"type", "VEC3"},
                       {"count", positions.size()}, {"min", {low.x(), low.y(), low.z()}},
                       {"max", {high.x(), high.y(), high.z()}}});
  primitive_attributes["POSITION"] = 0;
  for (const VertexAttributeData& attribute : attributes) {
    json accessor = {{"bufferView", add_view(std::string(attribute.bytes.begin(), attribute.bytes.end()))},
                     {"componentType", attribute.accessor.component_type},
                     {"type", attribute.accessor.type},
                     {"count", attribute.accessor.count}};
    if (attribute.accessor.normalized) accessor["normalized"] = true;
    primitive_attributes[attribute.semantic] = accessors.size();
    accessors.push_back(accessor);
  }
  // Node 0 is a plain root above the skeleton's roots, node 1 + j is joint j, the last node the mesh.
  json nodes = json::array({{{"name", "armature"}, {"children", json::array()}}});
  json skin_joints = json::array();
  for (int j = 0; j < skeleton.size(); ++j) {
    nodes.push_back({{"name", skeleton.names[j]}});
    skin_joints.push_back(1 + j);
  }
  for (int j = 0; j < skeleton.size(); ++j) {
    int parent = skeleton.parents[j];
    json& parent_node = parent < 0 ? nodes[0] : nodes[1 + parent];
    parent_node["children"].push_back(1 + j);
  }
  nodes.push_back({{"name", "skinned"}, {"mesh", 0}, {"skin", 0}});
  json gltf = {{"asset", {{"version", "2.0"}, {"generator", "rigbake pack_influences_test"}}},
               {"scene", 0},
               {"scenes", {{{"nodes", {0, nodes.size() - 1}}}}},
               {"nodes", nodes},
               {"skins", {{{"joints", skin_joints}}}},
               {"meshes", {{{"primitives", {{{"attributes", primitive_attributes}, {"mode", 0}}}}}}},
               {"accessors", accessors},
               {"bufferViews", views},
               {"buffers", {{{"uri", "skin.bin"}, {"byteLength", bin.size()}}}}};
  // The test's own input, not a rigbake output: written plainly, so that the suite's validator pass
  // over rigbake's outputs (RIGBAKE_KEEP_OUTPUTS) does not take it for one (its buffer is a file beside it).
  std::ofstream(dir + "/skin.bin", std::ios::binary) << bin;
  std::ofstream(dir + "/skin.gltf", std::ios::binary) << gltf.dump(1);
}

}  // namespace

TEST_CASE("the Khronos validator accepts the standard and the packed attributes on real meshes") {
  namespace ext = test::external;
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  int files = 0;
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    if (asset.parts.empty()) continue;
    // The largest part of each asset, widened so 10 influences fill three JOINTS_n/WEIGHTS_n sets.
    const test::PartInfluences* part = &asset.parts.front();
    for (const test::PartInfluences& candidate : asset.parts) {
      if (candidate.positions.size() > part->positions.size()) part = &candidate;
    }
    for (int budget : kPackedInfluenceCounts) {
      for (WeightStorage storage : {WeightStorage::kUnsignedByte, WeightStorage::kUnsignedShort}) {
        INFO(part->name << " N=" << budget << (storage == WeightStorage::kUnsignedByte ? " u8" : " u16"));
        QuantizedInfluences q = quantizeInfluences(pruneInfluences(part->wide, budget));
        std::vector<VertexAttributeData> attributes = standardSkinAttributes(q, asset.skeleton.size(), storage);
        for (VertexAttributeData& packed :
             packedGltfAttributes(packInfluences(q, asset.skeleton.size(), packedIndexBytesFor(asset.skeleton.size()))))
          attributes.push_back(std::move(packed));
        ext::ScratchDir dir;
        REQUIRE_FALSE(dir.path().empty());
        writeSkinnedGltf(dir.path(), asset.skeleton, part->positions, attributes);
        ext::ValidationSummary report = ext::validateWithKhronos(dir.file("skin.gltf"));
        INFO(report.raw);
        CHECK(report.exit_code == 0);
        CHECK(report.errors == 0);
        CHECK(report.warnings == 0);
        ++files;
      }
    }
  }
  if (!test::assetInfluences().empty()) CHECK(files > 0);
}

TEST_CASE("the GLSL decoder compiles as GLSL 4.50 and as Vulkan SPIR-V") {
  const bool have_validator = std::system("command -v glslangValidator > /dev/null 2>&1") == 0;
  const char* ci = std::getenv("CI");
  if (!have_validator) {
    // scripts/deps-apt.txt installs glslang-tools; CI must have it.
    if (ci && std::string(ci) == "true") FAIL("glslangValidator missing under CI (apt package glslang-tools)");
    WARN("glslangValidator not installed; GLSL compile check skipped outside CI");
    return;
  }
  const std::string library = readFile(test::sourceDir() + "/formats/shaders/unpack_influences.glsl");
  // A vertex shader that skins through every decoder: the glTF carrier for 10 and 7 influences, the
  // R10G10B10A2_UNORM fetch for 4, and 8/16-bit index records read from a storage buffer.
  const std::string shader = "#version 450\n" + library + R"(
layout(location = 0) in vec3 position;
layout(location = 1) in uvec4 packed_weights_0;
layout(location = 2) in uvec2 packed_weights_1;
layout(location = 3) in uvec4 packed_joints_0;
layout(location = 4) in uvec4 packed_joints_1;
layout(location = 5) in uvec4 packed_joints_2;
layout(location = 6) in vec4 unorm_weights;
layout(location = 7) in uint record_word_index;
layout(std430, binding = 0) readonly buffer Palette { mat4 skin[]; };
layout(std430, binding = 1) readonly buffer Records { uint index_words[]; };
void main() {
  uvec3 words = uvec3(rigbakeWordFromShorts(packed_weights_0.xy), rigbakeWordFromShorts(packed_weights_0.zw),
                      rigbakeWordFromShorts(packed_weights_1));
  float w10[10];
  rigbakeUnpackWeights10(words, w10);
  float w7[7];
  rigbakeUnpackWeights7(words.xy, w7);
  vec4 w4 = rigbakeUnpackWeights4(words.x) + rigbakeUnpackWeights4Unorm(unorm_weights);
  uint joints[10] = uint[10](packed_joints_0.x, packed_joints_0.y, packed_joints_0.z, packed_joints_0.w,
                             packed_joints_1.x, packed_joints_1.y, packed_joints_1.z, packed_joints_1.w,
                             packed_joints_2.x, packed_joints_2.y);
  mat4 m = mat4(0.0);
  for (int k = 0; k < 10; ++k) m += w10[k] * skin[joints[k]];
  for (int k = 0; k < 7; ++k)
    m += w7[k] * skin[rigbakeJointIndex8(index_words[record_word_index + uint(k) / 4u], uint(k))];
  for (int k = 0; k < 4; ++k)
    m += w4[k] * skin[rigbakeJointIndex16(index_words[record_word_index + uint(k) / 2u], uint(k))];
  gl_Position = m * vec4(position, 1.0);
}
)";
  const std::string dir = temporaryDirectory();
  const std::string path = dir + "/skin.vert";
  writeFileAtomically(path, shader);
  const std::string log = dir + "/log.txt";
  int opengl = std::system(("glslangValidator " + path + " > " + log + " 2>&1").c_str());
  std::string opengl_log = readFile(log);
  int vulkan = std::system(("glslangValidator -V " + path + " -o " + dir + "/skin.spv > " + log + " 2>&1").c_str());
  std::string vulkan_log = readFile(log);
  std::remove(path.c_str());
  std::remove(log.c_str());
  std::remove((dir + "/skin.spv").c_str());
  rmdir(dir.c_str());
  INFO(opengl_log);
  CHECK(opengl == 0);
  INFO(vulkan_log);
  CHECK(vulkan == 0);
}
