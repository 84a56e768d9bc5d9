// `rigbake bake --vrm 1` on a VRM 0.x avatar: the output is a VRM 1.0 (VRMC_vrm with every 0.x humanoid
// bone under its 1.0 name, the meta permissions, VRMC_springBone with every 0.x spring joint and
// collider), it faces +Z, carries the helper joints' VRMC_node_constraint and passes the Khronos
// validator; impossible version changes are refused with one coded line and no file.
//
// The input is the sample's VRM 0.x variant (faces -Z, as UniVRM exports) with a secondaryAnimation of
// the shape UniVRM writes added to it: the sample itself has no spring bones, and the shared assets
// hold no VRM.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/gltf_document.h"
#include "formats/vrm0_to_vrm1.h"
#include "glb_support.h"
#include "test_support.h"

#include <catch2/catch.hpp>

using namespace rigbake;
namespace ext = rigbake::test::external;
using rigbake::test::runCli;
using rigbake::test::slurp;

namespace vrm_convert_test {

// `glb` with its JSON chunk replaced by `json` (padded with spaces to 4 bytes, as GLB asks).
std::string withJson(const std::string& glb, const nlohmann::json& json) {
  std::uint32_t old_length = 0;
  std::memcpy(&old_length, glb.data() + 12, 4);
  std::string text = json.dump();
  while (text.size() % 4 != 0) text += ' ';
  const std::string rest = glb.substr(20 + old_length);
  std::string out = glb.substr(0, 12);
  const std::uint32_t length = static_cast<std::uint32_t>(text.size());
  out.append(reinterpret_cast<const char*>(&length), 4);
  out += "JSON";
  out += text;
  out += rest;
  const std::uint32_t total = static_cast<std::uint32_t>(out.size());
  std::memcpy(&out[8], &total, 4);
  return out;
}

int humanNode(const nlohmann::json& vrm0, const std::string& bone) {
  for (const auto& entry : vrm0["humanoid"]["humanBones"])
    if (entry["bone"] == bone) return entry["node"].get<int>();
  return -1;
}

// The sample as VRM 0.x with two bone groups and three collider groups, values in 0.x's Unity axes:
// both toes (leaves, so each gets a 7 cm tail) under a slanted gravity, and the left shoulder, whose
// joint branches into the clavicle's leaf helpers and the arm, colliding with the head and right hand.
std::string sampleVrm0WithSprings(const test::TempDir& dir) {
  const std::string plain = dir / "plain0.vrm";
  REQUIRE(runCli("sample --vrm 0 -o " + ext::shellQuote(plain)).exit_code == 0);
  const std::string bytes = slurp(plain);
  nlohmann::json json = test::glbJson(bytes);
  nlohmann::json& vrm = json["extensions"]["VRM"];
  auto sphere = [](double x, double y, double z, double radius) {
    return nlohmann::json{{"offset", {{"x", x}, {"y", y}, {"z", z}}}, {"radius", radius}};
  };
  // A look-at origin off the head's axis, to see the 0.x (Unity-axes) offset turned.
  vrm["firstPerson"]["firstPersonBoneOffset"] = {{"x", 0.01}, {"y", 0.06}, {"z", 0.02}};
  vrm["secondaryAnimation"] = {
      {"colliderGroups",
       {{{"node", humanNode(vrm, "head")}, {"colliders", {sphere(0.0, 0.08, 0.01, 0.1)}}},
        {{"node", humanNode(vrm, "leftHand")}, {"colliders", {sphere(0.0, 0.0, 0.0, 0.05), sphere(-0.05, 0.0, 0.0, 0.04)}}},
        {{"node", humanNode(vrm, "rightHand")}, {"colliders", {sphere(0.05, 0.01, 0.02, 0.04)}}}}},
      {"boneGroups",
       {{{"comment", "toes"}, {"stiffiness", 1.5}, {"gravityPower", 0.5}, {"gravityDir", {{"x", 0.3}, {"y", -1.0}, {"z", 0.2}}},
         {"dragForce", 0.4}, {"center", -1}, {"hitRadius", 0.02},
         {"bones", {humanNode(vrm, "leftToes"), humanNode(vrm, "rightToes")}}, {"colliderGroups", {0}}},
        {{"comment", "left shoulder"}, {"stiffiness", 2.0}, {"gravityPower", 0.0}, {"gravityDir", {{"x", 0.0}, {"y", -1.0}, {"z", 0.0}}},
         {"dragForce", 0.7}, {"center", humanNode(vrm, "hips")}, {"hitRadius", 0.03},
         {"bones", {humanNode(vrm, "leftShoulder")}}, {"colliderGroups", {0, 2}}}}}};
  const std::string path = dir / "springs0.vrm";
  std::ofstream(path, std::ios::binary) << withJson(bytes, json);
  return path;
}

// Every node below `root`, itself included.
void descendants(const nlohmann::json& nodes, int root, std::set<int>* out) {
  out->insert(root);
  for (const auto& child : nodes[root].value("children", nlohmann::json::array())) descendants(nodes, child.get<int>(), out);
}

Eigen::Vector3d bindOf(const Character& character, const std::string& bone) {
  return character.skeleton.bindPosition(character.vrm_humanoid.at(bone));
}

std::string base64(const std::string& bytes) {
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned a = static_cast<unsigned char>(bytes[i]);
    const unsigned b = i + 1 < bytes.size() ? static_cast<unsigned char>(bytes[i + 1]) : 0u;
    const unsigned c = i + 2 < bytes.size() ? static_cast<unsigned char>(bytes[i + 2]) : 0u;
    const unsigned n = (a << 16) | (b << 8) | c;
    out += kDigits[(n >> 18) & 63];
    out += kDigits[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[n & 63] : '=';
  }
  return out;
}

std::string threeVrmBundle() { return test::sourceDir() + "/.tools/three-vrm-check/three-vrm-check.js"; }

std::string chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"})
    if (ext::onPath(name)) return name;
  return "";
}

