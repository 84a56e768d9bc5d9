// `rigbake build` as a studio's CI runs it: a manifest of characters, some placed from the preset, one
// retargeted from another, one broken; in parallel and in order, incrementally, through Ninja and in
// shards.
#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_support.h"
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

int countOf(const std::string& text, const std::string& needle) {
  int count = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++count;
  return count;
}

const char* kOutputs[] = {"muscles.json", "report.json", "report.junit.xml", "report.html"};

void copyFile(const std::string& from, const std::string& to) {
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

// A project folder `sub` with hero.glb and manifest.json (outputs to sub/out): hero, the sample, placed
// from the preset; cesium, CesiumMan, muscles retargeted from hero; kaykit, the KayKit mannequin (a
// .gltf whose buffers are separate files, which the content hash must cover) at 7 influences. `extra` characters are appended as given. Returns the manifest's path.
std::string writeManifest(const test::TempDir& dir, const std::string& sub, const nlohmann::json& extra = nlohmann::json::array()) {
  fs::create_directories(dir / sub);
  copyFile(test::sampleGlbPathForCli(), dir / (sub + "/hero.glb"));
  nlohmann::json characters = nlohmann::json::array();
  characters.push_back({{"name", "hero"}, {"input", "hero.glb"}});
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  const std::string kaykit = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (!cesium.empty()) characters.push_back({{"name", "cesium"}, {"input", cesium}, {"muscles_from", "hero"}});
  if (!kaykit.empty()) characters.push_back({{"name", "kaykit"}, {"input", kaykit}, {"influences", 7}});
  for (const auto& c : extra) characters.push_back(c);
  // These tests are about the build (outputs, summaries, incremental rebuilds, Ninja, shards), not the
  // response fit, which the bake and deformation-quality tests cover: the preset's response is kept,
  // which halves each bake (the fit is half of it; under the sanitizers 6 of a mannequin's 10 s).
  const nlohmann::json manifest = {{"preset", "gow_biped"}, {"influences", 10}, {"response", "keep"}, {"out", "out"}, {"characters", characters}};
  const std::string path = dir / (sub + "/manifest.json");
  std::ofstream(path) << manifest.dump(2);
  return path;
}

// Every file under `root`, relative path -> bytes.
std::map<std::string, std::string> filesUnder(const std::string& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) files[fs::relative(entry.path(), root).string()] = slurp(entry.path().string());
  }
  return files;
}

nlohmann::json summaryOf(const std::string& out_dir) { return nlohmann::json::parse(slurp(out_dir + "/summary.json")); }

std::string statusOf(const nlohmann::json& summary, const std::string& name) {
  for (const auto& c : summary["characters"]) {
    if (c["name"] == name) return c["status"];
  }
  return "absent";
}

std::vector<std::string> namesBuilt(const std::string& json_out) {
  std::vector<std::string> names;
  for (const auto& c : nlohmann::json::parse(json_out)) names.push_back(c["name"]);
  return names;
}

}  // namespace

TEST_CASE("cli build: a character whose file puts invalid UTF-8 into its error fails alone, and the summary is still JSON") {
  // The JSON parser's message quotes the bytes it read; written raw into summary.json it made the
  // summary's own JSON writer throw, and the whole build end in INTERNAL (exit 5) with no summary.
  test::TempDir dir;
  std::string glb = slurp(test::sampleGlbPathForCli());
  const size_t at = glb.find("\"asset\"");
  REQUIRE(at != std::string::npos);
  glb[at + 1] = '\xA3';
  fs::create_directories(dir / "p");
  std::ofstream(dir / "p/garbled.glb", std::ios::binary) << glb;
  const nlohmann::json manifest = {{"preset", "gow_biped"}, {"influences", 4}, {"out", "out"},
                                   {"characters", {{{"name", "garbled"}, {"input", "garbled.glb"}}}}};
  std::ofstream(dir / "p/manifest.json") << manifest.dump(2);
  test::CliResult run = runCli("build " + ext::shellQuote(dir / "p/manifest.json") + " --json");
  INFO(run.err);
  CHECK(run.exit_code == 1);
  CHECK(run.err.find("INTERNAL") == std::string::npos);
  const nlohmann::json summary = summaryOf(dir / "p/out");
  CHECK(statusOf(summary, "garbled") == "failed");
  CHECK(summary.dump().find("\\\\xA3") != std::string::npos);  // the escape, itself escaped in JSON
  CHECK(nlohmann::json::parse(run.out).size() == 1);
}

