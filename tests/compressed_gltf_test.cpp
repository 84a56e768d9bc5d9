// Compressed inputs, made at test time from the shared characters by the tools that ship them:
// gltfpack (Debian's) writes EXT_meshopt_compression with -c and -cc and KHR_mesh_quantization by
// default; glTF-Transform's `draco` command (npm, scripts/install-gltf-transform.sh) writes
// KHR_draco_mesh_compression. Each must give the landmarks and `rigbake place` locators of the
// uncompressed file within 2 mm (quantization moves vertices and joints a little, nothing more), and
// its bake must pass the Khronos validator with 0 errors, written without compression. Under CI=true
// a missing tool fails the test instead of skipping it.
#include <algorithm>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "cli_support.h"
#include "external_tools.h"
#include "formats/gltf_document.h"
#include "glb_support.h"

using namespace rigbake;
namespace ext = rigbake::test::external;

namespace {

constexpr double kCompressedTolerance = 0.002;  // 2 mm, in the scene's metres

struct CompressedInput {
  std::string asset;      // shared asset name
  std::string original;   // its path
  std::string variant;    // the command that made it
  std::string extension;  // the extension the tool must have used
  std::string path;
  bool validate = false;
};

bool endsWithGlb(const std::string& name) { return name.size() > 4 && name.compare(name.size() - 4, 4, ".glb") == 0; }

// The variants of one shared asset (none when it is missing outside CI), made once per test process
// into a scratch directory.
const std::vector<CompressedInput>& compressedInputsOf(const std::string& name) {
  static ext::ScratchDir dir;
  static std::map<std::string, std::vector<CompressedInput>> made;
  if (made.count(name)) return made.at(name);
  std::vector<CompressedInput> inputs;
  const std::string original = test::requireAsset(name);
  const bool gltfpack = ext::requireTool(ext::onPath("gltfpack"), "gltfpack (Debian package gltfpack)");
  const bool gltf_transform =
      ext::requireTool(test::fileExists(ext::gltfTransformCli()),
                       "gltf-transform (scripts/install-gltf-transform.sh, at " + ext::gltfTransformCli() + ")");
  std::string stem = name.substr(name.find_last_of('/') + 1);
  stem = stem.substr(0, stem.find('.'));
  struct Recipe {
    bool available;
    std::string variant, extension, file;
    // Also in the validator test: one file per encoder, not per flag (-c and -cc differ in how hard
    // the same meshopt codec works, a .gltf in its container; the validator is the suite's slowest tool).
    bool validate;
  };
  std::vector<Recipe> recipes = {
      {gltfpack, "gltfpack -c", "EXT_meshopt_compression", stem + "-c.glb", false},
      // No keep flags: gltfpack may merge meshes and drop names it does not need; joints keep theirs.
      {gltfpack, "gltfpack -cc", "EXT_meshopt_compression", stem + "-cc.glb", true},
      {gltfpack, "gltfpack -cc -kn -km", "EXT_meshopt_compression", stem + "-cc-kn-km.glb", false},
      {gltfpack, "gltfpack", "KHR_mesh_quantization", stem + "-quantized.glb", false},
      {gltf_transform, "gltf-transform draco", "KHR_draco_mesh_compression", stem + "-draco.glb", true},
  };
  // JSON glTF out: the fallback buffer has no uri, which tinygltf cannot load unaided. (From a GLB
  // only: gltfpack does not copy a .gltf's external texture beside its output.)
  if (endsWithGlb(name))
    recipes.push_back({gltfpack, "gltfpack -c", "EXT_meshopt_compression", stem + "-c.gltf", false});
  for (const Recipe& recipe : recipes) {
    if (original.empty() || !recipe.available) continue;
    const std::string out = dir.file(recipe.file);
    std::string command;
    if (recipe.variant.rfind("gltfpack", 0) == 0) {
      command = "gltfpack -i " + ext::shellQuote(original) + " -o " + ext::shellQuote(out) + recipe.variant.substr(8);
    } else {
      command =
          ext::shellQuote(ext::gltfTransformCli()) + " draco " + ext::shellQuote(original) + " " + ext::shellQuote(out);
    }
    ext::CommandResult run = ext::runCommand(command + " 2>&1");
    INFO(command << "\n" << run.output);
    REQUIRE(run.exit_code == 0);
    // The tool really compressed: the extension is required by the file it wrote.
    REQUIRE(test::slurp(out).find(recipe.extension) != std::string::npos);
    inputs.push_back({name, original, recipe.variant, recipe.extension, out, recipe.validate});
  }
  return made[name] = inputs;
}

std::vector<CompressedInput> allCompressedInputs() {
  std::vector<CompressedInput> all;
  for (const std::string& name : test::sharedAssetNames()) {
    const std::vector<CompressedInput>& inputs = compressedInputsOf(name);
    all.insert(all.end(), inputs.begin(), inputs.end());
  }
  return all;
}

// Every [x, y, z] under the muscle JSON's groups (the talk's export shape), by path.
void collectLocators(const nlohmann::json& json, const std::string& prefix,
                     std::map<std::string, Eigen::Vector3d>* out) {
  for (const auto& [key, value] : json.items()) {
    if (prefix.empty() && key == "rigbake") continue;
    if (value.is_object()) collectLocators(value, prefix + key + "/", out);
    if (value.is_array() && value.size() == 3 && value[0].is_number())
      (*out)[prefix + key] = Eigen::Vector3d(value[0].get<double>(), value[1].get<double>(), value[2].get<double>());
  }
}

std::map<std::string, Eigen::Vector3d> placedLocators(const std::string& character, const std::string& out) {
  test::CliResult run = test::runCli("place " + ext::shellQuote(character) + " -o " + ext::shellQuote(out));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  std::map<std::string, Eigen::Vector3d> locators;
  collectLocators(nlohmann::json::parse(test::slurp(out)), "", &locators);
  return locators;
}

std::set<std::string> warningSet(const ext::ValidationSummary& summary) {
  return std::set<std::string>(summary.warning_codes.begin(), summary.warning_codes.end());
}

}  // namespace