// three-vrm 3.x (tests/three_vrm/check.js) loads `vrm` in headless Chromium and plays its first clip;
// its report, or a null JSON when a tool is missing (under CI=true that fails the test).
nlohmann::json runThreeVrm(const test::TempDir& dir, const std::string& vrm) {
  if (!ext::requireTool(!chromium().empty(), "chromium (apt-get install chromium)") ||
      !ext::requireTool(ext::onPath("node"), "node (scripts/install-deps.sh)") ||
      !ext::requireTool(test::fileExists(threeVrmBundle()), threeVrmBundle() + " (run scripts/install-three-vrm-check.sh)"))
    return nullptr;
  std::ofstream(dir / "data.js", std::ios::binary) << "window.RIGBAKE_VRM_BASE64 = \"" << base64(slurp(vrm)) << "\";\n";
  std::ofstream(dir / "check.js", std::ios::binary) << slurp(threeVrmBundle());
  std::ofstream(dir / "page.html", std::ios::binary)
      << "<!doctype html><html><head><meta charset=\"utf-8\"><title>rigbake-test: running</title></head><body>"
         "<script src=\"data.js\"></script><script src=\"check.js\"></script></body></html>\n";
  const ext::CommandResult run = ext::runCommand("node " + ext::shellQuote(test::sourceDir() + "/player/test/run_page.mjs") + " " +
                                                 ext::shellQuote(chromium()) + " " + ext::shellQuote("file://" + (dir / "page.html")) +
                                                 " 120 2>&1");
  INFO(run.output);
  nlohmann::json page = nlohmann::json::parse(run.output, nullptr, false);
  REQUIRE(page.is_object());
  CHECK(page.value("exceptions", nlohmann::json::array()).empty());
  CHECK(page.value("console", nlohmann::json::array()).empty());  // three-vrm warns of what it cannot use
  REQUIRE(page["result"].is_object());
  return page["result"];
}

}  // namespace vrm_convert_test

namespace vt = vrm_convert_test;

