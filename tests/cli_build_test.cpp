// `rigbake build` as a studio's CI runs it: a manifest of characters, some placed from the preset, one
// retargeted from another, one broken; in parallel and in order, incrementally, through Ninja and in
// shards.
#include <fcntl.h>
#include <sys/file.h>

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
  CHECK(run.exit_code == 4);
  CHECK(run.err.find("INTERNAL") == std::string::npos);
  const nlohmann::json summary = summaryOf(dir / "p/out");
  CHECK(statusOf(summary, "garbled") == "failed");
  CHECK(summary.dump().find("\\\\xA3") != std::string::npos);  // the escape, itself escaped in JSON
  CHECK(nlohmann::json::parse(run.out).size() == 1);
}

TEST_CASE("cli build: a landmark no joint matches asks for a naming map by the manifest's key, not bake's flag") {
  test::TempDir dir;
  fs::create_directories(dir / "p");
  copyFile(test::sampleGlbPathForCli(), dir / "p/hero.glb");
  // The Mixamo map finds none of the sample's JO* joints: the character fails before its bake.
  const nlohmann::json manifest = {{"preset", "gow_biped"}, {"influences", 4}, {"out", "out"},
                                   {"characters", {{{"name", "hero"}, {"input", "hero.glb"}, {"map", "mixamo"}}}}};
  const std::string path = dir / "p/manifest.json";
  std::ofstream(path) << manifest.dump(2);
  test::CliResult run = runCli("build " + ext::shellQuote(path));
  INFO(run.err);
  CHECK(run.exit_code == 4);
  const nlohmann::json summary = summaryOf(dir / "p/out");
  CHECK(statusOf(summary, "hero") == "failed");
  const std::string error = summary["characters"][0]["error"];
  CHECK(error.rfind("LANDMARK_UNRESOLVED ", 0) == 0);
  CHECK(error.find("give a JSON naming map (as " + path + "#/characters/0/map)") != std::string::npos);
  CHECK(error.find("--map") == std::string::npos);
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
  CHECK(run.exit_code == 4);
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
      // bake's options: hits and spring bones need a jiggle, and every preset must exist.
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"hits", "hits.json"}}}}},
       "#/characters/0: gives hits but no jiggle"},
      {{{"out", "out"}, {"vrm_springs_only", true}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}},
       "#/characters/0: sets vrm_springs_only but gives no jiggle"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"jiggle", "no_such_jiggle"}}}}},
       "#/characters/0/jiggle"},
      {{{"out", "out"}, {"regions", "no_such_regions"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}},
       "#/regions"},
      {{{"out", "out"}, {"fit_poses", 0}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}}, "#/fit_poses"},
      {{{"out", "out"}, {"fit_smoothness", -3}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}},
       "#/fit_smoothness"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"fit_smoothness", "smooth"}}}}},
       "#/characters/0/fit_smoothness"},
      {{{"out", "out"}, {"fit_roughness_cap", 0.5}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}},
       "#/fit_roughness_cap: must be 0 (no cap) or from 1 to 100"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"fit_roughness_cap", 200}}}}},
       "#/characters/0/fit_roughness_cap"},
      {{{"out", "out"}, {"fit_volume", "area"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}}, "#/fit_volume"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"fit_volume", true}}}}}, "#/characters/0/fit_volume"},
      {{{"out", "out"}, {"fit_regions", "all"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}}}}},
       "#/fit_regions: must be \"fitted-poses\" or \"every-frame\""},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"fit_regions", 1}}}}}, "#/characters/0/fit_regions"},
      {{{"out", "out"}, {"characters", {{{"name", "a"}, {"input", "hero.glb"}, {"fps", -1}}}}}, "#/characters/0/fps"},
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

namespace {

// A project folder `sub` holding sample.glb and manifest.json: one character, `sample`, at `influences`,
// into sub/out (or `out`). The response is kept, which halves the bake; these tests are about the build.
std::string writeBuildProject(const test::TempDir& dir, const std::string& sub, int influences,
                              const nlohmann::json& extra_characters = nlohmann::json::array(),
                              const std::string& out = "out") {
  fs::create_directories(dir / sub);
  fs::copy_file(test::sampleGlbPathForCli(), dir / (sub + "/sample.glb"), fs::copy_options::overwrite_existing);
  nlohmann::json characters = {{{"name", "sample"}, {"input", "sample.glb"}}};
  for (const auto& c : extra_characters) characters.push_back(c);
  const nlohmann::json manifest = {
      {"influences", influences}, {"response", "keep"}, {"out", out}, {"characters", characters}};
  const std::string path = dir / (sub + "/manifest.json");
  std::ofstream(path) << manifest.dump(2);
  return path;
}

}  // namespace

