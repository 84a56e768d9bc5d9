// Numbers at the edges of the ranges a muscle file and a preset may hold (docs/muscle-json.md,
// docs/presets.md) are accepted, and what they bake is still valid glTF with no NaN (issue 34: a
// locator past the range once wrote NaN inverse bind matrices and "restLength": null). The bakes use
// the fuzz corpus's 80-triangle mannequin (tests/fuzz/make_seeds.py), a fraction of a second each.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "external_tools.h"

using namespace rigbake::test;
namespace ext = rigbake::test::external;

namespace {

// The JSON chunk of a GLB (nlohmann writes a NaN as null, so a null there is a NaN that got through).
std::string glbJsonChunk(const std::string& glb) {
  std::uint32_t length = 0;
  REQUIRE(glb.size() >= 20);
  std::memcpy(&length, glb.data() + 12, 4);
  REQUIRE(glb.size() >= 20 + length);
  return glb.substr(20, length);
}

// Bakes `extra` (--muscles or --preset) onto the small mannequin; checks the exit, the Khronos
// validator's verdict, that the model holds no null, and that the muscles it wrote read back.
void bakeAndCheck(const TempDir& dir, const std::string& name, const std::string& extra) {
  const std::string mannequin = ext::shellQuote(sourceDir() + "/tests/fuzz/character/mannequin.glb");
  const std::string glb = dir / (name + ".glb"), muscles = dir / (name + ".muscles.json");
  const CliResult run = runCli("bake " + mannequin + " " + extra + " -o " + glb + " --muscles-out " + muscles + " --stats " +
                               (dir / (name + ".stats.json")));
  INFO(name << "\n" << run.err);
  REQUIRE(run.exit_code == 0);
  const ext::ValidationSummary validation = ext::validateWithKhronos(glb);
  INFO(validation.raw);
  CHECK(validation.errors == 0);
  const std::string json = glbJsonChunk(slurp(glb));
  CHECK(json.find("null") == std::string::npos);
  CHECK(nlohmann::json::parse(json).contains("extensionsUsed"));
  // Every number the bake wrote into its muscle file is finite and within the ranges, or this fails.
  const CliResult again = runCli("bake " + mannequin + " --muscles " + muscles + " -o " + (dir / (name + ".again.glb")));
  INFO(again.err);
  CHECK(again.exit_code == 0);
}

}  // namespace

TEST_CASE("cli bake: muscle numbers at the edges of their ranges bake valid glTF with no NaN (Khronos)") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  TempDir dir;
  nlohmann::json arms = nlohmann::json::parse(slurp(sourceDir() + "/tests/fuzz/muscles/arms.json"));
  const double height = arms["rigbake"]["body_height"].get<double>();
  nlohmann::json& parts = arms["rigbake"]["muscles"];
  // Locators 98 body heights out (the joints' own offsets keep them inside the 100 allowed).
  const double far = 98.0 * height;
  parts["LeftBicep"]["origin"]["local"] = {far, 0.0, 0.0};
  parts["LeftBicep"]["insertion"]["local"] = {-far, 0.0, 0.0};
  parts["LeftBicep"]["driver"]["local"] = {0.0, far, 0.0};
  // Bulges and the weight radius at their bounds; response keys at the ends of `at`, with the largest
  // scale and the smallest positive one (a denormal).
  const double bulge = 99.9 * height, tiny = 5e-324;
  nlohmann::json& medial = parts["LeftTricepMedial"];
  medial["bulge"] = {bulge, -bulge};
  medial["weight_radius"] = 100.0 * height;
  medial["response"] = {
      {"ratio", {{{"at", 0.0}, {"bulge", {bulge, -bulge}}, {"scale", tiny}},
                 {{"at", 1.0}, {"bulge", {0.0, 0.0}}, {"scale", 1.0}},
                 {{"at", 100.0}, {"bulge", {-bulge, bulge}}, {"scale", 100.0}}}},
      {"twist_deg", {{{"at", -3600.0}, {"bulge", {bulge, 0.0}}, {"scale", 100.0}},
                     {{"at", 0.0}, {"bulge", {0.0, 0.0}}, {"scale", 1.0}},
                     {{"at", 3600.0}, {"bulge", {0.0, -bulge}}, {"scale", tiny}}}}};
  parts["RightTricepMedial"]["weight_radius"] = 0.0;
  std::ofstream(dir / "edges.json") << arms.dump();
  // --response keep: the curves above reach the bake as written, not refitted.
  bakeAndCheck(dir, "muscles", "--muscles " + (dir / "edges.json") + " --response keep");
}

TEST_CASE("cli bake: a preset at the edges of its ranges bakes valid glTF, or is refused when it places a muscle out of reach (Khronos)") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  TempDir dir;
  // The largest reference height: every offset shrinks to a 570th of its size, and the bake holds.
  nlohmann::json preset = nlohmann::json::parse(slurp(sourceDir() + "/presets/muscles/gow_biped.json"));
  preset["reference_height"] = 1000.0;
  std::ofstream(dir / "tall.json") << preset.dump();
  bakeAndCheck(dir, "tall", "--preset " + (dir / "tall.json"));

  // Every offset 99.9 reference heights long, every lerp 99.9 beyond its ends, bulges and weight radii
  // at 99.9 reference heights: each number is in its range, but together they place locators
  // kilometres from a 1.75 m body. Before, the bake wrote them (exit 0) into a muscle file its own
  // reader refused.
  const double edge = 99.9 * 1000.0;
  std::function<void(nlohmann::json&)> push = [&](nlohmann::json& value) {
    if (value.is_array()) {
      for (nlohmann::json& item : value) push(item);
      return;
    }
    if (!value.is_object()) return;
    for (auto it = value.begin(); it != value.end(); ++it) {
      if (it.key() == "ref_m" || it.key() == "weight_radius_ref_m") it.value() = edge;
      else if (it.key() == "t") it.value() = it.value().get<double>() > 0.5 ? 99.9 : -99.9;
      else if (it.key() == "bulge") it.value() = {edge, -edge};
      else push(it.value());
    }
  };
  push(preset["muscles"]);
  std::ofstream(dir / "edges.json") << preset.dump();
  const std::string mannequin = ext::shellQuote(sourceDir() + "/tests/fuzz/character/mannequin.glb");
  const CliResult run = runCli("bake " + mannequin + " --preset " + (dir / "edges.json") + " -o " + (dir / "edges.glb") +
                               " --muscles-out " + (dir / "edges.muscles.json"));
  INFO(run.err);
  CHECK(run.exit_code == 3);
  CHECK(lineCount(run.err) == 1);
  CHECK(run.err.rfind("PRESET_INVALID " + (dir / "edges.json") + "#/muscles/", 0) == 0);
  CHECK(run.err.find(" m from the origin; a muscle lies within 100 body heights (174.725 m)") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir / "edges.glb"));
  CHECK_FALSE(std::filesystem::exists(dir / "edges.muscles.json"));
}