TEST_CASE("compressed glTF: landmarks and placed locators within 2 mm of the uncompressed file's") {
  const std::vector<CompressedInput> inputs = allCompressedInputs();
  test::TempDir dir;
  std::map<std::string, test::Resolved> originals;
  std::map<std::string, std::map<std::string, Eigen::Vector3d>> original_locators;
  for (const CompressedInput& input : inputs) {
    INFO(input.asset << " through " << input.variant << " (" << input.path << ")");
    if (!originals.count(input.asset)) {
      originals[input.asset] = test::resolveShipped(input.original);
      original_locators[input.asset] = placedLocators(input.original, dir / "original.json");
    }
    const test::Resolved& original = originals.at(input.asset);
    LoadedCharacter loaded = loadCharacter(input.path);
    // Decoded on load: what the stages and writers see has no compression left.
    const std::vector<std::string>& used = modelOf(*loaded.document).extensionsUsed;
    CHECK(std::count(used.begin(), used.end(), "EXT_meshopt_compression") == 0);
    CHECK(std::count(used.begin(), used.end(), "KHR_draco_mesh_compression") == 0);
    const test::Resolved compressed = test::resolveWithShippedPresets(std::move(loaded.character));
    CHECK(compressed.landmarks.map_name == original.landmarks.map_name);
    double worst = 0.0;
    std::string worst_name;
    for (const auto& [name, landmark] : original.landmarks.landmarks) {
      if (!landmark.resolved) continue;
      INFO(name);
      REQUIRE(compressed.landmarks.has(name));
      const double distance = (compressed.landmarks.get(name).position - landmark.position).norm();
      if (distance > worst) {
        worst = distance;
        worst_name = name;
      }
    }
    INFO("worst landmark " << worst_name << ": " << worst * 1000 << " mm");
    CHECK(worst <= kCompressedTolerance);

    const std::map<std::string, Eigen::Vector3d> locators = placedLocators(input.path, dir / "compressed.json");
    const std::map<std::string, Eigen::Vector3d>& expected = original_locators.at(input.asset);
    REQUIRE(locators.size() == expected.size());
    // Three locators for each of the 28 muscles and each armpit corrective part (one per carrier joint).
    REQUIRE(expected.size() % 3 == 0);
    REQUIRE(expected.size() > 84);
    worst = 0.0;
    for (const auto& [name, position] : expected) {
      REQUIRE(locators.count(name) == 1);
      const double distance = (locators.at(name) - position).norm();
      if (distance > worst) {
        worst = distance;
        worst_name = name;
      }
    }
    INFO("worst locator " << worst_name << ": " << worst * 1000 << " mm");
    CHECK(worst <= kCompressedTolerance);
  }
}