TEST_CASE("cli build: outputs replaced after their stamp was written are rebuilt, never up-to-date") {
  // The state a build killed right after renaming a new sample.glb into place left (issue 34): the old
  // stamp, for influences 10, beside the 4-influence model and muscles of the interrupted run.
  test::TempDir dir;
  const std::string manifest10 = writeBuildProject(dir, "p", 10);
  const std::string manifest4 = writeBuildProject(dir, "q", 4);
  REQUIRE(runCli("build " + ext::shellQuote(manifest10) + " -j 1").exit_code == 0);
  REQUIRE(runCli("build " + ext::shellQuote(manifest4) + " -j 1").exit_code == 0);
  const std::string built10 = slurp(dir / "p/out/sample/sample.glb");
  REQUIRE(built10 != slurp(dir / "q/out/sample/sample.glb"));
  for (const char* file : {"sample.glb", "muscles.json"})
    fs::copy_file(dir / ("q/out/sample/" + std::string(file)), dir / ("p/out/sample/" + std::string(file)),
                  fs::copy_options::overwrite_existing);
  const test::CliResult rerun = runCli("build " + ext::shellQuote(manifest10) + " -j 1");
  INFO(rerun.err);
  CHECK(rerun.exit_code == 0);
  CHECK(rerun.err.find("sample: built") != std::string::npos);
  CHECK(statusOf(summaryOf(dir / "p/out"), "sample") == "built");
  CHECK(slurp(dir / "p/out/sample/sample.glb") == built10);
  // And unchanged outputs are still skipped.
  const test::CliResult again = runCli("build " + ext::shellQuote(manifest10) + " -j 1");
  CHECK(again.err.find("sample: up-to-date") != std::string::npos);
}

TEST_CASE("cli build: a second build into a folder another build holds stops at once with one line") {
  test::TempDir dir;
  const std::string manifest = writeBuildProject(dir, "p", 4);
  fs::create_directories(dir / "p/out");
  // This test process plays the first build: it holds the lock a build takes.
  const int fd = ::open((dir / "p/out/.rigbake-lock").c_str(), O_RDWR | O_CREAT, 0644);
  REQUIRE(fd >= 0);
  REQUIRE(::flock(fd, LOCK_EX) == 0);
  const test::CliResult refused = runCli("build " + ext::shellQuote(manifest));
  ::close(fd);
  INFO(refused.err);
  CHECK(refused.exit_code == 2);
  CHECK(test::lineCount(refused.err) == 1);
  CHECK(refused.err.rfind("BUILD_OUTPUT_LOCKED " + (dir / "p/out") + ":", 0) == 0);
  CHECK(!fs::exists(dir / "p/out/sample"));
  CHECK(!fs::exists(dir / "p/out/summary.json"));
  // Released, the same build runs.
  CHECK(runCli("build " + ext::shellQuote(manifest)).exit_code == 0);
}

TEST_CASE("cli build: temporary files a killed run left in the output folder are removed by the next build") {
  test::TempDir dir;
  const std::string manifest = writeBuildProject(dir, "p", 4);
  REQUIRE(runCli("build " + ext::shellQuote(manifest)).exit_code == 0);
  const std::vector<std::string> leftovers = {"p/out/summary.json.rigbake-tmp-Ab12Cd", "p/out/sample/sample.glb.rigbake-tmp-x9Y8z7"};
  for (const std::string& leftover : leftovers) std::ofstream(dir / leftover) << "half a file";
  std::ofstream(dir / "p/out/sample/notes.txt") << "mine";
  // Another program's temporary file (a `rigbake bake -o` into the same folder, running now) is not the
  // build's to remove.
  std::ofstream(dir / "p/out/sample/other.glb.rigbake-tmp-Qr5St6") << "being written";
  const test::CliResult run = runCli("build " + ext::shellQuote(manifest));
  INFO(run.err);
  CHECK(run.exit_code == 0);
  for (const std::string& leftover : leftovers) CHECK(!fs::exists(dir / leftover));
  CHECK(slurp(dir / "p/out/sample/notes.txt") == "mine");
  CHECK(slurp(dir / "p/out/sample/other.glb.rigbake-tmp-Qr5St6") == "being written");
}

