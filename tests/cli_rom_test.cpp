// `rigbake rom` from the command line: the ROM file comes out with the character's own clips first,
// deterministic; bad input is one error line, a documented exit status and no file.
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
  for (const nlohmann::json& channel : gltf["animations"][3]["channels"]) CHECK(channel["target"]["path"] == "rotation");
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
  std::ofstream(dir / "typo.json") << R"({"clips": [{"name": "x", "from_deg": 0, "to_deg": 10, "motion": {"from": "down", "towards": "lateral"}, "joints": [{"landmark": "upper_arm"}], "durration_s": 2}]})";
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