TEST_CASE("cli build: every character gets its outputs and a summary, a broken one fails the run, not the others") {
  test::TempDir dir;
  // A truncated GLB: the loader must reject it, and the build must go on with the others.
  const std::string hero_bytes = slurp(test::sampleGlbPathForCli());
  fs::create_directories(dir / "p");
  std::ofstream(dir / "p/broken.glb", std::ios::binary) << hero_bytes.substr(0, hero_bytes.size() / 3);
  const std::string manifest = writeManifest(dir, "p", nlohmann::json::array({{{"name", "broken"}, {"input", "broken.glb"}}}));
  test::CliResult run = runCli("build " + ext::shellQuote(manifest) + " -j 2 --progress always");
  INFO(run.err);
  CHECK(run.exit_code == 1);
  CHECK(run.err.find("FAILED broken: GLTF_PARSE_FAILED") != std::string::npos);
  CHECK(run.err.find("BUILD_FAILED") != std::string::npos);
  CHECK(run.err.find("] hero: built") != std::string::npos);  // a line per character as it finishes
  // --progress always: what is done and what runs, as it changes.
  CHECK(run.err.find("rigbake build: 0 of ") != std::string::npos);
  CHECK(run.err.find("characters done; building hero") != std::string::npos);

  const nlohmann::json summary = summaryOf(dir / "p/out");
  CHECK(statusOf(summary, "hero") == "built");
  CHECK(statusOf(summary, "broken") == "failed");
  CHECK(summary["counts"]["failed"] == 1);
  const std::string junit = slurp(dir / "p/out/summary.junit.xml");
  CHECK(countOf(junit, "<testcase ") == static_cast<int>(summary["characters"].size()));
  CHECK(countOf(junit, "<failure ") == 1);

  for (const auto& c : summary["characters"]) {
    const std::string name = c["name"];
    const std::string folder = dir / ("p/out/" + name);
    if (name == "broken") {
      CHECK_FALSE(fs::exists(folder + "/broken.glb"));
      CHECK_FALSE(fs::exists(folder + "/report.json"));
      continue;
    }
    INFO(name);
    CHECK(c["status"] == "built");
    CHECK(fs::file_size(folder + "/" + name + ".glb") > 100000);
    for (const char* file : kOutputs) CHECK(fs::exists(folder + "/" + file));
    const nlohmann::json report = nlohmann::json::parse(slurp(folder + "/report.json"));
    CHECK(report["passed"] == true);
    CHECK(report["character"] == name + ".glb");
    // 28 muscles and the armpit correctives on the joints each skeleton resolves: 10 parts on the
    // mannequin, 6 on KayKit (its clavicle and scapula landmarks ride one joint with the chest's).
    CHECK(report["character_stats"]["muscles"].get<int>() >= 34);
    if (name == "hero") CHECK(report["character_stats"]["muscles"] == 38);
  }
  // No temporary file is left behind by the atomic writes.
  for (const auto& entry : fs::recursive_directory_iterator(dir.path)) {
    CHECK(entry.path().string().find(".rigbake-tmp-") == std::string::npos);
  }
}