TEST_CASE("cli build: file-system problems are IO_* lines naming the path, never INTERNAL") {
  test::TempDir dir;
  SECTION("out is a regular file") {
    const std::string manifest = writeBuildProject(dir, "p", 4, nlohmann::json::array(), "taken");
    std::ofstream(dir / "p/taken") << "a file";
    const test::CliResult run = runCli("build " + ext::shellQuote(manifest));
    INFO(run.err);
    CHECK(run.exit_code == 2);
    CHECK(test::lineCount(run.err) == 1);
    CHECK(run.err.rfind("IO_WRITE_FAILED " + (dir / "p/taken") + ":", 0) == 0);
    CHECK(slurp(dir / "p/taken") == "a file");
  }
  SECTION("out has a component longer than the file system allows") {
    const std::string manifest = writeBuildProject(dir, "p", 4, nlohmann::json::array(), std::string(300, 'o'));
    const test::CliResult run = runCli("build " + ext::shellQuote(manifest));
    INFO(run.err);
    CHECK(run.exit_code == 2);
    CHECK(test::lineCount(run.err) == 1);
    CHECK(run.err.rfind("IO_WRITE_FAILED " + (dir / ("p/" + std::string(300, 'o'))) + ":", 0) == 0);
  }
  SECTION("the manifest read through a pipe: its relative out is under /dev/fd") {
    const std::string manifest = writeBuildProject(dir, "p", 4);
    nlohmann::json json = nlohmann::json::parse(slurp(manifest));
    json["characters"][0]["input"] = dir / "p/sample.glb";
    const ext::CommandResult run = ext::runCommand("echo " + ext::shellQuote(json.dump()) + " | " + std::string(rigbake::test::kRigbakeCli) +
                                                   " build /dev/fd/3 3<&0 2>&1 </dev/null");
    INFO(run.output);
    CHECK(run.exit_code == 2);
    CHECK(test::lineCount(run.output) == 1);
    CHECK(run.output.rfind("IO_WRITE_FAILED /dev/fd/out:", 0) == 0);
  }
  SECTION("an empty out is a manifest error") {
    const std::string manifest = writeBuildProject(dir, "p", 4, nlohmann::json::array(), "");
    const test::CliResult run = runCli("build " + ext::shellQuote(manifest));
    INFO(run.err);
    CHECK(run.exit_code == 3);
    CHECK(run.err.rfind("MANIFEST_INVALID " + manifest + "#/out:", 0) == 0);
  }
}

TEST_CASE("cli build: a character whose muscles_from source failed has a coded line too") {
  test::TempDir dir;
  fs::create_directories(dir / "p");
  std::ofstream(dir / "p/broken.glb") << "glTF but not really";
  const std::string manifest =
      writeBuildProject(dir, "p", 4, {{{"name", "broken"}, {"input", "broken.glb"}},
                                      {{"name", "follower"}, {"input", "sample.glb"}, {"muscles_from", "broken"}}});
  const test::CliResult run = runCli("build " + ext::shellQuote(manifest) + " -j 1");
  INFO(run.err);
  CHECK(run.exit_code == 4);
  CHECK(run.err.find("FAILED follower: BUILD_SOURCE_FAILED " + manifest + "#/characters/2/muscles_from: muscles_from character 'broken' failed") !=
        std::string::npos);
  const auto summary = nlohmann::json::parse(slurp(dir / "p/out/summary.json"));
  CHECK(summary["characters"][2]["error"].get<std::string>().rfind("BUILD_SOURCE_FAILED ", 0) == 0);
}

TEST_CASE("cli build: a character name that is too long or not one printable line is MANIFEST_INVALID") {
  test::TempDir dir;
  for (const std::string& name : {std::string(129, 'n'), std::string("two\nlines"), std::string("bell\x07")}) {
    const std::string manifest = writeBuildProject(dir, "p", 4, {{{"name", name}, {"input", "sample.glb"}}});
    const test::CliResult run = runCli("build " + ext::shellQuote(manifest));
    INFO(run.err);
    CHECK(run.exit_code == 3);
    CHECK(test::lineCount(run.err) == 1);
    CHECK(run.err.rfind("MANIFEST_INVALID " + manifest + "#/characters/1/name:", 0) == 0);
    CHECK(run.err.size() < 400);
    CHECK(!fs::exists(dir / "p/out"));
  }
}

TEST_CASE("cli build: --emit-ninja '' is USAGE, not a build") {
  test::TempDir dir;
  const std::string manifest = writeBuildProject(dir, "p", 4);
  const test::CliResult run = runCli("build " + ext::shellQuote(manifest) + " --emit-ninja ''");
  INFO(run.err);
  CHECK(run.exit_code == 1);
  CHECK(run.err.rfind("USAGE --emit-ninja:", 0) == 0);
  CHECK(!fs::exists(dir / "p/out"));
}