TEST_CASE("VRM 0.x humanoid names: the thumbs shift one bone, every other name stays") {
  CHECK(vrm1HumanBoneName("leftThumbProximal") == "leftThumbMetacarpal");
  CHECK(vrm1HumanBoneName("leftThumbIntermediate") == "leftThumbProximal");
  CHECK(vrm1HumanBoneName("leftThumbDistal") == "leftThumbDistal");
  CHECK(vrm1HumanBoneName("rightThumbIntermediate") == "rightThumbProximal");
  CHECK(vrm1HumanBoneName("rightLittleIntermediate") == "rightLittleIntermediate");
  CHECK(vrm1HumanBoneName("upperChest") == "upperChest");
  CHECK(vrm1HumanBoneName("leftThumbMetacarpal").empty());  // a 1.0 name, not a 0.x one
  CHECK(vrm1HumanBoneName("tail").empty());
}

TEST_CASE("cli bake --vrm 1: a VRM 0.x avatar becomes a VRM 1.0 with its humanoid, meta, springs and colliders") {
  test::TempDir dir;
  const std::string input = vt::sampleVrm0WithSprings(dir);
  const std::string output = dir / "converted.vrm";
  test::CliResult run = runCli("bake " + ext::shellQuote(input) + " --vrm 1 --helper-joints --influences 4 --response keep -o " +
                               ext::shellQuote(output));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  CHECK(run.err.find("converted VRM 0.x to VRM 1.0: 22 humanoid bones, 7 springs (10 joints, 7 7 cm leaf tails added), 4 "
                     "colliders in 3 groups") != std::string::npos);
  CHECK(run.err.find("licenseName 'CC0' has no VRM 1.0 field") != std::string::npos);

  const nlohmann::json source = test::glbJson(slurp(input));
  const nlohmann::json& vrm0 = source["extensions"]["VRM"];
  const nlohmann::json gltf = test::glbJson(slurp(output));
  const std::vector<std::string> used = gltf["extensionsUsed"];
  CHECK(std::count(used.begin(), used.end(), "VRM") == 0);
  CHECK(gltf["extensions"].count("VRM") == 0);
  for (const char* name : {"VRMC_vrm", "VRMC_springBone", "VRMC_node_constraint"})
    CHECK(std::count(used.begin(), used.end(), name) == 1);

  const nlohmann::json& vrm1 = gltf["extensions"]["VRMC_vrm"];
  CHECK(vrm1["specVersion"] == "1.0");
  // Every 0.x humanoid bone, on the same node, under its 1.0 name.
  REQUIRE(vrm1["humanoid"]["humanBones"].size() == vrm0["humanoid"]["humanBones"].size());
  for (const auto& bone : vrm0["humanoid"]["humanBones"]) {
    const std::string name = vrm1HumanBoneName(bone["bone"].get<std::string>());
    INFO(name);
    CHECK(vrm1["humanoid"]["humanBones"][name]["node"] == bone["node"]);
  }
  // The sample's 0.x meta: Everyone, violence and sex disallowed, commercial use allowed, CC0.
  const nlohmann::json& meta = vrm1["meta"];
  CHECK(meta["name"] == vrm0["meta"]["title"]);
  CHECK(meta["authors"] == nlohmann::json::array({vrm0["meta"]["author"]}));
  CHECK(meta["licenseUrl"] == "https://vrm.dev/licenses/1.0/");
  CHECK(meta["avatarPermission"] == "everyone");
  CHECK(meta["allowExcessivelyViolentUsage"] == false);
  CHECK(meta["allowExcessivelySexualUsage"] == false);
  CHECK(meta["commercialUsage"] == "personalProfit");
  CHECK(meta["creditNotation"] == "required");
  // firstPerson names the body's node instead of its mesh; lookAt keeps the 0.x ranges.
  REQUIRE(vrm1["firstPerson"]["meshAnnotations"].size() == 1);
  CHECK(gltf["nodes"][vrm1["firstPerson"]["meshAnnotations"][0]["node"].get<int>()]["mesh"] == 0);
  CHECK(vrm1["lookAt"]["offsetFromHeadBone"] == nlohmann::json::array({0.01, 0.06, -0.02}));  // in the head's frame
  CHECK(vrm1["lookAt"]["type"] == "bone");
  CHECK(vrm1["lookAt"]["rangeMapHorizontalOuter"]["inputMaxValue"] == 90.0);
  CHECK(vrm1["lookAt"]["rangeMapHorizontalOuter"]["outputScale"] == 10.0);

  // Springs: every descendant of a 0.x root bone is a joint of exactly one spring.
  const nlohmann::json& springs = gltf["extensions"]["VRMC_springBone"];
  std::set<int> expected;
  for (const auto& group : vrm0["secondaryAnimation"]["boneGroups"])
    for (const auto& bone : group["bones"]) vt::descendants(source["nodes"], bone.get<int>(), &expected);
  std::multiset<int> joints;
  for (const auto& spring : springs["springs"]) {
    REQUIRE(spring["joints"].size() >= 2);
    for (size_t j = 0; j + 1 < spring["joints"].size(); ++j) joints.insert(spring["joints"][j]["node"].get<int>());
    const nlohmann::json& tail = spring["joints"].back();
    CHECK(tail.count("stiffness") == 0);
  }
  CHECK(springs["springs"].size() == 7);
  CHECK(joints.size() == expected.size());
  CHECK(std::set<int>(joints.begin(), joints.end()) == expected);
  CHECK(springs["colliders"].size() == 4);
  CHECK(springs["colliderGroups"].size() == 3);
  // 0.x vectors are in Unity's axes: a node-local offset turns (x, y, -z), a model-space direction
  // (-x, y, z) once the model faces +Z.
  CHECK(springs["colliders"][3]["shape"]["sphere"]["offset"] == nlohmann::json::array({0.05, 0.01, -0.02}));
  const nlohmann::json& toe = springs["springs"][0]["joints"][0];
  CHECK(toe["gravityDir"] == nlohmann::json::array({-0.3, -1.0, 0.2}));
  CHECK(toe["stiffness"] == 1.5);
  CHECK(toe["dragForce"] == 0.4);
  CHECK(toe["hitRadius"] == 0.02);
  CHECK(toe["gravityPower"] == 0.5);
  CHECK(springs["springs"][1]["colliderGroups"] == nlohmann::json::array({0}));
  CHECK(springs["springs"][2]["colliderGroups"] == nlohmann::json::array({0, 2}));
  CHECK(springs["springs"][2]["center"] == vt::humanNode(vrm0, "hips"));
  // The toe's tail: 7 cm along the toe bone, in the toe's frame.
  const nlohmann::json& tail_node = gltf["nodes"][springs["springs"][0]["joints"][1]["node"].get<int>()];
  const Eigen::Vector3d tail(tail_node["translation"][0], tail_node["translation"][1], tail_node["translation"][2]);
  const nlohmann::json& toe_node = source["nodes"][vt::humanNode(vrm0, "leftToes")];
  const Eigen::Vector3d bone(toe_node["translation"][0], toe_node["translation"][1], toe_node["translation"][2]);
  CHECK(std::abs(tail.norm() - 0.07) < 1e-9);
  CHECK(tail.normalized().dot(bone.normalized()) > 1.0 - 1e-9);

  // The root node turns the avatar to face +Z: the avatar's left hand at +X, toes ahead of the feet.
  // (The skinned mesh's node stays a root: its transform does not move the skin.)
  REQUIRE(gltf["scenes"][0]["nodes"].size() == 2);
  const nlohmann::json& turn = gltf["nodes"][gltf["scenes"][0]["nodes"][0].get<int>()];
  CHECK(turn["rotation"] == nlohmann::json::array({0.0, 1.0, 0.0, 0.0}));
  CHECK(turn["children"] == nlohmann::json::array({vt::humanNode(vrm0, "hips")}));
  CHECK(gltf["nodes"][gltf["scenes"][0]["nodes"][1].get<int>()].contains("skin"));
  const Character before = loadCharacter(input).character;
  const Character after = loadCharacter(output).character;
  CHECK(after.vrm_version == "1.0");
  const Eigen::Vector3d hand0 = vt::bindOf(before, "leftHand"), hand1 = vt::bindOf(after, "leftHand");
  INFO("left hand " << hand0.transpose() << " -> " << hand1.transpose());
  CHECK(hand0.x() < -0.5);
  CHECK(hand1.x() > 0.5);
  CHECK((hand1 - Eigen::Vector3d(-hand0.x(), hand0.y(), -hand0.z())).norm() < 1e-6);
  CHECK(vt::bindOf(after, "leftToes").z() > vt::bindOf(after, "leftFoot").z() + 0.1);

  // The helper joints carry their aim constraints, as on any VRM 1.0 bake.
  int constrained = 0;
  for (const auto& node : gltf["nodes"]) constrained += node.contains("extensions") && node["extensions"].contains("VRMC_node_constraint");
  CHECK(constrained > 0);
  CHECK(run.err.find("VRM 1.0: the base and tip joints of " + std::to_string(constrained / 2) + " muscles carry") != std::string::npos);

  if (ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) {
    const ext::ValidationSummary summary = ext::validateWithKhronos(output);
    INFO(summary.raw);
    CHECK(summary.errors == 0);
    CHECK(summary.warnings == 0);
  }

  // three-vrm 3.x loads it as a VRM 1.0, its springs swing and its constraints aim while the clip plays.
  const nlohmann::json three = vt::runThreeVrm(dir, output);
  if (three.is_null()) return;
  INFO(three.dump());
  REQUIRE(!three.contains("error"));
  CHECK(three["metaVersion"] == "1");
  CHECK(three["humanBones"] == vrm0["humanoid"]["humanBones"].size());
  CHECK(three["springJoints"] == expected.size());
  // three-vrm keeps the collider groups that springs use: the toes' head group and the shoulder's
  // right-hand group, one sphere each (the left hand's group is the shoulder spring's own joint).
  CHECK(three["colliders"] == 2);
  CHECK(three["colliderGroups"] == 2);
  CHECK(three["constraints"] == constrained);
  CHECK(three["leftHandX"].get<double>() > 0.5);
  CHECK(three["largestSpringSwingDeg"].get<double>() > 1.0);
  CHECK(three["largestAimErrorDeg"].get<double>() < 0.01);
  // The file's own clip plays only with autoUpdateHumanBones off (docs/extensions.md).
  CHECK(three["largestClipTurnDeg"].get<double>() > 90.0);
  CHECK(three["largestClipTurnDegWithAutoUpdate"].get<double>() < 1.0);
}

