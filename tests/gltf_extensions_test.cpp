// extensionsRequired (glTF 2.0, "Specifying Extensions"): a file that requires an extension rigbake
// cannot honour is refused with GLTF_EXTENSION_UNSUPPORTED by every command, in one line naming the
// extension and the file, with exit status 3 and no output; extensions that are only used, or that
// rigbake honours, never stop a load. docs/extensions.md lists every honoured extension.
#include "formats/gltf_extensions.h"

#include <cstring>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "cli_support.h"
#include "glb_support.h"

using namespace rigbake;
using namespace rigbake::test;

namespace {

void writeExtensionTestFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// The sample written by the CLI as JSON glTF, parsed.
nlohmann::json sampleGltfJson(const TempDir& dir) {
  const std::string path = dir / "sample.gltf";
  REQUIRE(runCli("sample -o " + path).exit_code == 0);
  return nlohmann::json::parse(slurp(path));
}

nlohmann::json requiring(nlohmann::json gltf, const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    gltf["extensionsUsed"].push_back(name);
    gltf["extensionsRequired"].push_back(name);
  }
  return gltf;
}

// `glb` with its JSON chunk replaced by `json` (padded with spaces, as the GLB format wants).
std::string glbWithJsonChunk(const std::string& glb, const nlohmann::json& json) {
  uint32_t old_length = 0;
  std::memcpy(&old_length, glb.data() + 12, 4);
  std::string text = json.dump();
  while (text.size() % 4) text += ' ';
  const std::string rest = glb.substr(20 + old_length);
  const uint32_t length = static_cast<uint32_t>(text.size());
  const uint32_t total = static_cast<uint32_t>(12 + 8 + text.size() + rest.size());
  std::string out = glb.substr(0, 8);
  out.append(reinterpret_cast<const char*>(&total), 4);
  out.append(reinterpret_cast<const char*>(&length), 4);
  out += "JSON" + text + rest;
  return out;
}

void expectRefused(const CliResult& result, const std::string& file, const std::string& output) {
  INFO("stderr: " << result.err);
  CHECK(result.exit_code == 3);
  CHECK(result.err.rfind("GLTF_EXTENSION_UNSUPPORTED " + file + ": ", 0) == 0);
  CHECK(result.err.find("EXT_made_up") != std::string::npos);
  CHECK(lineCount(result.err) == 1);
  if (!output.empty()) CHECK_FALSE(fileExists(output));
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(file).parent_path()))
    CHECK(entry.path().filename().string().find("rigbake-tmp") == std::string::npos);
}

}  // namespace

TEST_CASE("cli: a file that requires an extension rigbake cannot honour is refused by every command") {
  TempDir dir;
  const std::string made_up = dir / "made_up.gltf";
  writeExtensionTestFile(made_up, requiring(sampleGltfJson(dir), {"EXT_made_up"}).dump());
  const std::string muscles = dir / "muscles.json";
  REQUIRE(runCli("place " + sampleGlbPathForCli() + " -o " + muscles).exit_code == 0);

  SECTION("place") {
    expectRefused(runCli("place " + made_up + " -o " + (dir / "out.json")), made_up, dir / "out.json");
  }
  SECTION("landmarks") { expectRefused(runCli("landmarks " + made_up), made_up, ""); }
  SECTION("bake") {
    expectRefused(runCli("bake " + made_up + " --muscles " + muscles + " -o " + (dir / "out.glb")), made_up,
                  dir / "out.glb");
  }
  SECTION("retarget, onto and from it") {
    expectRefused(runCli("retarget " + muscles + " --from " + sampleGlbPathForCli() + " --to " + made_up + " -o " +
                         (dir / "out.json")),
                  made_up, dir / "out.json");
    expectRefused(runCli("retarget " + muscles + " --from " + made_up + " --to " + sampleGlbPathForCli() + " -o " +
                         (dir / "out.json")),
                  made_up, dir / "out.json");
  }
  SECTION("validate") {
    expectRefused(runCli("validate " + made_up + " --report " + (dir / "report")), made_up, dir / "report");
  }
}