TEST_CASE("cli build: outputs are byte-identical whatever -j, and unchanged characters are skipped by content") {
  test::TempDir dir;
  const std::string serial = writeManifest(dir, "serial");
  const std::string parallel = writeManifest(dir, "parallel");
  REQUIRE(runCli("build " + ext::shellQuote(serial) + " -j 1").exit_code == 0);
  REQUIRE(runCli("build " + ext::shellQuote(parallel) + " -j 3").exit_code == 0);
  const auto serial_files = filesUnder(dir / "serial/out"), parallel_files = filesUnder(dir / "parallel/out");
  CHECK(serial_files.size() >= 6);
  CHECK(serial_files == parallel_files);

  // Nothing changed: every character is up to date and no file changes.
  test::CliResult again = runCli("build " + ext::shellQuote(parallel) + " --json");
  INFO(again.err);
  REQUIRE(again.exit_code == 0);
  nlohmann::json summary = summaryOf(dir / "parallel/out");
  CHECK(summary["counts"]["up_to_date"] == summary["counts"]["total"]);
  auto unchanged = filesUnder(dir / "parallel/out");
  unchanged.erase("summary.json");  // now says up-to-date instead of built
  auto before = parallel_files;
  before.erase("summary.json");
  CHECK(unchanged == before);

  // Rewriting the same bytes is not a change (content hashes, not timestamps).
  copyFile(test::sampleGlbPathForCli(), dir / "parallel/hero.glb");
  REQUIRE(runCli("build " + ext::shellQuote(parallel)).exit_code == 0);
  CHECK(statusOf(summaryOf(dir / "parallel/out"), "hero") == "up-to-date");

  // A different hero rebuilds hero; the KayKit mannequin, which does not depend on it, stays up to date.
  REQUIRE(runCli("sample --vertices 4000 -o " + ext::shellQuote(dir / "parallel/hero.glb")).exit_code == 0);
  test::CliResult changed = runCli("build " + ext::shellQuote(parallel));
  INFO(changed.err);
  REQUIRE(changed.exit_code == 0);
  summary = summaryOf(dir / "parallel/out");
  CHECK(statusOf(summary, "hero") == "built");
  if (statusOf(summary, "kaykit") != "absent") CHECK(statusOf(summary, "kaykit") == "up-to-date");
  CHECK(slurp(dir / "parallel/out/hero/hero.glb") != parallel_files.at("hero/hero.glb"));
}

TEST_CASE("cli build: gltf_weights picks each character's WEIGHTS_n precision, and changing it rebuilds") {
  test::TempDir dir;
  const nlohmann::json fine = {{{"name", "fine"}, {"input", "hero.glb"}, {"gltf_weights", "unorm16"}}};
  const std::string manifest = writeManifest(dir, "p", fine);
  REQUIRE(runCli("build " + ext::shellQuote(manifest)).exit_code == 0);
  CHECK(test::largestOffMilliLattice(dir / "p/out/hero/hero.glb") < 1000.0 / 65535.0);
  CHECK(test::largestOffMilliLattice(dir / "p/out/fine/fine.glb") > 0.1);
  // The same character at the manifest's default precision is a different build.
  nlohmann::json edited = nlohmann::json::parse(slurp(manifest));
  for (auto& character : edited["characters"]) character.erase("gltf_weights");
  edited["gltf_weights"] = "unorm16";
  std::ofstream(manifest) << edited.dump(2);
  test::CliResult again = runCli("build " + ext::shellQuote(manifest));
  INFO(again.err);
  REQUIRE(again.exit_code == 0);
  const nlohmann::json summary = summaryOf(dir / "p/out");
  CHECK(statusOf(summary, "hero") == "built");
  CHECK(statusOf(summary, "fine") == "up-to-date");
  CHECK(test::largestOffMilliLattice(dir / "p/out/hero/hero.glb") > 0.1);
}

