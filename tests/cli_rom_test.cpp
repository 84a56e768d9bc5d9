// `rigbake rom`, and `bake --rom` / `validate --rom` from the command line: the ROM file comes out with
// the character's own clips first, deterministic; bad input is one error line, a documented exit
// status and no file; characters without clips get deformation figures through --rom.
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "external_tools.h"
#include "glb_support.h"

using namespace rigbake::test;

namespace {

bool romOutputExists(const TempDir& dir) { return std::filesystem::exists(dir / "rom.glb"); }

}  // namespace

TEST_CASE("cli rom: the mannequin gets ten rom_* animations after its own three, and a JSON summary") {
  TempDir dir;
  CliResult r = runCli("rom " + sampleGlbPathForCli() + " -o " + (dir / "rom.glb") + " --json");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("wrote ") == 0);
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  CHECK(summary["character"] == std::filesystem::path(sampleGlbPathForCli()).filename().string());
  CHECK(summary["output"] == "rom.glb");
  CHECK(summary["preset"] == "default");
  CHECK(summary["own_clips"] == 3);
  CHECK(summary["joints_keyed"] == 19);
  REQUIRE(summary["clips"].size() == 10);
  CHECK(summary["skipped"].empty());
  const nlohmann::json& elbow = summary["clips"][0];
  CHECK(elbow["name"] == "elbow_flexion");
  CHECK(elbow["animation"] == "rom_elbow_flexion");
  CHECK(elbow["duration_s"] == 2.0);
  CHECK(elbow["keys"] == 61);
  CHECK(elbow["to_deg"] == 130.0);
  CHECK(elbow["peak_s"] == 1.0);
  REQUIRE(elbow["sides"].size() == 2);
  CHECK(elbow["sides"][0]["joints"][0]["joint"] == "JOLeftLowerArm1");
  CHECK(elbow["sides"][0]["axis"] == nlohmann::json({0.0, -1.0, 0.0}));
  const nlohmann::json abduction = summary["clips"][1];
  CHECK(abduction["sides"][0]["joints"][0]["joint"] == "JOLeftClavicle1");
  CHECK(abduction["sides"][0]["joints"][0]["follows"] == true);
  CHECK(summary["clips"][4]["sides"][0]["side"] == "central");

  const nlohmann::json gltf = glbJson(slurp(dir / "rom.glb"));
  REQUIRE(gltf["animations"].size() == 13);
  CHECK(gltf["animations"][0]["name"] == "ElbowFlexion");
  CHECK(gltf["animations"][3]["name"] == "rom_elbow_flexion");
  CHECK(gltf["animations"][12]["name"] == "rom_hip_abduction");
  for (const nlohmann::json& sampler : gltf["animations"][3]["samplers"]) CHECK(sampler["interpolation"] == "LINEAR");
  for (const nlohmann::json& channel : gltf["animations"][3]["channels"])
    CHECK(channel["target"]["path"] == "rotation");
}

TEST_CASE("cli rom: --clips picks clips, and two runs write the same bytes") {
  TempDir dir;
  const std::string args = "rom " + sampleGlbPathForCli() + " --clips knee_flexion,elbow_flexion -o ";
  REQUIRE(runCli(args + (dir / "a.glb")).exit_code == 0);
  REQUIRE(runCli(args + (dir / "b.glb")).exit_code == 0);
  CHECK(slurp(dir / "a.glb") == slurp(dir / "b.glb"));
  const nlohmann::json gltf = glbJson(slurp(dir / "a.glb"));
  REQUIRE(gltf["animations"].size() == 5);
  // Preset order, not --clips order.
  CHECK(gltf["animations"][3]["name"] == "rom_elbow_flexion");
  CHECK(gltf["animations"][4]["name"] == "rom_knee_flexion");
}