TEST_CASE("cli: a GLB that requires an unknown extension is refused, naming every one") {
  TempDir dir;
  const std::string glb = slurp(sampleGlbPathForCli());
  nlohmann::json json = requiring(glbJson(glb), {"EXT_made_up", "KHR_texture_transform", "EXT_also_made_up"});
  const std::string path = dir / "made_up.glb";
  writeExtensionTestFile(path, glbWithJsonChunk(glb, json));
  CliResult r = runCli("place " + path + " -o " + (dir / "out.json"));
  expectRefused(r, path, dir / "out.json");
  // Only the unknown ones are named; KHR_texture_transform is honoured.
  CHECK(r.err.find("EXT_made_up, EXT_also_made_up") != std::string::npos);
  CHECK(r.err.find("KHR_texture_transform") == std::string::npos);
}

TEST_CASE("cli: a required unknown extension is named even when the file is one tinygltf cannot parse") {
  // An indices accessor without a bufferView, as an extension could define one: tinygltf 2.7 refuses
  // the file ("accessor[N] invalid bufferView"); the reason to give is the extension.
  TempDir dir;
  nlohmann::json gltf = requiring(sampleGltfJson(dir), {"EXT_made_up"});
  gltf["accessors"].push_back({{"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}});
  gltf["meshes"][0]["primitives"][0]["indices"] = gltf["accessors"].size() - 1;
  const std::string path = dir / "made_up.gltf";
  writeExtensionTestFile(path, gltf.dump());
  expectRefused(runCli("place " + path + " -o " + (dir / "out.json")), path, dir / "out.json");
  // Without the requirement it is a plain parse failure.
  gltf.erase("extensionsRequired");
  writeExtensionTestFile(path, gltf.dump());
  CliResult r = runCli("place " + path + " -o " + (dir / "out.json"));
  CHECK(r.exit_code == 3);
  CHECK(r.err.rfind("GLTF_PARSE_FAILED ", 0) == 0);
}

TEST_CASE("cli: extensions that are only used, or that rigbake honours, do not stop a load") {
  TempDir dir;
  nlohmann::json gltf = sampleGltfJson(dir);
  gltf["extensionsUsed"].push_back("EXT_made_up");
  gltf["extensions"]["EXT_made_up"] = {{"anything", 1}};
  for (const char* honoured : {"KHR_texture_transform", "KHR_materials_emissive_strength", "KHR_mesh_quantization"}) {
    gltf["extensionsUsed"].push_back(honoured);
    gltf["extensionsRequired"].push_back(honoured);
  }
  const std::string path = dir / "used.gltf";
  writeExtensionTestFile(path, gltf.dump());
  CliResult placed = runCli("place " + path + " -o " + (dir / "muscles.json"));
  INFO(placed.err);
  REQUIRE(placed.exit_code == 0);
  // The bake keeps what it does not understand, and the requirements with it.
  CliResult baked = runCli("bake " + path + " --muscles " + (dir / "muscles.json") + " -o " + (dir / "baked.gltf"));
  INFO(baked.err);
  REQUIRE(baked.exit_code == 0);
  nlohmann::json out = nlohmann::json::parse(slurp(dir / "baked.gltf"));
  CHECK(out["extensions"]["EXT_made_up"]["anything"] == 1);
  CHECK(out["extensionsRequired"] ==
        nlohmann::json({"KHR_texture_transform", "KHR_materials_emissive_strength", "KHR_mesh_quantization"}));
}

TEST_CASE("every honoured extension is documented in docs/extensions.md") {
  const std::string doc = slurp(sourceDir() + "/docs/extensions.md");
  for (const HonouredExtension& extension : honouredExtensions()) {
    INFO(extension.name);
    CHECK(doc.find("`" + std::string(extension.name) + "`") != std::string::npos);
  }
  CHECK(unhonouredExtensions({"KHR_mesh_quantization", "EXT_made_up", "EXT_made_up"}) ==
        std::vector<std::string>{"EXT_made_up"});
  try {
    requireHonouredExtensions({"EXT_mesh_gpu_instancing"}, "hero.glb");
    FAIL("expected GLTF_EXTENSION_UNSUPPORTED");
  } catch (const Error& e) {
    CHECK(e.code() == "GLTF_EXTENSION_UNSUPPORTED");
    CHECK(e.where() == "hero.glb");
    CHECK(e.exitCode() == ExitCode::kInvalidInput);
  }
}
