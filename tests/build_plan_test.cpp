// The batch build's plan as a module (pipeline/build_plan.h): the order that puts every muscles_from
// source first, the groups and shards, the output paths and the Ninja graph, on a manifest of the shared
// characters (tests/cli_build_test.cpp runs the builds themselves).
#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "pipeline/build_plan.h"
#include "test_support.h"

using namespace rigbake;

namespace {

BuildCharacter manifestCharacter(const std::string& name, const std::string& muscles_from, int index) {
  BuildCharacter c;
  c.name = name;
  c.input = "/assets/" + name + ".glb";
  c.preset = "/presets/muscles/gow_biped.json";
  c.muscles_from = muscles_from;
  c.pointer = "/characters/" + std::to_string(index);
  return c;
}

// CesiumMan takes its muscles from Soldier, Soldier from the mannequin; Fox and the mannequin stand
// alone (the mannequin's chain is the group "Mannequin").
BuildManifest retargetChainManifest() {
  BuildManifest manifest;
  manifest.file = "/work/build.json";
  manifest.out = "/work/out";
  manifest.characters = {manifestCharacter("CesiumMan", "Soldier", 0), manifestCharacter("Fox", "", 1), manifestCharacter("Soldier", "Mannequin", 2),
                         manifestCharacter("Mannequin", "", 3)};
  return manifest;
}

std::string buildOrderErrorCode(const BuildManifest& manifest, std::string* where) {
  try {
    buildOrder(manifest);
  } catch (const Error& error) {
    *where = error.where();
    return error.code();
  }
  return "";
}

}  // namespace

TEST_CASE("build plan: every muscles_from source is built before the characters that take from it", "[build-plan]") {
  const BuildManifest manifest = retargetChainManifest();
  // From CesiumMan the chain Mannequin, Soldier, CesiumMan; then Fox in manifest order.
  CHECK(buildOrder(manifest) == std::vector<int>{3, 2, 0, 1});
  CHECK(characterIndex(manifest, "Soldier") == 2);
  CHECK(characterIndex(manifest, "Nobody") == -1);
  // Without dependencies the order is the manifest's.
  BuildManifest plain = manifest;
  for (BuildCharacter& c : plain.characters) c.muscles_from.clear();
  CHECK(buildOrder(plain) == std::vector<int>{0, 1, 2, 3});
}

TEST_CASE("build plan: an unknown or cyclic muscles_from is MANIFEST_INVALID at its pointer", "[build-plan]") {
  BuildManifest unknown = retargetChainManifest();
  unknown.characters[1].muscles_from = "Nobody";
  std::string where;
  CHECK(buildOrderErrorCode(unknown, &where) == "MANIFEST_INVALID");
  CHECK(where == "/work/build.json#/characters/1/muscles_from");
  BuildManifest cycle = retargetChainManifest();
  cycle.characters[3].muscles_from = "CesiumMan";  // Mannequin -> CesiumMan -> Soldier -> Mannequin
  CHECK(buildOrderErrorCode(cycle, &where) == "MANIFEST_INVALID");
  CHECK(where.find("#/characters/") != std::string::npos);
  BuildManifest itself = retargetChainManifest();
  itself.characters[1].muscles_from = "Fox";
  CHECK(buildOrderErrorCode(itself, &where) == "MANIFEST_INVALID");
  CHECK(where == "/work/build.json#/characters/1/muscles_from");
}

TEST_CASE("build plan: a chain is one group, and every group lands on exactly one shard", "[build-plan]") {
  const BuildManifest manifest = retargetChainManifest();
  CHECK(buildGroup(manifest, 0) == "Mannequin");
  CHECK(buildGroup(manifest, 2) == "Mannequin");
  CHECK(buildGroup(manifest, 3) == "Mannequin");
  CHECK(buildGroup(manifest, 1) == "Fox");
  // Groups sorted by name (Fox, Mannequin) and dealt round-robin.
  CHECK(inShard(manifest, 1, 0, 2));
  CHECK(inShard(manifest, 0, 1, 2));
  for (int count = 1; count <= 4; ++count) {
    INFO("shards " << count);
    for (int c = 0; c < static_cast<int>(manifest.characters.size()); ++c) {
      int shards = 0;
      for (int index = 0; index < count; ++index) shards += inShard(manifest, c, index, count) ? 1 : 0;
      CHECK(shards == 1);
      // A retarget's source is on its shard.
      const std::string& from = manifest.characters[c].muscles_from;
      if (from.empty()) continue;
      for (int index = 0; index < count; ++index)
        CHECK(inShard(manifest, c, index, count) == inShard(manifest, characterIndex(manifest, from), index, count));
    }
  }
}

TEST_CASE("build plan: outputs under OUT/NAME and a Ninja graph in build order with escaped paths", "[build-plan]") {
  BuildManifest manifest = retargetChainManifest();
  const CharacterOutputs outputs = characterOutputs(manifest, manifest.characters[0]);
  CHECK(outputs.directory == "/work/out/CesiumMan");
  CHECK(outputs.model == "/work/out/CesiumMan/CesiumMan.glb");
  CHECK(outputs.muscles == "/work/out/CesiumMan/muscles.json");
  CHECK(outputs.report_json == "/work/out/CesiumMan/report.json");
  CHECK(outputs.report_junit == "/work/out/CesiumMan/report.junit.xml");
  CHECK(outputs.report_html == "/work/out/CesiumMan/report.html");
  CHECK(outputs.stamp == "/work/out/CesiumMan/.rigbake-inputs");

  manifest.characters[1].input = "/assets/my fox:1$.glb";  // Ninja escapes ' ', ':' and '$' with '$'
  // The commands are the CLI's (cli/cmd_build.cpp writes them); the file runs them as given.
  const std::string build = shellWord("/opt/rig'bake") + " build " + shellWord("/work/build.json");
  const std::string ninja = ninjaFile(manifest, "/work/build.json", {"rigbake build --emit-ninja", build + " --character $name", build + " --summary-only"});
  CHECK(ninja.rfind("# Written by `rigbake build --emit-ninja`: one edge per character.", 0) == 0);
  CHECK(ninja.find("command = '/opt/rig'\\''bake' build '/work/build.json' --character $name\n") != std::string::npos);
  CHECK(ninja.find("command = '/opt/rig'\\''bake' build '/work/build.json' --summary-only\n") != std::string::npos);
  CHECK(ninja.find("/assets/my$ fox$:1$$.glb") != std::string::npos);
  // One edge per character, in build order.
  std::vector<size_t> at;
  for (const char* name : {"Mannequin", "Soldier", "CesiumMan", "Fox"}) at.push_back(ninja.find("  name = " + std::string(name) + "\n"));
  for (size_t position : at) REQUIRE(position != std::string::npos);
  CHECK(std::is_sorted(at.begin(), at.end()));
  // CesiumMan's edge waits for Soldier's muscles and reads its input.
  const size_t cesium_edge = ninja.rfind("build ", at[2]);
  const std::string edge = ninja.substr(cesium_edge, at[2] - cesium_edge);
  CHECK(edge.find("/work/out/Soldier/muscles.json /assets/Soldier.glb") != std::string::npos);
  CHECK(ninja.find("build /work/out/summary.json /work/out/summary.junit.xml: rigbake_summary") != std::string::npos);
  CHECK(ninja.find("default /work/out/summary.json") != std::string::npos);
}
