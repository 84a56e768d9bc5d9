#include "formats/muscle_json.h"

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "cli_support.h"

using namespace rigbake;

namespace {
void expectSameMuscles(const MuscleSet& a, const MuscleSet& b, double tolerance) {
  REQUIRE(a.parts.size() == b.parts.size());
  for (size_t i = 0; i < a.parts.size(); ++i) {
    INFO(a.parts[i].fullName());
    CHECK(a.parts[i].fullName() == b.parts[i].fullName());
    CHECK(a.parts[i].group == b.parts[i].group);
    CHECK(a.parts[i].origin.joint == b.parts[i].origin.joint);
    CHECK(a.parts[i].insertion.joint == b.parts[i].insertion.joint);
    CHECK((a.parts[i].origin.world - b.parts[i].origin.world).norm() <= tolerance);
    CHECK((a.parts[i].insertion.world - b.parts[i].insertion.world).norm() <= tolerance);
    CHECK((a.parts[i].driver.world - b.parts[i].driver.world).norm() <= tolerance);
    CHECK(a.parts[i].compression == b.parts[i].compression);
    CHECK(a.parts[i].stretch == b.parts[i].stretch);
    CHECK((a.parts[i].bulge - b.parts[i].bulge).norm() <= tolerance);
    CHECK(a.parts[i].kind == b.parts[i].kind);
    CHECK(a.parts[i].carrier_landmark == b.parts[i].carrier_landmark);
    CHECK(a.parts[i].carrier == b.parts[i].carrier);
  }
}
}  // namespace

TEST_CASE("muscle JSON round-trips through the rigbake block on every character") {
  test::TempDir dir;
  std::vector<std::string> paths = test::sampleAndAssetPaths();
  for (const std::string& path : paths) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    MuscleSet placed = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
    std::string text = muscleJson(placed, r.character.skeleton, "gow_biped");
    std::ofstream(dir / "m.json") << text;
    MuscleSet read = readMuscleJson(dir / "m.json", r.character, r.landmarks, test::gowPreset());
    expectSameMuscles(placed, read, 1e-9 * r.landmarks.body.height);
    // Writing what was read gives the same bytes.
    CHECK(muscleJson(read, r.character.skeleton, "gow_biped") == text);
    nlohmann::json json = nlohmann::json::parse(text);
    CHECK(json["Arms"]["Left"].contains("LeftBicep_muscleOrigin"));
    CHECK(json["Trapezius"]["Right"].contains("RightTrapeziusC_muscleDriver"));
    CHECK(json["rigbake"]["units"] == "m");
    // Muscles are written as they always were; a corrective says what it is and what carries it.
    CHECK_FALSE(json["rigbake"]["muscles"]["LeftBicep"].contains("kind"));
    CHECK(json["rigbake"]["muscles"]["LeftAxillaUpperArm"]["kind"] == "corrective");
    CHECK(json["rigbake"]["muscles"]["RightAxillaUpperArm"]["carrier_landmark"] == "upper_arm_r");
    CHECK(json["Axilla"]["Left"].contains("LeftAxillaChest_muscleOrigin"));
  }
}

TEST_CASE("a corrective whose carrier landmark the character does not resolve is refused with MUSCLES_MISMATCH") {
  test::TempDir dir;
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  MuscleSet placed = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  nlohmann::json json = nlohmann::json::parse(muscleJson(placed, r.character.skeleton, "gow_biped"));
  json["rigbake"]["muscles"]["LeftAxillaChest"]["carrier_landmark"] = "toe_tip_l";
  std::ofstream(dir / "m.json") << json.dump(2);
  try {
    readMuscleJson(dir / "m.json", r.character, r.landmarks, test::gowPreset());
    FAIL("expected MUSCLES_MISMATCH");
  } catch (const Error& error) {
    CHECK(error.code() == "MUSCLES_MISMATCH");
    CHECK(std::string(error.what()).find("m.json#/rigbake/muscles/LeftAxillaChest/carrier_landmark") != std::string::npos);
    CHECK(std::string(error.what()).find("toe_tip_l") != std::string::npos);
  }
}

TEST_CASE("correctives are named by their carrier landmark") {
  CHECK(correctivePartName("Axilla", "upper_arm") == "AxillaUpperArm");
  CHECK(correctivePartName("Axilla", "spine_t12") == "AxillaSpineT12");
  CHECK(correctivePartName("Axilla", "chest") == "AxillaChest");
}

TEST_CASE("the talk's positions-only export is read, with attach joints from the preset") {
  test::TempDir dir;
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  MuscleSet placed = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  nlohmann::json json = nlohmann::json::parse(muscleJson(placed, r.character.skeleton, "gow_biped"));
  json.erase("rigbake");
  // The talk spells the teres group "TerasMajor".
  json["TerasMajor"] = json["TeresMajor"];
  json.erase("TeresMajor");
  std::ofstream(dir / "talk.json") << json.dump(2);
  MuscleSet read = readMuscleJson(dir / "talk.json", r.character, r.landmarks, test::gowPreset());
  expectSameMuscles(placed, read, 1e-12);
}

TEST_CASE("a muscle file for another character is refused with MUSCLES_MISMATCH") {
  std::string cesium = test::requireAsset("CesiumMan.glb");
  if (cesium.empty()) return;
  test::TempDir dir;
  test::Resolved sample = test::resolveShipped(test::sampleGlbPath());
  MuscleSet placed = placeMuscles(sample.character, sample.landmarks, test::gowPreset(), Sides::kBoth);
  std::ofstream(dir / "m.json") << muscleJson(placed, sample.character.skeleton, "gow_biped");
  test::Resolved other = test::resolveShipped(cesium);
  try {
    readMuscleJson(dir / "m.json", other.character, other.landmarks, test::gowPreset());
    FAIL("expected MUSCLES_MISMATCH");
  } catch (const Error& e) {
    CHECK(e.code() == "MUSCLES_MISMATCH");
    CHECK(std::string(e.what()).find("is not in CesiumMan.glb") != std::string::npos);
  }
}