TEST_CASE("cli build: a character bakes with bake's map, regions, jiggle, hits, fps, fit poses, smoothness and roughness cap and spring bones, byte for byte as `rigbake bake` does") {
  test::TempDir dir;
  copyFile(test::sampleGlbPathForCli(), dir / "hero.glb");
  REQUIRE(runCli("sample --vrm 1 -o " + ext::shellQuote(dir / "hero1.vrm")).exit_code == 0);
  std::ofstream(dir / "hits.json") << R"({"hits": [{"clip": "ArmRaise", "time": 0.5, "direction": [0, 0, 1], "magnitude": 1.5, "joints": ["LeftBicep"], "why": "a punch"}]})";
  const nlohmann::json manifest = {
      {"out", "out"}, {"response", "keep"}, {"stats", true}, {"packed", true}, {"jiggle", "biceps"},
      {"characters",
       {{{"name", "hero"}, {"input", "hero.glb"}, {"influences", 4}, {"map", "gow"}, {"regions", "body"}, {"hits", "hits.json"},
         {"fps", 20}, {"response", "fit"}, {"fit_poses", 4}, {"fit_smoothness", 500}, {"fit_roughness_cap", 1.5},
         {"fit_volume", "occupied"}},
        {{"name", "springy"}, {"input", "hero1.vrm"}, {"vrm_springs_only", true}},
        {{"name", "plain"}, {"input", "hero.glb"}, {"vrm_springs_only", true}},
        {{"name", "regions"}, {"input", "hero.glb"}, {"influences", 4}, {"response", "auto"}, {"fit_regions", "every-frame"}}}}};
  std::ofstream(dir / "manifest.json") << manifest.dump(2);
  const test::CliResult build = runCli("build -j 2 " + ext::shellQuote(dir / "manifest.json"));
  INFO(build.err);
  // Spring bones need a VRM: that character fails, naming the manifest key, and the others are built.
  CHECK(build.exit_code == 4);
  CHECK(build.err.find("FAILED plain: MANIFEST_INVALID " + dir / "manifest.json" + "#/characters/2/vrm_springs_only: " +
                       dir / "hero.glb" + " is not a VRM, so there is nowhere to put spring bones") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "out/plain/plain.glb"));
  const std::string bake_dir = dir / "bake";
  fs::create_directories(bake_dir);
  auto bake = [&](const std::string& input, const std::string& name, const std::string& flags) {
    const test::CliResult run = runCli("bake " + ext::shellQuote(dir / input) + " -o " + ext::shellQuote(bake_dir + "/" + name + ".glb") +
                                       " --jiggle biceps --stats " + ext::shellQuote(bake_dir + "/" + name + ".stats.json") +
                                       " --packed-out " + ext::shellQuote(bake_dir + "/" + name + ".rbpk") + " --muscles-out " +
                                       ext::shellQuote(bake_dir + "/" + name + ".muscles.json") + " " + flags);
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
  };
  bake("hero.glb", "hero", "--influences 4 --map gow --regions body --hits " + ext::shellQuote(dir / "hits.json") +
                               " --fps 20 --response fit --fit-poses 4 --fit-smoothness 500 --fit-roughness-cap 1.5 --fit-volume occupied");
  bake("hero1.vrm", "springy", "--vrm-springs-only --response keep --influences 10");  // build's default: 10
  bake("hero.glb", "regions", "--influences 4 --fit-regions every-frame");
  for (const std::string name : {"hero", "springy", "regions"}) {
    INFO(name);
    const std::string built = dir / ("out/" + name + "/");
    CHECK(slurp(built + name + ".glb") == slurp(bake_dir + "/" + name + ".glb"));
    CHECK(slurp(built + "stats.json") == slurp(bake_dir + "/" + name + ".stats.json"));
    CHECK(slurp(built + name + ".rbpk") == slurp(bake_dir + "/" + name + ".rbpk"));
  }
  // The muscle file names the character it was baked on, which build calls NAME.glb: hero's is hero.glb.
  CHECK(slurp(dir / "out/hero/muscles.json") == slurp(bake_dir + "/hero.muscles.json"));
  // The jiggles went where bake puts them: into the rig (hero), and as VRM spring bones (springy).
  const nlohmann::json hero = test::glbJson(slurp(dir / "out/hero/hero.glb"));
  CHECK(hero["extensions"]["RIGBAKE_muscle_rig"]["jiggles"].size() == 2);
  CHECK(test::glbJson(slurp(dir / "out/springy/springy.glb"))["extensions"]["VRMC_springBone"]["springs"].size() == 2);
  const nlohmann::json stats = nlohmann::json::parse(slurp(dir / "out/hero/stats.json"));
  CHECK(stats["influences"] == 4);
  CHECK(stats["clips"] == 3);
  // The validation read the file with the same map: its landmark check passed.
  const nlohmann::json report = nlohmann::json::parse(slurp(dir / "out/hero/report.json"));
  for (const auto& check : report["checks"])
    if (check["code"] == "LANDMARKS_RESOLVED") CHECK(check["status"] == "pass");
  // A --map for all would not be in the stamps: build refuses it.
  const test::CliResult map = runCli("build --map gow " + ext::shellQuote(dir / "manifest.json"));
  CHECK(map.exit_code == 1);
  CHECK(map.err.rfind("USAGE --map: ", 0) == 0);
}
