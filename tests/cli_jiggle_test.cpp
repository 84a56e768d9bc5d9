// `rigbake bake --jiggle` as a technical artist runs it: the talk's jiggle settings baked into every
// clip of the sample and of real characters, kicked by hits, exported as VRM spring bones, checked by
// `rigbake validate`, accepted by the Khronos validator; and bad jiggle input refused cleanly.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "pipeline/checks.h"
#include "external_tools.h"
#include "glb_support.h"
#include "test_support.h"

#include <catch2/catch.hpp>

using namespace rigbake;
namespace ext = rigbake::test::external;
using rigbake::test::runCli;
using rigbake::test::slurp;

namespace {

namespace fs = std::filesystem;

nlohmann::json glbFileJson(const std::string& path) { return test::glbJson(slurp(path)); }

std::string bakeArgs(const std::string& input, const std::string& output, const std::string& extra) {
  // Sampled motion: these tests read the baked jiggle channels back. They are about the jiggles, not the
  // response fit (the bake and deformation-quality tests cover it): the preset's response is kept.
  return "bake " + ext::shellQuote(input) + " --influences 4 --muscle-motion both --response keep " + extra + " -o " +
         ext::shellQuote(output);
}

const nlohmann::json* jiggleOf(const nlohmann::json& animation, const std::string& joint) {
  for (const auto& entry : animation["extras"]["rigbake"]["jiggle"]) {
    if (entry["joint"] == joint) return &entry;
  }
  return nullptr;
}

std::string sampleVrm(const test::TempDir& dir, int version) {
  const std::string path = dir / ("sample" + std::to_string(version) + ".vrm");
  REQUIRE(runCli("sample --vrm " + std::to_string(version) + " -o " + ext::shellQuote(path)).exit_code == 0);
  return path;
}

}  // namespace

// That two runs give the same bytes is parallel_test.cpp's CLI determinism test (a jiggle bake at 1, 2
// and 3 threads) and the golden bakes' sample-jiggle (this bake's flags, against recorded bytes).
TEST_CASE("cli bake --jiggle: every clip carries the jiggles, inside their cones") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  test::CliResult run = runCli(bakeArgs(sample, dir / "a.glb", "--jiggle gow_examples"));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  CHECK(run.err.find("jiggle: 6 joints, 0 hits, baked into every clip") != std::string::npos);

  const nlohmann::json gltf = glbFileJson(dir / "a.glb");
  int hand_node = -1;
  for (size_t n = 0; n < gltf["nodes"].size(); ++n) {
    if (gltf["nodes"][n].value("name", "") == "JOLeftHand1") hand_node = static_cast<int>(n);
  }
  REQUIRE(hand_node >= 0);
  REQUIRE(gltf["animations"].size() == 3);
  double largest_swing = 0.0;
  for (const auto& animation : gltf["animations"]) {
    INFO(animation.value("name", ""));
    const auto& block = animation["extras"]["rigbake"];
    REQUIRE(block["jiggle"].size() == 6);
    const size_t samples = block["times"].size();
    CHECK(samples >= 60);
    for (const auto& entry : block["jiggle"]) {
      REQUIRE(entry["angle_deg"].size() == samples);
      for (size_t t = 0; t < samples; ++t) {
        CHECK(entry["angle_deg"][t].get<double>() <= entry["clamp_deg"][t].get<double>() + 1e-6);
        largest_swing = std::max(largest_swing, entry["angle_deg"][t].get<double>());
      }
    }
    // The hand's own channels are replaced by its jiggled keys: one per path, on the sample times.
    int rotation_channels = 0;
    for (const auto& channel : animation["channels"]) {
      if (channel["target"].value("node", -1) != hand_node) continue;
      rotation_channels += channel["target"]["path"] == "rotation";
      const auto& sampler = animation["samplers"][channel["sampler"].get<int>()];
      CHECK(gltf["accessors"][sampler["input"].get<int>()]["count"] == samples);
    }
    CHECK(rotation_channels == 1);
  }
  // The clips swing the arms hard enough that the soft, unclamped jiggles lag visibly.
  CHECK(largest_swing > 2.0);
}

