#include "formats/gltf_write.h"

#include <tiny_gltf.h>

#include <cstring>
#include <fstream>
#include <set>

#include "core/error.h"
#include "external_tools.h"
#include "formats/atomic_file.h"
#include "formats/gltf_document.h"
#include "formats/sample_gltf.h"
#include "sample/sample_character.h"
#include "test_support.h"
#include "glb_support.h"

using namespace rigbake;
namespace ext = rigbake::test::external;

namespace {

// A 2x2 RGB PNG, small enough to inline and valid enough for the validator to read its header.
const std::vector<unsigned char>& tinyPng() {
  static const std::vector<unsigned char> kPng = {
      0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
      0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0xfd, 0xd4, 0x9a, 0x73, 0x00, 0x00, 0x00, 0x12, 0x49,
      0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8, 0xcf, 0xc0, 0xc0, 0x00, 0xc2, 0x0c, 0xff, 0x81, 0x00, 0x00, 0x1f, 0xee,
      0x05, 0xfb, 0xf1, 0xab, 0xba, 0x77, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
  return kPng;
}

uint32_t readU32(const std::string& bytes, size_t at) {
  uint32_t value = 0;
  std::memcpy(&value, bytes.data() + at, 4);  // GLB is little-endian, as is every target we build for
  return value;
}

tinygltf::Model smallSampleModel(SampleVrm vrm = SampleVrm::kNone) {
  SampleOptions options;
  options.target_vertices = kMinSampleVertices;
  options.vrm = vrm;
  return sampleToGltf(makeSampleCharacter(options));
}

std::set<std::string> asSet(const std::vector<std::string>& items) { return {items.begin(), items.end()}; }

// Skeleton, meshes, clips and images of two loads of the same content agree.
void requireSameCharacter(const LoadedCharacter& a, const LoadedCharacter& b) {
  const Character& x = a.character;
  const Character& y = b.character;
  REQUIRE(x.skeleton.size() == y.skeleton.size());
  for (int j = 0; j < x.skeleton.size(); ++j) {
    CHECK(x.skeleton.names[j] == y.skeleton.names[j]);
    CHECK(x.skeleton.parents[j] == y.skeleton.parents[j]);
    CHECK(x.skeleton.bind_world[j].isApprox(y.skeleton.bind_world[j], 1e-9));
  }
  REQUIRE(x.meshes.size() == y.meshes.size());
  for (size_t m = 0; m < x.meshes.size(); ++m) {
    INFO("mesh part " << m);
    CHECK(x.meshes[m].name == y.meshes[m].name);
    CHECK(x.meshes[m].positions == y.meshes[m].positions);
    CHECK(x.meshes[m].triangles == y.meshes[m].triangles);
    CHECK(x.meshes[m].joints == y.meshes[m].joints);
    CHECK(x.meshes[m].weights == y.meshes[m].weights);
  }
  REQUIRE(x.clips.size() == y.clips.size());
  for (size_t c = 0; c < x.clips.size(); ++c) {
    CHECK(x.clips[c].name == y.clips[c].name);
    CHECK(x.clips[c].tracks.size() == y.clips[c].tracks.size());
    CHECK(x.clips[c].duration == y.clips[c].duration);
  }
  CHECK(x.vrm_version == y.vrm_version);
  CHECK(x.vrm_humanoid == y.vrm_humanoid);
  const tinygltf::Model& mx = modelOf(*a.document);
  const tinygltf::Model& my = modelOf(*b.document);
  CHECK(mx.materials.size() == my.materials.size());
  CHECK(mx.textures.size() == my.textures.size());
  REQUIRE(mx.images.size() == my.images.size());
  for (size_t i = 0; i < mx.images.size(); ++i) CHECK(mx.images[i].image == my.images[i].image);
}

}  // namespace

TEST_CASE("serialization is byte-deterministic") {
  for (bool binary : {true, false}) {
    INFO((binary ? "GLB" : "glTF"));
    // Two independent generations, not one model written twice.
    std::string first = serializeGltf(sampleToGltf(makeSampleCharacter({})), binary);
    std::string second = serializeGltf(sampleToGltf(makeSampleCharacter({})), binary);
    CHECK(first.size() > 100000);
    CHECK(first == second);
  }
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  tinygltf::Model model = smallSampleModel(SampleVrm::kVrm1);
  writeGltf(model, dir.file("a.vrm"));
  writeGltf(model, dir.file("b.vrm"));
  CHECK(readFile(dir.file("a.vrm")) == readFile(dir.file("b.vrm")));
  CHECK(readFile(dir.file("a.vrm")) == serializeGltf(model, true));
}

TEST_CASE("empty objects and arrays in extensions and extras are written as {} and [], never null") {
  // tinygltf 2.7 alone writes each of these as null (a VRM 0.x avatar's "floatProperties": {}).
  tinygltf::Model model = smallSampleModel(SampleVrm::kNone);
  tinygltf::Value::Object nested;
  nested["floatProperties"] = tinygltf::Value(tinygltf::Value::Object{});
  nested["boneGroups"] = tinygltf::Value(tinygltf::Value::Array{});
  nested["deeper"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(tinygltf::Value::Object{}), tinygltf::Value(1.5)});
  model.extensions["EXT_test_empty"] = tinygltf::Value(nested);
  model.nodes[0].extras = tinygltf::Value(nested);
  model.materials[0].pbrMetallicRoughness.extras = tinygltf::Value(nested);
  for (bool binary : {true, false}) {
    INFO((binary ? "GLB" : "glTF"));
    const std::string bytes = serializeGltf(model, binary);
    const nlohmann::json json = binary ? glbJson(bytes) : nlohmann::json::parse(bytes);
    for (const nlohmann::json* value : {&json["extensions"]["EXT_test_empty"], &json["nodes"][0]["extras"],
                                        &json["materials"][0]["pbrMetallicRoughness"]["extras"]}) {
      CHECK((*value)["floatProperties"] == nlohmann::json::object());
      CHECK((*value)["boneGroups"] == nlohmann::json::array());
      CHECK((*value)["deeper"] == nlohmann::json::parse("[{}, 1.5]"));
    }
    CHECK(bytes.find("rigbake:empty-") == std::string::npos);
  }
}