TEST_CASE("cli bake --vrm: a version the input cannot become is one VRM_CONVERSION_UNSUPPORTED line, no file") {
  test::TempDir dir;
  const std::string vrm1 = dir / "sample1.vrm";
  REQUIRE(runCli("sample --vrm 1 -o " + ext::shellQuote(vrm1)).exit_code == 0);
  // The message says the version in words: the loader that refuses it knows no flag (build asks by "vrm").
  const std::vector<std::array<std::string, 3>> cases = {
      {test::sampleGlbPathForCli(), "1", "is not a VRM (no VRM or VRMC_vrm extension), so there is no avatar to write as VRM 1.0\n"},
      {vrm1, "0", "is a VRM 1.0 asked to be VRM 0.x; rigbake converts VRM 0.x to 1.0, not back\n"}};
  for (const auto& [input, version, message] : cases) {
    const std::string output = dir / "out.vrm";
    test::CliResult run = runCli("bake " + ext::shellQuote(input) + " --vrm " + version + " -o " + ext::shellQuote(output));
    INFO(input << " --vrm " << version << "\n" << run.err);
    CHECK(run.exit_code == 3);
    CHECK(run.err == "VRM_CONVERSION_UNSUPPORTED " + input + ": " + message);
    CHECK(test::lineCount(run.err) == 1);
    CHECK_FALSE(std::filesystem::exists(output));
  }
}