TEST_CASE("cli bake --hits: a hit moves the part that was hit from its time on, and nothing before it") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  std::ofstream(dir / "hits.json") << R"({"hits": [{"clip": "ArmRaise", "time": 0.5, "direction": [0, 0, 1],
                                          "magnitude": 1.5, "joints": ["LeftBicep"], "why": "punch from behind"}]})";
  REQUIRE(runCli(bakeArgs(sample, dir / "calm.glb", "--jiggle biceps")).exit_code == 0);
  test::CliResult hit = runCli(bakeArgs(sample, dir / "hit.glb", "--jiggle biceps --hits " + ext::shellQuote(dir / "hits.json")));
  INFO(hit.err);
  REQUIRE(hit.exit_code == 0);
  const nlohmann::json calm = glbFileJson(dir / "calm.glb"), kicked = glbFileJson(dir / "hit.glb");
  for (size_t a = 0; a < calm["animations"].size(); ++a) {
    const std::string clip = calm["animations"][a]["name"];
    INFO(clip);
    const auto& times = calm["animations"][a]["extras"]["rigbake"]["times"];
    for (const std::string joint : {"LeftBicep_muscleSkinned", "RightBicep_muscleSkinned"}) {
      const nlohmann::json* before = jiggleOf(calm["animations"][a], joint);
      const nlohmann::json* after = jiggleOf(kicked["animations"][a], joint);
      REQUIRE(before);
      REQUIRE(after);
      double largest_change = 0.0;
      for (size_t t = 0; t < times.size(); ++t) {
        const double change = std::abs((*after)["angle_deg"][t].get<double>() - (*before)["angle_deg"][t].get<double>());
        if (times[t].get<double>() < 0.5) CHECK(change == 0.0);
        largest_change = std::max(largest_change, change);
      }
      const bool hit_here = clip == "ArmRaise" && joint == "LeftBicep_muscleSkinned";
      if (hit_here) CHECK(largest_change > 0.5);
      else CHECK(largest_change == 0.0);
    }
  }
}

TEST_CASE("cli validate: a jiggle bake passes JIGGLE_WITHIN_CLAMP and the report plots each clip's jiggle angles") {
  test::TempDir dir;
  REQUIRE(runCli(bakeArgs(test::sampleGlbPathForCli(), dir / "j.glb", "--jiggle gow_examples")).exit_code == 0);
  test::CliResult run = runCli("validate " + ext::shellQuote(dir / "j.glb") + " --report " + ext::shellQuote(dir / "r"));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(slurp(dir / "r/report.json"));
  bool found = false;
  for (const auto& check : report["checks"]) {
    if (check["code"] != "JIGGLE_WITHIN_CLAMP") continue;
    found = true;
    CHECK(check["status"] == "pass");
    CHECK(check["measured"].get<double>() <= 1e-6);
  }
  CHECK(found);
  REQUIRE(report["plots"]["jiggle_angle"].size() == 3);
  CHECK(report["plots"]["jiggle_angle"][0]["jiggles"].size() == 6);
  const std::string html = slurp(dir / "r/report.html");
  CHECK(html.find("<section id=\"jiggles\">") != std::string::npos);
  CHECK(html.find("aria-label=\"jiggle angle over time, clip ArmRaise\"") != std::string::npos);

  // Without --jiggle the check is skipped, not failed, and there is no jiggle section.
  REQUIRE(runCli(bakeArgs(test::sampleGlbPathForCli(), dir / "plain.glb", "")).exit_code == 0);
  REQUIRE(runCli("validate " + ext::shellQuote(dir / "plain.glb") + " --report " + ext::shellQuote(dir / "p")).exit_code == 0);
  CHECK(slurp(dir / "p/report.html").find("<section id=\"jiggles\">") == std::string::npos);
}

