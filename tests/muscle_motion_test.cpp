// `bake --muscle-motion runtime|sampled|both` (issue 12): a runtime bake, evaluated by the C++ runtime
// from its RIGBAKE_muscle_rig extension, skins like a sampled bake plays its channels; runtime adds no
// animation bytes; every mode's output passes the Khronos glTF-Validator.
#include <nlohmann/json.hpp>

#include <set>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "pipeline/checks.h"
#include "pipeline/influences.h"
#include "pipeline/pose.h"
#include "pipeline/skinning.h"

using namespace rigbake;
using namespace rigbake::test;
namespace ext = rigbake::test::external;

namespace {

// The sample, and the shared characters with clips that the current asset selection holds.
std::vector<std::string> charactersWithClips() {
  std::vector<std::string> paths = {sampleGlbPathForCli()};
  const std::set<std::string> chosen(sharedAssetNames().begin(), sharedAssetNames().end());
  for (const char* asset : {"CesiumMan.glb", "Quaternius_Cyberpunk_Character.glb"}) {
    if (!chosen.count(asset)) continue;
    const std::string path = requireAsset(asset);
    if (!path.empty()) paths.push_back(path);
  }
  return paths;
}

std::string bakeIn(const TempDir& dir, const std::string& input, const std::string& motion, nlohmann::json* stats) {
  const std::string muscles = dir / "muscles.json";
  if (!std::filesystem::exists(muscles)) REQUIRE(runCli("place " + input + " -o " + muscles).exit_code == 0);
  const std::string out = dir / (motion + ".glb");
  CliResult r = runCli("bake " + input + " --muscles " + muscles + " --influences 10 --muscle-motion " + motion + " -o " + out +
                       " --stats " + (dir / (motion + ".json")));
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  if (stats) *stats = nlohmann::json::parse(slurp(dir / (motion + ".json")));
  return out;
}

// Every skinned part's positions at `pose`, skinned with the file's own weights and the matrices an
// engine uses (the runtime rig where the file carries it, else the channels).
std::vector<Eigen::Vector3d> skinAll(const Character& character, const BakedFileData& file, const Pose& pose) {
  const std::vector<Eigen::Affine3d> matrices = bakedSkinMatrices(character, file, pose);
  std::vector<Eigen::Vector3d> all;
  for (const MeshPart& mesh : character.meshes) {
    if (!mesh.skinned || mesh.positions.empty()) continue;
    const std::vector<Eigen::Vector3d> posed = skinLinearBlend(mesh.positions, influencesFromMesh(mesh), matrices);
    all.insert(all.end(), posed.begin(), posed.end());
  }
  return all;
}

}  // namespace

TEST_CASE("muscle motion: a runtime bake evaluated by the C++ runtime matches a sampled bake on every sampled frame within 1e-5 m") {
  for (const std::string& input : charactersWithClips()) {
    INFO(input);
    TempDir dir;
    const LoadedCharacter runtime = loadCharacter(bakeIn(dir, input, "runtime", nullptr));
    const LoadedCharacter sampled = loadCharacter(bakeIn(dir, input, "sampled", nullptr));
    const BakedFileData runtime_file = readBakedFileData(runtime);
    const BakedFileData sampled_file = readBakedFileData(sampled);
    REQUIRE(runtime_file.rig.present);
    REQUIRE(runtime_file.rig.problems.empty());
    REQUIRE_FALSE(sampled_file.rig.present);
    REQUIRE(runtime.character.clips.size() == sampled.character.clips.size());
    double worst = 0.0;
    int frames = 0;
    for (size_t c = 0; c < sampled.character.clips.size(); ++c) {
      // The sampled file's key times are the bake's samples.
      for (double t : sampleTimes(sampled.character.clips[c], 0.0)) {
        const std::vector<Eigen::Vector3d> a =
            skinAll(runtime.character, runtime_file, sampleClip(runtime.character.skeleton, runtime.character.clips[c], t));
        const std::vector<Eigen::Vector3d> b =
            skinAll(sampled.character, sampled_file, sampleClip(sampled.character.skeleton, sampled.character.clips[c], t));
        REQUIRE(a.size() == b.size());
        for (size_t v = 0; v < a.size(); ++v) worst = std::max(worst, (a[v] - b[v]).norm());
        ++frames;
      }
    }
    INFO(frames << " frames, largest difference " << worst << " m");
    CHECK(frames > 0);
    CHECK(worst <= 1e-5);
  }
}

TEST_CASE("muscle motion: runtime adds no animation bytes, sampled and both add the skinned joints' channels, Khronos 0 errors") {
  const bool validator = ext::requireTool(ext::validatorAvailable(), ext::validatorHint());
  for (const std::string& input : charactersWithClips()) {
    INFO(input);
    TempDir dir;
    nlohmann::json runtime, sampled, both;
    const std::string runtime_path = bakeIn(dir, input, "runtime", &runtime);
    const std::string sampled_path = bakeIn(dir, input, "sampled", &sampled);
    const std::string both_path = bakeIn(dir, input, "both", &both);
    const nlohmann::json& bytes = runtime["animation_bytes"];
    INFO("runtime " << bytes << ", sampled " << sampled["animation_bytes"] << ", both " << both["animation_bytes"]);
    CHECK(bytes["muscle_motion"] == "runtime");
    CHECK(bytes["output"] == bytes["input"]);
    CHECK(sampled["animation_bytes"]["output"].get<int64_t>() > sampled["animation_bytes"]["input"].get<int64_t>());
    CHECK(both["animation_bytes"]["output"] == sampled["animation_bytes"]["output"]);
    // The extension is the only other growth: runtime's file is the smallest.
    CHECK(std::filesystem::file_size(runtime_path) < std::filesystem::file_size(sampled_path));
    CHECK(std::filesystem::file_size(sampled_path) < std::filesystem::file_size(both_path));
    if (!validator) continue;
    for (const std::string& path : {runtime_path, sampled_path, both_path}) {
      INFO(path);
      const ext::ValidationSummary summary = ext::validateWithKhronos(path);
      INFO(summary.raw.substr(0, 2000));
      CHECK(summary.exit_code == 0);
      CHECK(summary.errors == 0);
    }
  }
}