TEST_CASE("GLB output is one well-formed container with one BIN chunk") {
  tinygltf::Model model = smallSampleModel();
  std::string glb = serializeGltf(model, true);
  REQUIRE(glb.size() >= 28);
  CHECK(glb.compare(0, 4, "glTF") == 0);
  CHECK(readU32(glb, 4) == 2);
  CHECK(readU32(glb, 8) == glb.size());
  uint32_t json_length = readU32(glb, 12);
  CHECK(readU32(glb, 16) == 0x4E4F534Au);  // "JSON"
  CHECK(json_length % 4 == 0);
  size_t bin_header = 20 + json_length;
  REQUIRE(bin_header + 8 <= glb.size());
  uint32_t bin_length = readU32(glb, bin_header);
  CHECK(readU32(glb, bin_header + 4) == 0x004E4942u);  // "BIN\0"
  CHECK(bin_length % 4 == 0);
  CHECK(bin_header + 8 + bin_length == glb.size());
  nlohmann::json json = test::glbJson(glb);
  REQUIRE(json["buffers"].size() == 1);
  CHECK_FALSE(json["buffers"][0].contains("uri"));
  CHECK(json["buffers"][0]["byteLength"].get<size_t>() <= bin_length);
  CHECK(json["buffers"][0]["byteLength"].get<size_t>() + 3 >= bin_length);

  nlohmann::json gltf = nlohmann::json::parse(serializeGltf(model, false));
  REQUIRE(gltf["buffers"].size() == 1);
  CHECK(gltf["buffers"][0]["uri"].get<std::string>().rfind("data:application/octet-stream;base64,", 0) == 0);
  CHECK(isBinaryGltfPath("x/out.GLB"));
  CHECK(isBinaryGltfPath("avatar.vrm"));
  CHECK_FALSE(isBinaryGltfPath("out.gltf"));
}

