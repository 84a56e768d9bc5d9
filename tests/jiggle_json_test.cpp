// Strict reading of jiggle presets and hit files (formats/jiggle_json.h): every shipped preset parses,
// and every mistake is reported with its code and JSON pointer.
#include <catch2/catch.hpp>
#include <functional>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "formats/jiggle_json.h"

namespace rigbake {
namespace {

std::string errorOf(const std::function<void()>& run) {
  try {
    run();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

nlohmann::json onePreset() {
  return nlohmann::json::parse(R"({"jiggles": [{"joint": "JOHead1", "stiffness": 0.1, "damping": 0.1,
                                                "clamp_major_deg": 15, "clamp_minor_deg": 15}]})");
}

nlohmann::json oneHit() {
  return nlohmann::json::parse(R"({"hits": [{"time": 0.5, "direction": [0, 0, 1], "magnitude": 2,
                                            "joints": ["JOLeftLowerArm1"]}]})");
}

TEST_CASE("jiggle json: the shipped presets parse with the talk's settings") {
  const JigglePreset examples = readJigglePreset(test::presetsDir() + "/jiggle/gow_examples.json");
  CHECK(examples.name == "gow_examples");
  REQUIRE(examples.jiggles.size() == 6);
  const double expected[][4] = {{0.05, 0.1, 90, 90}, {0.15, 0.1, 90, 90}, {0.15, 0.025, 90, 90},
                                {0.1, 0.1, 90, 90},  {0.1, 0.1, 15, 15},  {0.5, 0.05, 90, 2.5}};
  for (size_t i = 0; i < 6; ++i) {
    const JiggleParams& p = examples.jiggles[i].params;
    CHECK(p.stiffness == expected[i][0]);
    CHECK(p.damping == expected[i][1]);
    CHECK(p.clamp_major_deg == expected[i][2]);
    CHECK(p.clamp_minor_deg == expected[i][3]);
  }
  CHECK(examples.jiggles[5].muscle == "LeftBicep");
  const JigglePreset biceps = readJigglePreset(test::presetsDir() + "/jiggle/biceps.json");
  REQUIRE(biceps.jiggles.size() == 2);
  CHECK(biceps.jiggles[1].muscle == "RightBicep");
}

TEST_CASE("jiggle json: preset mistakes are errors with their JSON pointer") {
  auto parse = [](const nlohmann::json& json) { return errorOf([&] { parseJigglePreset(json, "p.json"); }); };
  nlohmann::json typo = onePreset();
  typo["jiggles"][0]["stifness"] = 0.5;
  CHECK(parse(typo).find("PRESET_INVALID p.json#/jiggles/0/stifness: unknown key 'stifness'") == 0);
  nlohmann::json top = onePreset();
  top["jigles"] = 1;
  CHECK(parse(top).find("PRESET_INVALID p.json#/jigles") == 0);
  nlohmann::json missing = onePreset();
  missing["jiggles"][0].erase("damping");
  CHECK(parse(missing).find("PRESET_INVALID p.json#/jiggles/0: missing required key 'damping'") == 0);
  nlohmann::json range = onePreset();
  range["jiggles"][0]["clamp_minor_deg"] = 91;
  CHECK(parse(range).find("PRESET_INVALID p.json#/jiggles/0/clamp_minor_deg: must be in [0") == 0);
  nlohmann::json stiff = onePreset();
  stiff["jiggles"][0]["stiffness"] = -0.1;
  CHECK(parse(stiff).find("PRESET_INVALID p.json#/jiggles/0/stiffness") == 0);
  nlohmann::json two = onePreset();
  two["jiggles"][0]["muscle"] = "LeftBicep";
  CHECK(parse(two).find("PRESET_INVALID p.json#/jiggles/0: needs exactly one of") == 0);
  nlohmann::json none = onePreset();
  none["jiggles"][0].erase("joint");
  CHECK(parse(none).find("PRESET_INVALID p.json#/jiggles/0: needs exactly one of") == 0);
  nlohmann::json landmark = onePreset();
  landmark["jiggles"][0].erase("joint");
  landmark["jiggles"][0]["landmark"] = "tailbone";
  CHECK(parse(landmark).find("PRESET_LANDMARK_UNKNOWN p.json#/jiggles/0/landmark") == 0);
  nlohmann::json axis = onePreset();
  axis["jiggles"][0]["axis"] = {0, 0, 0};
  CHECK(parse(axis).find("PRESET_INVALID p.json#/jiggles/0/axis: must not be the zero vector") == 0);
  nlohmann::json axis_size = onePreset();
  axis_size["jiggles"][0]["axis"] = {1, 0};
  CHECK(parse(axis_size).find("PRESET_INVALID p.json#/jiggles/0/axis") == 0);
  nlohmann::json length = onePreset();
  length["jiggles"][0]["length"] = 0;
  CHECK(parse(length).find("PRESET_INVALID p.json#/jiggles/0/length: must be positive") == 0);
  nlohmann::json empty = onePreset();
  empty["jiggles"] = nlohmann::json::array();
  CHECK(parse(empty).find("PRESET_INVALID p.json#/jiggles: must list at least one jiggle") == 0);
  CHECK(parse(onePreset()) == "no error");
}

TEST_CASE("jiggle json: hit files parse strictly") {
  const std::vector<HitImpulse> hits = parseHits(oneHit(), "h.json");
  REQUIRE(hits.size() == 1);
  CHECK(hits[0].time == 0.5);
  CHECK(hits[0].magnitude == 2.0);
  CHECK(hits[0].direction == Eigen::Vector3d::UnitZ());
  CHECK(hits[0].joints == std::vector<std::string>{"JOLeftLowerArm1"});
  CHECK(hits[0].where == "h.json#/hits/0");
  auto parse = [](const nlohmann::json& json) { return errorOf([&] { parseHits(json, "h.json"); }); };
  nlohmann::json typo = oneHit();
  typo["hits"][0]["magnitud"] = 1;
  CHECK(parse(typo).find("HITS_INVALID h.json#/hits/0/magnitud: unknown key") == 0);
  nlohmann::json zero = oneHit();
  zero["hits"][0]["direction"] = {0, 0, 0};
  CHECK(parse(zero).find("HITS_INVALID h.json#/hits/0/direction: must not be the zero vector") == 0);
  nlohmann::json negative = oneHit();
  negative["hits"][0]["magnitude"] = -1;
  CHECK(parse(negative).find("HITS_INVALID h.json#/hits/0/magnitude") == 0);
  nlohmann::json early = oneHit();
  early["hits"][0]["time"] = -0.1;
  CHECK(parse(early).find("HITS_INVALID h.json#/hits/0/time") == 0);
  nlohmann::json no_joints = oneHit();
  no_joints["hits"][0]["joints"] = nlohmann::json::array();
  CHECK(parse(no_joints).find("HITS_INVALID h.json#/hits/0/joints") == 0);
  nlohmann::json bad_name = oneHit();
  bad_name["hits"][0]["joints"] = {"JOLeftHand1", 3};
  CHECK(parse(bad_name).find("HITS_INVALID h.json#/hits/0/joints/1: must be a string") == 0);
  CHECK(errorOf([] { readHits("/nonexistent/hits.json"); }).find("IO_FILE_NOT_FOUND") == 0);
}

}  // namespace
}  // namespace rigbake