TEST_CASE("cli bake --jiggle on VRM 1.0 and 0.x: the jiggles are also exported as spring bones") {
  test::TempDir dir;
  for (int version : {1, 0}) {
    INFO("VRM " << version);
    const std::string input = sampleVrm(dir, version);
    const std::string output = dir / ("baked" + std::to_string(version) + ".vrm");
    test::CliResult run = runCli(bakeArgs(input, output, "--jiggle biceps"));
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    CHECK(run.err.find("exported as VRM spring bones, without their cones") != std::string::npos);
    const nlohmann::json gltf = glbFileJson(output);
    auto nameOf = [&](int node) { return gltf["nodes"][node].value("name", ""); };
    if (version == 1) {
      const auto& springs = gltf["extensions"]["VRMC_springBone"]["springs"];
      REQUIRE(springs.size() == 2);
      for (const auto& spring : springs) {
        REQUIRE(spring["joints"].size() == 2);
        const auto& head = spring["joints"][0];
        CHECK(nameOf(head["node"]) == spring["name"]);
        CHECK(nameOf(spring["joints"][1]["node"]) == spring["name"].get<std::string>() + "_jiggleTail");
        // Stiffness 0.5 / damping 0.05 mapped at 60 Hz (docs/jiggle.md): a stiff spring, little drag.
        CHECK(head["stiffness"].get<double>() > 0.1);
        CHECK(head["dragForce"].get<double>() > 0.0);
        CHECK(head["dragForce"].get<double>() < 0.2);
        CHECK(head["gravityPower"].get<double>() == 0.0);
      }
      CHECK(std::count(gltf["extensionsUsed"].begin(), gltf["extensionsUsed"].end(), "VRMC_springBone") == 1);
    } else {
      const auto& secondary = gltf["extensions"]["VRM"]["secondaryAnimation"];
      REQUIRE(secondary["boneGroups"].size() == 2);
      for (const auto& group : secondary["boneGroups"]) {
        REQUIRE(group["bones"].size() == 1);
        CHECK(nameOf(group["bones"][0]) == group["comment"]);
        CHECK(group["stiffiness"].get<double>() > 0.1);  // sic: VRM 0.x's key
      }
    }
  }
  // --vrm-springs-only: springs for the runtime, clips left un-jiggled.
  const std::string input = sampleVrm(dir, 1);
  test::CliResult only = runCli(bakeArgs(input, dir / "springs.vrm", "--jiggle biceps --vrm-springs-only"));
  INFO(only.err);
  REQUIRE(only.exit_code == 0);
  const nlohmann::json gltf = glbFileJson(dir / "springs.vrm");
  CHECK(gltf["extensions"]["VRMC_springBone"]["springs"].size() == 2);
  for (const auto& animation : gltf["animations"]) CHECK_FALSE(animation.contains("extras"));
}

TEST_CASE("cli bake --jiggle: bad jiggle input is one line with a stable code, and no output") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  std::ofstream(dir / "stranger.json") << R"({"hits": [{"time": 0.1, "direction": [1, 0, 0], "magnitude": 1, "joints": ["Tail"]}]})";
  std::ofstream(dir / "typo.json") << R"({"jiggles": [{"landmark": "hand_l", "stifness": 0.5, "damping": 0.1,
                                          "clamp_major_deg": 90, "clamp_minor_deg": 90}]})";
  const std::string vrm = sampleVrm(dir, 1);
  struct Case {
    std::string args;
    int exit_code;
    std::string code;
  };
  const std::vector<Case> cases = {
      {"--hits " + ext::shellQuote(dir / "stranger.json"), 1, "USAGE --hits"},
      {"--jiggle biceps --hits " + ext::shellQuote(dir / "stranger.json"), 3, "HITS_INVALID"},
      {"--jiggle " + ext::shellQuote(dir / "typo.json"), 3, "PRESET_INVALID"},
      {"--jiggle no_such_preset", 2, "IO_FILE_NOT_FOUND"},
      {"--jiggle biceps --vrm-springs-only", 1, "USAGE --vrm-springs-only"},
  };
  for (const Case& c : cases) {
    test::CliResult run = runCli(bakeArgs(sample, dir / "out.glb", c.args));
    INFO(c.args << "\n" << run.err);
    CHECK(run.exit_code == c.exit_code);
    CHECK(run.err.rfind(c.code, 0) == 0);
    CHECK(test::lineCount(run.err) == 1);
    CHECK_FALSE(fs::exists(dir / "out.glb"));
  }
  // The VRM humanoid has no forearm roll joints for gow_examples' talk examples 3 and 4.
  test::CliResult unresolved = runCli(bakeArgs(vrm, dir / "out.vrm", "--jiggle gow_examples"));
  CHECK(unresolved.exit_code == 3);
  CHECK(unresolved.err.rfind("JIGGLE_UNRESOLVED ", 0) == 0);
  CHECK(unresolved.err.find("gow_examples.json#/jiggles/2") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "out.vrm"));
}