TEST_CASE("several buffers, external and data-URI images are merged into one stand-alone buffer") {
  tinygltf::Model model = smallSampleModel();
  // Move every other buffer view into a second buffer, at an offset that is 2 modulo 4.
  tinygltf::Buffer second;
  second.data = {0, 0};
  for (size_t v = 1; v < model.bufferViews.size(); v += 2) {
    tinygltf::BufferView& view = model.bufferViews[v];
    while (second.data.size() % 4 != view.byteOffset % 4) second.data.push_back(0);
    const unsigned char* from = model.buffers[0].data.data() + view.byteOffset;
    view.byteOffset = second.data.size();
    second.data.insert(second.data.end(), from, from + view.byteLength);
    view.buffer = 1;
  }
  model.buffers.push_back(second);
  // As the loader leaves them: an external file, a decoded data: URI, and a buffer-view image.
  tinygltf::Image external;
  external.uri = "textures/skin.png";
  external.image = tinyPng();
  external.as_is = true;
  tinygltf::Image data_uri;
  data_uri.mimeType = "image/png";
  data_uri.image = tinyPng();
  data_uri.as_is = true;
  tinygltf::BufferView png_view;
  png_view.buffer = 1;
  png_view.byteOffset = second.data.size();
  png_view.byteLength = tinyPng().size();
  model.buffers[1].data.insert(model.buffers[1].data.end(), tinyPng().begin(), tinyPng().end());
  model.bufferViews.push_back(png_view);
  tinygltf::Image in_view;
  in_view.bufferView = static_cast<int>(model.bufferViews.size()) - 1;
  in_view.mimeType = "image/png";
  in_view.image = tinyPng();
  in_view.as_is = true;
  model.images = {external, data_uri, in_view};

  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  std::string reference = dir.file("reference.glb");
  writeGltf(smallSampleModel(), reference);
  LoadedCharacter expected = loadCharacter(reference);
  for (const char* name : {"merged.glb", "merged.gltf"}) {
    INFO(name);
    std::string path = dir.file(name);
    writeGltf(model, path);
    LoadedCharacter loaded = loadCharacter(path);
    const tinygltf::Model& back = modelOf(*loaded.document);
    CHECK(back.buffers.size() == 1);
    REQUIRE(back.images.size() == 3);
    for (const tinygltf::Image& image : back.images) {
      CHECK(image.bufferView >= 0);
      CHECK(image.uri.empty());
      CHECK(image.mimeType == "image/png");
      CHECK(image.image == tinyPng());
    }
    const Character& c = loaded.character;
    const Character& e = expected.character;
    REQUIRE(c.meshes.size() == 1);
    CHECK(c.meshes[0].positions == e.meshes[0].positions);
    CHECK(c.meshes[0].triangles == e.meshes[0].triangles);
    CHECK(c.meshes[0].weights == e.meshes[0].weights);
    CHECK(c.meshes[0].joints == e.meshes[0].joints);
    CHECK(c.clips.size() == e.clips.size());
    if (ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) {
      ext::ValidationSummary report = ext::validateWithKhronos(path);
      INFO(report.raw);
      CHECK(report.exit_code == 0);
      CHECK(report.errors == 0);
      CHECK(report.warnings == 0);
    }
  }
}

TEST_CASE("the sample GLB, glTF and both VRM variants pass the Khronos glTF-Validator") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  struct Variant {
    SampleVrm vrm;
    const char* file;
    std::set<std::string> warnings;
    bool upper_chest = true;
  };
  // VRM 0.x's extension is named "VRM", without the vendor prefix glTF extension names have, so the
  // validator warns INVALID_EXTENSION_NAME_FORMAT; VRM 1.0's "VRMC_vrm" is well-formed. Both are
  // unknown to the validator, which only reports that as info (UNSUPPORTED_EXTENSION).
  for (const Variant& variant : {Variant{SampleVrm::kNone, "sample.glb", {}}, Variant{SampleVrm::kNone, "sample.gltf", {}},
                                 Variant{SampleVrm::kVrm0, "sample0.vrm", {"INVALID_EXTENSION_NAME_FORMAT"}},
                                 Variant{SampleVrm::kVrm1, "sample1.vrm", {}},
                                 Variant{SampleVrm::kVrm0, "sample0-no-upper-chest.vrm",
                                         {"INVALID_EXTENSION_NAME_FORMAT"}, false},
                                 Variant{SampleVrm::kVrm1, "sample1-no-upper-chest.vrm", {}, false}}) {
    INFO(variant.file);
    SampleOptions options;
    options.vrm = variant.vrm;
    options.upper_chest = variant.upper_chest;
    std::string path = dir.file(variant.file);
    writeGltf(sampleToGltf(makeSampleCharacter(options)), path);
    ext::ValidationSummary report = ext::validateWithKhronos(path);
    INFO(report.raw);
    CHECK(report.exit_code == 0);
    CHECK(report.errors == 0);
    CHECK(asSet(report.warning_codes) == variant.warnings);
  }
  // The benchmark size needs 32-bit indices.
  SampleOptions large;
  large.target_vertices = 100000;
  std::string path = dir.file("large.glb");
  writeGltf(sampleToGltf(makeSampleCharacter(large)), path);
  ext::ValidationSummary report = ext::validateWithKhronos(path);
  INFO(report.raw);
  CHECK(report.errors == 0);
  CHECK(report.warnings == 0);
}