TEST_CASE("cli build: --emit-ninja writes a graph that ninja builds into the same files as a direct build") {
  if (!ext::requireTool(ext::onPath("ninja"), "ninja (Debian package ninja-build)")) return;
  test::TempDir dir;
  const std::string direct = writeManifest(dir, "direct");
  const std::string graph = writeManifest(dir, "graph");
  REQUIRE(runCli("build " + ext::shellQuote(direct)).exit_code == 0);
  test::CliResult emit = runCli("build " + ext::shellQuote(graph) + " --emit-ninja " + ext::shellQuote(dir / "build.ninja"));
  INFO(emit.err);
  REQUIRE(emit.exit_code == 0);
  CHECK_FALSE(fs::exists(dir / "graph/out"));  // emitting builds nothing
  const std::string ninja_file = slurp(dir / "build.ninja");
  CHECK(ninja_file.find("--character hero") == std::string::npos);  // the name is a variable of the edge
  CHECK(countOf(ninja_file, ": rigbake_character ") >= 2);

  ext::CommandResult ninja = ext::runCommand("ninja -f " + ext::shellQuote(dir / "build.ninja") + " 2>&1");
  INFO(ninja.output);
  REQUIRE(ninja.exit_code == 0);
  // Ninja keeps its log beside the outputs (builddir), not in the directory it was started from.
  CHECK(fs::exists(dir / "graph/out/.ninja_log"));
  auto graph_files = filesUnder(dir / "graph/out");
  graph_files.erase(".ninja_log");
  graph_files.erase(".ninja_deps");
  CHECK(graph_files == filesUnder(dir / "direct/out"));
  // A second ninja run has nothing to do.
  ext::CommandResult noop = ext::runCommand("ninja -f " + ext::shellQuote(dir / "build.ninja") + " 2>&1");
  CHECK(noop.output.find("no work to do") != std::string::npos);
}

TEST_CASE("cli build: --shard I/N puts every character on exactly one shard, with its muscles_from source") {
  test::TempDir dir;
  const std::string manifest = writeManifest(dir, "p", nlohmann::json::array({{{"name", "twin"}, {"input", "hero.glb"}}}));
  std::vector<std::string> all;
  const nlohmann::json parsed = nlohmann::json::parse(slurp(manifest));
  for (const auto& c : parsed["characters"]) all.push_back(c["name"]);
  std::set<std::string> seen;
  std::vector<std::vector<std::string>> shards;
  for (int shard = 0; shard < 2; ++shard) {
    test::CliResult run = runCli("build " + ext::shellQuote(manifest) + " --shard " + std::to_string(shard) + "/2 --json");
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    shards.push_back(namesBuilt(run.out));
    for (const std::string& name : shards.back()) CHECK(seen.insert(name).second);
    // Deterministic: the same shard again selects the same characters (now up to date).
    CHECK(namesBuilt(runCli("build " + ext::shellQuote(manifest) + " --shard " + std::to_string(shard) + "/2 --json").out) ==
          shards.back());
  }
  CHECK(seen == std::set<std::string>(all.begin(), all.end()));
  CHECK_FALSE(shards[0].empty());
  CHECK_FALSE(shards[1].empty());
  for (const auto& shard : shards) {
    const bool has_hero = std::count(shard.begin(), shard.end(), "hero") > 0;
    const bool has_cesium = std::count(shard.begin(), shard.end(), "cesium") > 0;
    if (std::count(all.begin(), all.end(), "cesium")) CHECK(has_hero == has_cesium);
  }
  test::CliResult bad = runCli("build " + ext::shellQuote(manifest) + " --shard 2/2");
  CHECK(bad.exit_code == 1);
  CHECK(bad.err.rfind("USAGE --shard", 0) == 0);
}

TEST_CASE("cli build: a malformed manifest is MANIFEST_INVALID with its JSON pointer, and nothing is built") {
  test::TempDir dir;
  copyFile(test::sampleGlbPathForCli(), dir / "hero.glb");
  struct Case {
    nlohmann::json manifest;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{{"out", "out"}, {"charaters", nlohmann::json::array()}}, "#/charaters"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"muscles_from", "nobody"}}}}}, "nobody"},
      {{{"out", "out"}, {"influences", 5}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}}, "#/influences"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"gltf_weights", "half"}}}}},
       "#/characters/0/gltf_weights"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}, {{"name", "a"}, {"input", "hero.glb"}}}}},
       "duplicate"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / "m.json") << c.manifest.dump();
    test::CliResult run = runCli("build " + ext::shellQuote(dir / "m.json"));
    INFO(run.err);
    CHECK(run.exit_code == 3);
    CHECK(run.err.rfind("MANIFEST_INVALID ", 0) == 0);
    CHECK(run.err.find(c.expected) != std::string::npos);
    CHECK(test::lineCount(run.err) == 1);
    CHECK_FALSE(fs::exists(dir / "out"));
  }
}