TEST_CASE("Khronos validator: jiggle bakes of the sample, its VRM variants and real characters have 0 errors") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  test::TempDir dir;
  std::vector<std::pair<std::string, std::string>> inputs = {{test::sampleGlbPathForCli(), "gow_examples"},
                                                             {sampleVrm(dir, 0), "biceps"},
                                                             {sampleVrm(dir, 1), "biceps"}};
  for (const std::string name : {"CesiumMan.glb", "RobotExpressive.glb"}) {
    const std::string path = test::requireAsset(name);
    if (!path.empty()) inputs.push_back({path, "biceps"});
  }
  for (size_t i = 0; i < inputs.size(); ++i) {
    const auto& [input, preset] = inputs[i];
    const std::string output = dir / ("jiggle" + std::to_string(i) + (input.size() > 4 && input.substr(input.size() - 4) == ".vrm" ? ".vrm" : ".glb"));
    test::CliResult run = runCli(bakeArgs(input, output, "--jiggle " + preset));
    INFO(input << "\n" << run.err);
    REQUIRE(run.exit_code == 0);
    const ext::ValidationSummary summary = ext::validateWithKhronos(output);
    INFO(summary.raw);
    CHECK(summary.errors == 0);
  }
}

TEST_CASE("cli bake --jiggle: the summary says where the jiggle lives, extension or channels") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  // The default (runtime) bake writes no channels: its jiggles are the extension's.
  test::CliResult runtime = runCli("bake " + ext::shellQuote(sample) + " --response keep --jiggle biceps -o " + ext::shellQuote(dir / "r.glb"));
  INFO(runtime.err);
  REQUIRE(runtime.exit_code == 0);
  CHECK(runtime.err.find("in the RIGBAKE_muscle_rig extension, simulated at run time (no channels)") != std::string::npos);
  CHECK(runtime.err.find("baked into every clip") == std::string::npos);
  const nlohmann::json json = test::glbJson(slurp(dir / "r.glb"));
  CHECK(json["extensions"]["RIGBAKE_muscle_rig"].contains("jiggles"));
  test::CliResult sampled =
      runCli("bake " + ext::shellQuote(sample) + " --response keep --muscle-motion sampled --jiggle biceps -o " + ext::shellQuote(dir / "s.glb"));
  REQUIRE(sampled.exit_code == 0);
  CHECK(sampled.err.find("jiggle: 2 joints, 0 hits, baked into every clip\n") != std::string::npos);
}

