// The response fit's smoothness term (bake --fit-smoothness, pipeline/response_fit.h): on a character
// no figure was tuned on, the FBX Male_Casual on its clips and the ROM's, it takes the rig's roughness
// to plain skinning's and keeps the regions, at the cost of volume kept (docs/deformation-quality.md,
// "The fit's smoothness term", has every shared character at 100 to 10000). Its roughness cap
// (bake --fit-roughness-cap) keeps every clip within the cap of plain skinning's roughness.
#include <map>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "external_tools.h"

namespace ext = rigbake::test::external;

namespace {

struct SkinSummary {
  int clips = 0;
  double elbow_flexion = 0.0;  // rom_elbow_flexion's whole-body change over plain skinning's (0 without the clip)
  int closer_than_plain = 0;   // clips whose whole-body change is smaller than plain skinning's
  double roughest = 0.0;       // the largest rig / plain roughness rise over the clips
  double worst_region = 0.0;   // the largest loss of a body region beyond plain skinning's, points
  int occupied_halved = 0;     // clips whose occupied-volume change is at most half of plain skinning's
};

// The figures as docs/deformation-quality.md takes them: roughness against plain's rise floored at
// 0.01 mm (a rise below that is under a hundredth of the edge length of any shared character).
SkinSummary summarize(const nlohmann::json& quality) {
  SkinSummary out;
  for (const auto& [clip, body] : quality["body"]["per_clip"].items()) {
    ++out.clips;
    const double input = body["input"]["change_percent"], rig = body["rig"]["change_percent"];
    if (std::abs(rig) < std::abs(input)) ++out.closer_than_plain;
    if (clip == "rom_elbow_flexion") out.elbow_flexion = std::abs(rig) / std::abs(input);
  }
  for (const auto& [clip, surface] : quality["surface"]["per_clip"].items()) {
    const nlohmann::json& rise = surface["roughness_rise_p95_mm"];
    out.roughest = std::max(out.roughest, rise["rig"].get<double>() / std::max(rise["input"].get<double>(), 0.01));
    const nlohmann::json& occupied = surface["occupied_volume"];
    if (std::abs(occupied["rig"]["change_percent"].get<double>()) <= 0.5 * std::abs(occupied["input"]["change_percent"].get<double>()))
      ++out.occupied_halved;
  }
  for (const auto& [name, region] : quality["regions"].items()) {
    if (!region.contains("per_clip")) continue;
    for (const auto& [clip, figures] : region["per_clip"].items()) {
      const double input = figures["input"]["change_percent"], rig = figures["rig"]["change_percent"];
      out.worst_region = std::max(out.worst_region, std::min(input, 0.0) - rig);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("fit smoothness: on Male_Casual (FBX) weight 1000 keeps the rig within 1.2x plain skinning's roughness on every clip") {
  const std::string path = rigbake::test::requireAsset("fbx/Male_Casual.fbx");
  if (path.empty()) return;
  rigbake::test::TempDir dir;
  auto bake = [&](const std::string& name, const std::string& flags) {
    const rigbake::test::CliResult run =
        rigbake::test::runCli("bake " + ext::shellQuote(path) + " --rom --influences 10 -o " + (dir / (name + ".glb")) + " --stats " +
                              (dir / (name + ".json")) + " " + flags);
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    return summarize(nlohmann::json::parse(rigbake::test::slurp(dir / (name + ".json")))["deformation_quality"]);
  };
  const SkinSummary volume_only = bake("volume", "");
  const SkinSummary smooth = bake("smooth", "--fit-smoothness 1000 --threads 2");
  INFO("roughness x plain, largest: " << volume_only.roughest << " -> " << smooth.roughest << "; worst region beyond plain "
                                      << volume_only.worst_region << " -> " << smooth.worst_region << " points; clips closer "
                                      << "to the bind volume than plain skinning " << volume_only.closer_than_plain << " -> "
                                      << smooth.closer_than_plain << " of " << smooth.clips);
  REQUIRE(smooth.clips == 21);  // its 11 clips and the default ROM's 10
  // Measured: 1.48 -> 1.07, 0.99 -> 0.66 points, 18 -> 21 of 21. (The weight is per metre of a 1.8 m body;
  // Male_Casual is 4.89 m tall as Assimp reads it, so 1000 here is 368 per metre of its own.)
  CHECK(volume_only.roughest > 1.3);
  CHECK(smooth.roughest <= 1.2);
  CHECK(smooth.worst_region < volume_only.worst_region);
  CHECK(smooth.worst_region <= 1.0);
  CHECK(smooth.closer_than_plain == smooth.clips);
  // The term's normal equations are summed in pose order: one thread gives the same file as two.
  bake("one_thread", "--fit-smoothness 1000 --threads 1");
  CHECK(rigbake::test::slurp(dir / "one_thread.glb") == rigbake::test::slurp(dir / "smooth.glb"));
}

// The fit on the occupied volume (bake --fit-volume occupied): on Quaternius Cyberpunk, whose rig swelled
// into its folds most, with the smoothness term at 200 (Cyberpunk is 1.40 m tall: 257 per metre) it is no
// rougher than the signed fit and halves the occupied change on as many clips, to one
// (docs/deformation-quality.md, "The fit on the occupied volume").
TEST_CASE("fit volume: on Cyberpunk the occupied fit is no rougher and keeps the occupied volume as the signed fit does, with smoothness 200") {
  const std::string path = rigbake::test::requireAsset("Quaternius_Cyberpunk_Character.glb");
  if (path.empty()) return;
  rigbake::test::TempDir dir;
  auto bake = [&](const std::string& name, const std::string& flags) {
    const rigbake::test::CliResult run = rigbake::test::runCli("bake " + ext::shellQuote(path) + " --influences 10 -o " +
                                                               (dir / (name + ".glb")) + " --stats " + (dir / (name + ".json")) + " " + flags);
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    // Without the smoothness term the occupied fit says it is not stable.
    CHECK((run.err.find("note: --fit-volume occupied without --fit-smoothness") != std::string::npos) ==
          (flags.find("occupied") != std::string::npos && flags.find("smoothness") == std::string::npos));
    return summarize(nlohmann::json::parse(rigbake::test::slurp(dir / (name + ".json")))["deformation_quality"]);
  };
  const SkinSummary signed_fit = bake("signed", "--fit-smoothness 200");
  const SkinSummary occupied_fit = bake("occupied", "--fit-smoothness 200 --fit-volume occupied");
  INFO("occupied change halved on " << signed_fit.occupied_halved << " -> " << occupied_fit.occupied_halved << " of "
                                    << occupied_fit.clips << " clips; roughness x plain, largest " << signed_fit.roughest << " -> "
                                    << occupied_fit.roughest);
  REQUIRE(occupied_fit.clips == 22);
  // Measured: 1 -> 0 of 22, 1.26 -> 1.24. (1 -> 1, 1.44 -> 1.29 before the body's row spared the losses
  // of the skin no muscle moves, which smoothed the signed fit: the occupied fit's lead was the swelling
  // that row asked for; 8 -> 11, 2.34 -> 2.35 while muscles still took weight on Cyberpunk's armour
  // plates, which the input moves rigidly: the clips halved were the plates swelling; 8 -> 16, 2.39 ->
  // 2.14 before a compression key's bound fell towards rest with the talk's amplitude.)
  CHECK(occupied_fit.occupied_halved + 1 >= signed_fit.occupied_halved);
  CHECK(occupied_fit.roughest <= signed_fit.roughest);
  CHECK(occupied_fit.closer_than_plain == occupied_fit.clips);
  bake("occupied_alone", "--fit-volume occupied");
  // Each pose's exposure is its own: one thread gives the same file as two.
  bake("occupied_one_thread", "--fit-smoothness 200 --fit-volume occupied --threads 1");
  CHECK(rigbake::test::slurp(dir / "occupied_one_thread.glb") == rigbake::test::slurp(dir / "occupied.glb"));
}

// The roughness cap (bake --fit-roughness-cap): at each fitted pose no vertex the muscles move may stand
// out of its neighbours' plane by more than plain skinning's there plus what keeps the 95th percentile
// within the cap. On Quaternius Cyberpunk, whose default rig is rougher than 1.2x plain skinning on every
// clip, a cap of 1.2 keeps every clip within it; on Male_Casual a cap of 1.5 still halves the elbow's
// volume change with every clip within 1.2x (docs/deformation-quality.md, "The roughness cap").
TEST_CASE("fit roughness cap: at 1.2 every Cyberpunk clip is within 1.2x plain skinning's roughness, and at 1.5 Male_Casual halves its elbow flexion within 1.2x") {
  const std::string cyberpunk = rigbake::test::requireAsset("Quaternius_Cyberpunk_Character.glb");
  const std::string male = rigbake::test::requireAsset("fbx/Male_Casual.fbx");
  if (cyberpunk.empty() || male.empty()) return;
  rigbake::test::TempDir dir;
  std::map<std::string, std::string> said;  // each bake's stderr, by name
  auto bake = [&](const std::string& input, const std::string& name, const std::string& flags) {
    const rigbake::test::CliResult run = rigbake::test::runCli("bake " + ext::shellQuote(input) + " --influences 10 -o " +
                                                               (dir / (name + ".glb")) + " --stats " + (dir / (name + ".json")) + " " + flags);
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    said[name] = run.err;
    return summarize(nlohmann::json::parse(rigbake::test::slurp(dir / (name + ".json")))["deformation_quality"]);
  };
  const SkinSummary volume_only = bake(cyberpunk, "volume", "");
  const SkinSummary capped = bake(cyberpunk, "capped", "--fit-roughness-cap 1.2");
  INFO("Cyberpunk, roughness x plain, largest: " << volume_only.roughest << " -> " << capped.roughest << "; clips closer to the bind "
                                                 << "volume than plain skinning " << volume_only.closer_than_plain << " -> "
                                                 << capped.closer_than_plain << " of " << capped.clips);
  REQUIRE(capped.clips == 22);
  // Measured: 2.36 -> 1.02; 22 -> 22 of 22.
  CHECK(volume_only.roughest > 2.0);
  CHECK(capped.roughest <= 1.2);
  CHECK(capped.closer_than_plain >= 20);
  CHECK(capped.worst_region <= 1.0);
  // The bake names the cap where the rig is over the check, and not once the cap holds it.
  CHECK(said["volume"].find("on 20 of 22 clips (SKIN_ROUGHNESS_RISE): --fit-roughness-cap 1.20 bounds it") != std::string::npos);
  CHECK(said["capped"].find("--fit-roughness-cap") == std::string::npos);
  // The cap's bound per pose and its hinges are taken in pose order: one thread gives the same file as two.
  bake(cyberpunk, "capped_one_thread", "--fit-roughness-cap 1.2 --threads 1");
  CHECK(rigbake::test::slurp(dir / "capped_one_thread.glb") == rigbake::test::slurp(dir / "capped.glb"));

  const SkinSummary male_capped = bake(male, "male", "--rom --fit-roughness-cap 1.5");
  INFO("Male_Casual at 1.5: roughness x plain, largest " << male_capped.roughest << "; elbow flexion keeps "
                                                         << male_capped.elbow_flexion << " of plain skinning's change");
  REQUIRE(male_capped.clips == 21);
  // Measured: 1.10; 0.30 (the default rig: 1.48, 0.66).
  CHECK(male_capped.roughest <= 1.2);
  CHECK(male_capped.elbow_flexion > 0.0);
  CHECK(male_capped.elbow_flexion <= 0.5);
}