TEST_CASE("cli bake --vrm: a version the input has is kept, a conversion with jiggles is byte-identical at any thread count") {
  test::TempDir dir;
  const std::string vrm0 = vt::sampleVrm0WithSprings(dir);
  const std::string vrm1 = dir / "sample1.vrm";
  REQUIRE(runCli("sample --vrm 1 -o " + ext::shellQuote(vrm1)).exit_code == 0);
  auto bake = [&](const std::string& input, const std::string& flags, const std::string& output) {
    test::CliResult run = runCli("bake " + ext::shellQuote(input) + " --influences 4 --response keep " + flags + " -o " +
                                 ext::shellQuote(dir / output));
    INFO(run.err);
    REQUIRE(run.exit_code == 0);
    return run.err;
  };
  const std::string kept0 = bake(vrm0, "--vrm 0", "kept0.vrm");
  CHECK(kept0.find("converted VRM 0.x") == std::string::npos);
  CHECK(test::glbJson(slurp(dir / "kept0.vrm"))["extensions"].contains("VRM"));
  const std::string kept1 = bake(vrm1, "--vrm 1", "kept1.vrm");
  CHECK(kept1.find("converted VRM 0.x") == std::string::npos);
  CHECK(test::glbJson(slurp(dir / "kept1.vrm"))["extensions"]["VRMC_vrm"]["specVersion"] == "1.0");
  // With --jiggle, the jiggles' springs join the 7 converted ones.
  bake(vrm0, "--vrm 1 --helper-joints --jiggle biceps --threads 1", "one.vrm");
  bake(vrm0, "--vrm 1 --helper-joints --jiggle biceps --threads 2", "two.vrm");
  CHECK(slurp(dir / "one.vrm") == slurp(dir / "two.vrm"));
  const nlohmann::json springs = test::glbJson(slurp(dir / "one.vrm"))["extensions"]["VRMC_springBone"]["springs"];
  REQUIRE(springs.size() == 9);
  CHECK(springs[7]["name"] == "LeftBicep_muscleSkinned");
  CHECK(springs[8]["name"] == "RightBicep_muscleSkinned");
}