TEST_CASE("cli rom: bad input is one error line with its code, a non-zero exit and no output file") {
  TempDir dir;
  const std::string out = " -o " + (dir / "rom.glb");
  struct Case {
    std::string args, code;
    int exit;
  };
  std::ofstream(dir / "not.glb") << "this is not glTF";
  std::ofstream(dir / "typo.json")
      << R"({"clips": [{"name": "x", "from_deg": 0, "to_deg": 10, "motion": {"from": "down", "towards": "lateral"}, "joints": [{"landmark": "upper_arm"}], "durration_s": 2}]})";
  REQUIRE(runCli("rom " + sampleGlbPathForCli() + " -o " + (dir / "once.glb")).exit_code == 0);
  const std::vector<Case> cases = {
      {"rom " + sampleGlbPathForCli() + " --clips wrist_flexion" + out, "ROM_CLIP_UNKNOWN", 3},
      {"rom " + sampleGlbPathForCli() + " --clips elbow_flexion,," + out, "USAGE", 1},
      {"rom " + (dir / "not.glb") + out, "GLTF_PARSE_FAILED", 3},
      {"rom " + (dir / "missing.glb") + out, "IO_FILE_NOT_FOUND", 2},
      {"rom " + (dir / "once.glb") + out, "ROM_CLIP_EXISTS", 3},
      {"rom " + sampleGlbPathForCli() + " --preset " + (dir / "typo.json") + out, "PRESET_INVALID", 3},
      {"rom " + sampleGlbPathForCli() + " --preset no_such_preset" + out, "IO_FILE_NOT_FOUND", 2},
  };
  for (const Case& c : cases) {
    INFO(c.args);
    CliResult r = runCli(c.args);
    INFO(r.err);
    CHECK(r.exit_code == c.exit);
    CHECK(r.err.rfind(c.code + " ", 0) == 0);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.out.empty());
    CHECK_FALSE(romOutputExists(dir));
  }
  CliResult typo = runCli(cases[5].args);
  CHECK(typo.err.find("typo.json#/clips/0/durration_s") != std::string::npos);
  CliResult missing_output = runCli("rom " + sampleGlbPathForCli());
  CHECK(missing_output.exit_code == 1);
}

TEST_CASE("cli rom --help says what the clips are and how to measure on them") {
  CliResult r = runCli("rom --help");
  REQUIRE(r.exit_code == 0);
  for (const char* text : {"range-of-motion", "elbow flexion to 130", "skipped", "--clips", "--preset", "bake --rom",
                           "docs/rom.md", "Example:"})
    CHECK(r.out.find(text) != std::string::npos);
}

TEST_CASE("cli bake --rom: KayKit and the Soldier, which have no clips, get non-zero deformation figures") {
  for (const char* name : {"KayKit_Mannequin/manny_med_mod.gltf", "Quaternius_ModularWomen_Soldier.glb"}) {
    const std::string input = requireAsset(name);
    if (input.empty()) continue;
    INFO(name);
    TempDir dir;
    CliResult plain =
        runCli("bake " + input + " --influences 10 -o " + (dir / "plain.glb") + " --stats " + (dir / "plain.json"));
    REQUIRE(plain.exit_code == 0);
    CliResult r = runCli("bake " + input + " --influences 10 --rom -o " + (dir / "baked.glb") + " --stats " +
                         (dir / "stats.json"));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    const nlohmann::json before = nlohmann::json::parse(slurp(dir / "plain.json"));
    const nlohmann::json stats = nlohmann::json::parse(slurp(dir / "stats.json"));
    CHECK(before["deformation_error_mm"]["max"] == 0.0);
    CHECK(stats["clips"] == 10);
    CHECK(stats["deformation_error_mm"]["max"].get<double>() > 0.0);
    CHECK(stats["deformation_error_mm"]["rms"].get<double>() > 0.0);
    for (const char* clip : {"rom_elbow_flexion", "rom_shoulder_abduction", "rom_spine_twist", "rom_knee_flexion"}) {
      INFO(clip);
      REQUIRE(stats["deformation_error_mm"]["per_clip"].contains(clip));
      CHECK(stats["deformation_error_mm"]["per_clip"][clip]["max"].get<double>() > 0.0);
    }
    CHECK(stats["deformation_error_mm"]["worst"]["clip"].get<std::string>().rfind("rom_", 0) == 0);
    CHECK(stats["rom"]["clips"].size() == 10);
    // Measured on, never written: the baked file has no animation at all, like its input.
    const nlohmann::json gltf = glbJson(slurp(dir / "baked.glb"));
    CHECK((!gltf.contains("animations") || gltf["animations"].empty()));
  }
}