TEST_CASE("Khronos validator: bakes of compressed inputs have 0 errors and are written uncompressed") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  const std::vector<CompressedInput> inputs = allCompressedInputs();
  test::TempDir dir;
  for (const CompressedInput& input : inputs) {
    if (!input.validate) continue;
    INFO(input.asset << " through " << input.variant << " (" << input.path << ")");
    const std::string muscles = dir / "muscles.json";
    const std::string baked = dir / "baked.glb";
    REQUIRE(test::runCli("place " + ext::shellQuote(input.path) + " -o " + muscles).exit_code == 0);
    // About reading compressed inputs and writing valid output, not the fit: the preset's response is kept.
    test::CliResult bake =
        test::runCli("bake " + ext::shellQuote(input.path) + " --muscles " + muscles + " --response keep -o " + baked);
    INFO(bake.err);
    REQUIRE(bake.exit_code == 0);
    const nlohmann::json json = test::glbJson(test::slurp(baked));
    for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
      for (const nlohmann::json& name : json.value(key, nlohmann::json::array())) {
        CHECK(name != "EXT_meshopt_compression");
        CHECK(name != "KHR_draco_mesh_compression");
      }
    }
    for (const nlohmann::json& view : json["bufferViews"]) CHECK_FALSE(view.contains("extensions"));
    for (const nlohmann::json& mesh : json["meshes"]) {
      for (const nlohmann::json& primitive : mesh["primitives"]) CHECK_FALSE(primitive.contains("extensions"));
    }
    const ext::ValidationSummary report = ext::validateWithKhronos(baked);
    INFO(report.raw);
    CHECK(report.exit_code == 0);
    CHECK(report.errors == 0);
    // The bake adds no warning to those the compressed input already has (docs/validator-warnings.md).
    const ext::ValidationSummary source = ext::validateWithKhronos(input.path);
    INFO("input: " << source.raw);
    for (const std::string& code : warningSet(report)) {
      INFO(code);
      CHECK(warningSet(source).count(code) == 1);
    }
  }
}

TEST_CASE("compressed glTF: damaged and truncated files fail with a stable code, never a crash") {
  // Both compressed formats of the first shared character, cut short and with bytes of their binary chunk
  // flipped: each load either succeeds (the decoders give garbage, never out-of-bounds) or throws a
  // rigbake::Error whose code is documented. Under the sanitizer pass this is a memory-safety check
  // of the decoding paths.
  if (test::sharedAssetNames().empty()) return;
  const std::vector<CompressedInput>& inputs = compressedInputsOf(test::sharedAssetNames().front());
  test::TempDir dir;
  std::set<std::string> made, done;
  for (const CompressedInput& input : inputs) made.insert(input.extension);
  for (const CompressedInput& input : inputs) {
    if (!endsWithGlb(input.path) || !done.insert(input.extension).second) continue;
    if (input.extension == "KHR_mesh_quantization") continue;
    INFO(input.path);
    const std::string bytes = test::slurp(input.path);
    uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const size_t binary_start = 20 + json_length + 8;
    std::vector<std::string> damaged;
    for (int k = 1; k <= 24; ++k) damaged.push_back(bytes.substr(0, bytes.size() * k / 25));
    for (int k = 0; k < 24; ++k) {
      std::string flipped = bytes;
      const size_t at = binary_start + (flipped.size() - binary_start) * k / 24;
      for (size_t i = at; i < std::min(flipped.size(), at + 64); ++i) flipped[i] = static_cast<char>(flipped[i] ^ 0x5a);
      damaged.push_back(flipped);
    }
    for (size_t d = 0; d < damaged.size(); ++d) {
      const std::string path = dir / "damaged.glb";
      std::ofstream(path, std::ios::binary) << damaged[d];
      INFO("damage " << d);
      try {
        loadCharacter(path);
      } catch (const Error& e) {
        CHECK(e.exitCode() == ExitCode::kInvalidInput);
      }
    }
  }
  for (const char* extension : {"EXT_meshopt_compression", "KHR_draco_mesh_compression"})
    CHECK(done.count(extension) == made.count(extension));
}