TEST_CASE("cli bake --vrm 1: a malformed VRM 0.x spring names where, and writes nothing") {
  test::TempDir dir;
  const std::string good = vt::sampleVrm0WithSprings(dir);
  const std::string bytes = slurp(good);
  nlohmann::json json = test::glbJson(bytes);
  json["extensions"]["VRM"]["secondaryAnimation"]["boneGroups"][1]["bones"][0] = 9999;
  const std::string bad = dir / "bad0.vrm";
  std::ofstream(bad, std::ios::binary) << vt::withJson(bytes, json);
  const std::string output = dir / "out.vrm";
  test::CliResult run = runCli("bake " + ext::shellQuote(bad) + " --vrm 1 -o " + ext::shellQuote(output));
  INFO(run.err);
  CHECK(run.exit_code == 3);
  CHECK(run.err.rfind("GLTF_PARSE_FAILED " + bad + "#/extensions/VRM/secondaryAnimation/boneGroups/1/bones/0: ", 0) == 0);
  CHECK(test::lineCount(run.err) == 1);
  CHECK_FALSE(std::filesystem::exists(output));
}

TEST_CASE("cli build: a manifest character with \"vrm\": 1 is built from its VRM 0.x as a VRM 1.0, validated") {
  test::TempDir dir;
  vt::sampleVrm0WithSprings(dir);  // springs0.vrm beside the manifest
  const nlohmann::json manifest = {
      {"influences", 4}, {"response", "keep"}, {"helper_joints", true}, {"out", "out"},
      {"characters", {{{"name", "avatar"}, {"input", "springs0.vrm"}, {"vrm", 1}}}}};
  std::ofstream(dir / "manifest.json") << manifest.dump(2);
  test::CliResult run = runCli("build " + ext::shellQuote(dir / "manifest.json") + " -j 1 --progress never");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json summary = nlohmann::json::parse(slurp(dir / "out/summary.json"));
  CHECK(summary["counts"]["built"] == 1);
  CHECK(summary["counts"]["failed"] == 0);
  const nlohmann::json converted = test::glbJson(slurp(dir / "out/avatar/avatar.glb"));
  CHECK(converted["extensions"]["VRMC_vrm"]["specVersion"] == "1.0");
  CHECK(converted["extensions"]["VRMC_springBone"]["springs"].size() == 7);
  CHECK(converted["extensions"].count("VRM") == 0);
  // An impossible version fails that character alone, with the code.
  std::ofstream(dir / "bad.json") << nlohmann::json{{"out", "bad"}, {"characters", {{{"name", "plain"}, {"input", test::sampleGlbPathForCli()}, {"vrm", 1}}}}}.dump();
  test::CliResult bad = runCli("build " + ext::shellQuote(dir / "bad.json") + " -j 1 --progress never");
  INFO(bad.err);
  CHECK(bad.exit_code == 4);
  CHECK(bad.err.find("VRM_CONVERSION_UNSUPPORTED") != std::string::npos);
}