TEST_CASE("cli validate --rom: the report's per-clip deformation covers the ROM clips of a character without clips") {
  const std::string input = requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (input.empty()) return;
  TempDir dir;
  REQUIRE(runCli("place " + input + " -o " + (dir / "muscles.json")).exit_code == 0);
  REQUIRE(runCli("bake " + input + " --muscles " + (dir / "muscles.json") + " --influences 10 --rom=default -o " +
                 (dir / "baked.glb"))
              .exit_code == 0);
  CliResult plain = runCli("validate " + (dir / "baked.glb") + " --muscles " + (dir / "muscles.json") + " --report " +
                           (dir / "plain"));
  CliResult r = runCli("validate " + (dir / "baked.glb") + " --muscles " + (dir / "muscles.json") + " --report " +
                       (dir / "rom") + " --rom");
  INFO(r.err);
  CHECK(r.exit_code == plain.exit_code);
  const nlohmann::json before = nlohmann::json::parse(slurp(dir / "plain/report.json"));
  const nlohmann::json report = nlohmann::json::parse(slurp(dir / "rom/report.json"));
  REQUIRE(before["plots"]["packed_deformation"].size() == 1);
  CHECK(before["plots"]["packed_deformation"][0]["clip"] == "(rest pose)");
  const nlohmann::json& deformation = report["plots"]["packed_deformation"];
  REQUIRE(deformation.size() == 10);
  double largest = 0.0;
  for (const nlohmann::json& clip : deformation) {
    CHECK(clip["clip"].get<std::string>().rfind("rom_", 0) == 0);
    CHECK(clip["samples"] == 61);
    largest = std::max(largest, clip["max_m"].get<double>());
  }
  CHECK(largest > 0.0);
  CHECK(report["plots"]["muscle_ratio"].size() == 10);
}

TEST_CASE("cli build: a manifest's \"rom\" measures every character on the ROM clips, and a character can opt out") {
  const std::string kaykit = requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (kaykit.empty()) return;
  TempDir dir;
  const nlohmann::json manifest = {{"rom", "default"},
                                   {"out", "out"},
                                   {"characters",
                                    {{{"name", "kaykit"}, {"input", kaykit}},
                                     {{"name", "hero"}, {"input", sampleGlbPathForCli()}, {"rom", false}}}}};
  std::ofstream(dir / "manifest.json") << manifest.dump(2);
  CliResult r = runCli("build " + (dir / "manifest.json") + " -j 1");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const nlohmann::json kaykit_report = nlohmann::json::parse(slurp(dir / "out/kaykit/report.json"));
  REQUIRE(kaykit_report["plots"]["packed_deformation"].size() == 10);
  CHECK(kaykit_report["plots"]["packed_deformation"][0]["clip"] == "rom_elbow_flexion");
  const nlohmann::json baked = glbJson(slurp(dir / "out/kaykit/kaykit.glb"));
  CHECK((!baked.contains("animations") || baked["animations"].empty()));
  const nlohmann::json hero_report = nlohmann::json::parse(slurp(dir / "out/hero/report.json"));
  REQUIRE(hero_report["plots"]["packed_deformation"].size() == 3);
  CHECK(hero_report["plots"]["packed_deformation"][0]["clip"] == "ElbowFlexion");

  nlohmann::json broken = manifest;
  broken["characters"][1]["rom"] = "no_such_rom";
  std::ofstream(dir / "broken.json") << broken.dump(2);
  CliResult bad = runCli("build " + (dir / "broken.json"));
  CHECK(bad.exit_code == 3);
  CHECK(bad.err.rfind("MANIFEST_INVALID ", 0) == 0);
  CHECK(bad.err.find("#/characters/1/rom") != std::string::npos);
}