TEST_CASE("cli validate: a runtime jiggle is run by the runtime library and checked against its cone") {
  // A default bake keeps the jiggle in the RIGBAKE_muscle_rig extension, with no channels: validate runs
  // it over the file's clips with the runtime's MuscleRigJob and JiggleJob instead of skipping the check.
  test::TempDir dir;
  const std::string baked = dir / "runtime.gltf";
  test::CliResult bake = runCli("bake " + ext::shellQuote(test::sampleGlbPathForCli()) + " --jiggle biceps -o " +
                                ext::shellQuote(baked));
  INFO(bake.err);
  REQUIRE(bake.exit_code == 0);
  nlohmann::json gltf = nlohmann::json::parse(slurp(baked));
  REQUIRE(gltf["extensions"]["RIGBAKE_muscle_rig"]["jiggles"].size() == 2);
  for (const auto& animation : gltf["animations"]) CHECK_FALSE(animation.contains("extras"));

  auto clampCheck = [&](const std::string& file, const std::string& report_dir, int* exit_code) {
    test::CliResult run = runCli("validate " + ext::shellQuote(file) + " --report " + ext::shellQuote(report_dir));
    INFO(run.err);
    *exit_code = run.exit_code;
    const nlohmann::json report = nlohmann::json::parse(slurp(report_dir + "/report.json"));
    for (const auto& check : report["checks"])
      if (check["code"] == "JIGGLE_WITHIN_CLAMP") return std::make_pair(check, report["plots"]["jiggle_angle"]);
    FAIL("no JIGGLE_WITHIN_CLAMP in the report");
    return std::make_pair(nlohmann::json(), nlohmann::json());
  };
  int exit_code = -1;
  auto [check, plots] = clampCheck(baked, dir / "r", &exit_code);
  CHECK(exit_code == 0);
  CHECK(check["status"] == "pass");
  CHECK(check["measured"].get<double>() <= 1e-6);
  CHECK(check["message"].get<std::string>().find("run by the runtime library") != std::string::npos);
  // Every clip of the sample, both biceps, and they do swing: the check measured real motion.
  REQUIRE(plots.size() == 3);
  double largest_angle = 0.0;
  for (const auto& clip : plots) {
    CHECK(clip["jiggles"].size() == 2);
    for (const auto& jiggle : clip["jiggles"])
      for (const auto& angle : jiggle["angle_deg"]) largest_angle = std::max(largest_angle, angle.get<double>());
  }
  CHECK(largest_angle > 0.1);

  // A cone no runtime clamps to (wider than 90 degrees): the runtime refuses the jiggle, so nothing
  // bounds it, and the check fails naming it.
  gltf["extensions"]["RIGBAKE_muscle_rig"]["jiggles"][1]["clampMajorDeg"] = 120.0;
  const std::string broken = dir / "broken.gltf";
  std::ofstream(broken) << gltf.dump();
  auto [broken_check, broken_plots] = clampCheck(broken, dir / "b", &exit_code);
  CHECK(exit_code != 0);
  CHECK(broken_check["status"] == "fail");
  const std::string finding = broken_check["findings"][0]["message"];
  CHECK(finding.find("clamp_major_deg must be in [0, 90]") != std::string::npos);
  CHECK(broken_check["findings"][0]["location"] == "/extensions/RIGBAKE_muscle_rig/jiggles/1");
  // The other jiggle still ran.
  CHECK(broken_plots.size() == 3);
}

TEST_CASE("validate's runtime jiggle reproduces the bake's own simulation of the same jiggles") {
  // A bake with --muscle-motion both records the angles it simulated in the clips' extras and keeps the
  // jiggles in the extension: running the extension's jiggles through the runtime library over the file's
  // clips, as validate does for a runtime bake, must give the very same angles.
  test::TempDir dir;
  const std::string both = dir / "both.glb";
  REQUIRE(runCli("bake " + ext::shellQuote(test::sampleGlbPathForCli()) + " --jiggle biceps --muscle-motion both -o " +
                 ext::shellQuote(both))
              .exit_code == 0);
  const LoadedCharacter loaded = loadCharacter(both);
  const BakedFileData data = readBakedFileData(loaded);
  REQUIRE(data.rig.jiggles.size() == 2);
  REQUIRE(data.jiggles.size() == 3);
  const RuntimeJiggles runtime = simulateFileJiggles(loaded.character, data.rig);
  CHECK(runtime.refused.empty());
  REQUIRE(runtime.clips.size() == data.jiggles.size());
  double worst = 0.0, peak = 0.0;
  int compared = 0;
  for (size_t c = 0; c < runtime.clips.size(); ++c) {
    const ClipJiggles& ran = runtime.clips[c];
    const ClipJiggles& baked = data.jiggles[c];
    INFO(ran.clip);
    CHECK(ran.clip == baked.clip);
    REQUIRE(ran.times == baked.times);
    REQUIRE(ran.jiggles.size() == baked.jiggles.size());
    for (size_t j = 0; j < ran.jiggles.size(); ++j) {
      CHECK(ran.jiggles[j].joint == baked.jiggles[j].joint);
      for (size_t t = 0; t < ran.times.size(); ++t) {
        worst = std::max(worst, std::abs(ran.jiggles[j].angle_deg[t] - baked.jiggles[j].angle_deg[t]));
        worst = std::max(worst, std::abs(ran.jiggles[j].clamp_deg[t] - baked.jiggles[j].clamp_deg[t]));
        peak = std::max(peak, baked.jiggles[j].angle_deg[t]);
        ++compared;
      }
    }
  }
  CHECK(compared == 2 * 3 * 61);
  CHECK(peak > 2.0);  // the biceps do swing (2.49 degrees in ArmRaise)
  CHECK(worst <= 1e-9);  // measured: 0
}