TEST_CASE("every shared asset round-trips through the writer unchanged and valid") {
  const bool validate = ext::requireTool(ext::validatorAvailable(), ext::validatorHint());
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  for (const std::string& name : test::sharedAssetNames()) {
    std::string source = test::requireAsset(name);
    if (source.empty()) continue;
    INFO(name);
    LoadedCharacter original = loadCharacter(source);
    std::string stem = name.substr(name.find_last_of('/') + 1);
    stem = stem.substr(0, stem.find_last_of('.'));
    ext::ValidationSummary before;
    if (validate) before = ext::validateWithKhronos(source);
    // Written into an empty directory: any external buffer or image left as a reference would be
    // missing there, so a successful reload proves the output stands alone.
    for (const std::string extension : {".glb", ".gltf"}) {
      INFO(extension);
      std::string path = dir.file(stem + extension);
      writeGltf(modelOf(*original.document), path);
      LoadedCharacter written = loadCharacter(path);
      requireSameCharacter(original, written);
      const tinygltf::Model& model = modelOf(*written.document);
      CHECK(model.buffers.size() == 1);
      for (const tinygltf::Image& image : model.images) CHECK(image.bufferView >= 0);
      // Writing what was read gives the same bytes again.
      CHECK(serializeGltf(model, extension == ".glb") == readFile(path));
      if (!validate) continue;
      ext::ValidationSummary after = ext::validateWithKhronos(path);
      INFO(after.raw);
      CHECK(after.exit_code == 0);
      CHECK(after.errors == 0);
      // Nothing new to warn about: the source's own warnings (skinned mesh nodes that are not roots)
      // are all that remain.
      for (const std::string& code : after.warning_codes) CHECK(asSet(before.warning_codes).count(code) == 1);
    }
  }
}

TEST_CASE("a failed write leaves no file behind and says where") {
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  std::string path = dir.file("missing-dir/out.glb");
  try {
    writeGltf(smallSampleModel(), path);
    FAIL("writing into a missing directory succeeded");
  } catch (const Error& error) {
    CHECK(error.code() == "IO_WRITE_FAILED");
    CHECK(error.where() == path);
  }
  CHECK_FALSE(test::fileExists(path));
  CHECK(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()) == 0);

  tinygltf::Model broken = smallSampleModel();
  broken.bufferViews[0].byteLength = broken.buffers[0].data.size() + 1;
  try {
    serializeGltf(broken, true);
    FAIL("a buffer view past its buffer was written");
  } catch (const Error& error) {
    CHECK(error.code() == "GLTF_PARSE_FAILED");
    CHECK(error.where() == "/bufferViews/0");
  }
}

TEST_CASE("atomic files: an OutputBatch whose second file cannot be written leaves neither, and no temporary file") {
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  std::ofstream(dir.file("block")) << "a regular file, so block/x cannot be created";
  OutputBatch batch;
  batch.add(dir.file("first.json"), "{}\n");
  batch.add(dir.file("block/second.json"), "{}\n");
  try {
    batch.commit();
    FAIL("the batch committed although block/second.json cannot be written");
  } catch (const Error& error) {
    CHECK(error.code() == "IO_WRITE_FAILED");
    CHECK(error.where() == dir.file("block/second.json"));
  }
  std::set<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) left.insert(entry.path().filename().string());
  CHECK(left == std::set<std::string>{"block"});
}
