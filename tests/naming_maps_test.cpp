// Every shipped naming map resolves the skeleton it is written for, auto-detected from the names
// alone; a user map passed with --map overrides detection.
#include "anatomy_fixture.h"
#include "cli_support.h"

using namespace rigbake;

namespace {

// The sample character with its joints renamed into another convention.
test::Resolved renamed(const std::map<std::string, std::string>& names, const NamingMap* forced = nullptr) {
  Character character = loadCharacter(test::sampleGlbPath()).character;
  for (std::string& name : character.skeleton.names) {
    auto it = names.find(name);
    name = it == names.end() ? "extra_" + name : it->second;
  }
  return test::resolveWithShippedPresets(std::move(character), forced);
}

void expectJoint(const test::Resolved& r, const std::string& landmark, const std::string& joint) {
  INFO(landmark);
  REQUIRE(r.landmarks.has(landmark));
  CHECK(r.landmarks.get(landmark).from_joint == joint);
}

}  // namespace

TEST_CASE("naming maps: Mixamo, with and without the mixamorig: prefix") {
  for (std::string prefix : {"mixamorig:", ""}) {
    test::Resolved r = renamed({{"JOPelvis1", prefix + "Hips"}, {"JOBack1", prefix + "Spine"}, {"JOBack2", prefix + "Spine1"},
                                {"JOBack3", prefix + "Spine2"}, {"JONeck1", prefix + "Neck"}, {"JOHead1", prefix + "Head"},
                                {"JOLeftClavicle1", prefix + "LeftShoulder"}, {"JOLeftUpperArm1", prefix + "LeftArm"},
                                {"JOLeftLowerArm1", prefix + "LeftForeArm"}, {"JOLeftHand1", prefix + "LeftHand"},
                                {"JORightClavicle1", prefix + "RightShoulder"}, {"JORightUpperArm1", prefix + "RightArm"},
                                {"JORightLowerArm1", prefix + "RightForeArm"}, {"JORightHand1", prefix + "RightHand"}});
    CHECK(r.landmarks.map_name == "mixamo");
    expectJoint(r, "chest", prefix + "Spine2");
    expectJoint(r, "forearm_r", prefix + "RightForeArm");
    CHECK(r.landmarks.get("acromion_l").source == "derived");
  }
}

TEST_CASE("naming maps: Unreal mannequin with twist joints") {
  test::Resolved r = renamed({{"JOPelvis1", "pelvis"}, {"JOBack1", "spine_01"}, {"JOBack2", "spine_02"}, {"JOBack3", "spine_03"},
                              {"JONeck1", "neck_01"}, {"JOHead1", "head"}, {"JOLeftClavicle1", "clavicle_l"},
                              {"JOLeftUpperArm1", "upperarm_l"}, {"LeftUpperArm1Twist0", "upperarm_twist_01_l"},
                              {"JOLeftLowerArm1", "lowerarm_l"}, {"LeftLowerArm1Twist0", "lowerarm_twist_01_l"},
                              {"JOLeftHand1", "hand_l"}, {"JORightClavicle1", "clavicle_r"}, {"JORightUpperArm1", "upperarm_r"},
                              {"JORightLowerArm1", "lowerarm_r"}, {"JORightHand1", "hand_r"}});
  CHECK(r.landmarks.map_name == "unreal");
  expectJoint(r, "upper_arm_twist_l", "upperarm_twist_01_l");
  expectJoint(r, "forearm_twist_l", "lowerarm_twist_01_l");
  expectJoint(r, "chest", "spine_03");
}

TEST_CASE("naming maps: Rigify deform bones") {
  test::Resolved r = renamed({{"JOPelvis1", "DEF-spine"}, {"JOBack1", "DEF-spine.001"}, {"JOBack2", "DEF-spine.002"},
                              {"JOBack3", "DEF-spine.003"}, {"JONeck1", "DEF-spine.004"}, {"JOHead1", "DEF-spine.006"},
                              {"JOLeftClavicle1", "DEF-shoulder.L"}, {"JOLeftUpperArm1", "DEF-upper_arm.L"},
                              {"LeftUpperArm1Twist0", "DEF-upper_arm.L.001"}, {"JOLeftLowerArm1", "DEF-forearm.L"},
                              {"JOLeftHand1", "DEF-hand.L"}, {"JORightClavicle1", "DEF-shoulder.R"},
                              {"JORightUpperArm1", "DEF-upper_arm.R"}, {"JORightLowerArm1", "DEF-forearm.R"},
                              {"JORightHand1", "DEF-hand.R"}});
  CHECK(r.landmarks.map_name == "blender");
  expectJoint(r, "pelvis", "DEF-spine");
  expectJoint(r, "neck", "DEF-spine.004");
  expectJoint(r, "upper_arm_twist_l", "DEF-upper_arm.L.001");
  expectJoint(r, "hand_r", "DEF-hand.R");
}

TEST_CASE("naming maps: a user map given with --map overrides detection") {
  test::TempDir dir;
  std::ofstream(dir / "studio.json") << R"({"name": "studio", "side_tokens": {"l": ["lf"], "r": ["rt"]},
    "landmarks": {"pelvis": ["root_hip"], "chest": ["torso_up"], "neck": ["neck_base"], "head": ["skull"],
                  "upper_arm": ["{side}_shoulder"], "forearm": ["{side}_elbow"], "hand": ["{side}_wrist"]}})";
  NamingMap studio = readNamingMap(dir / "studio.json");
  test::Resolved r = renamed({{"JOPelvis1", "root_hip"}, {"JOBack3", "torso_up"}, {"JONeck1", "neck_base"}, {"JOHead1", "skull"},
                              {"JOLeftUpperArm1", "lf_shoulder"}, {"JOLeftLowerArm1", "lf_elbow"}, {"JOLeftHand1", "lf_wrist"},
                              {"JORightUpperArm1", "rt_shoulder"}, {"JORightLowerArm1", "rt_elbow"}, {"JORightHand1", "rt_wrist"}},
                             &studio);
  CHECK(r.landmarks.map_name == "studio");
  expectJoint(r, "upper_arm_r", "rt_shoulder");
  expectJoint(r, "pelvis", "root_hip");
  CHECK(r.landmarks.get("clavicle_l").source == "derived");
  // The CLI takes the same file.
  std::string glb = test::sampleGlbPath();
  test::CliResult cli = test::runCli("landmarks --json --map " + (dir / "studio.json") + " " + glb);
  CHECK(cli.exit_code == 3);  // the sample's JO* names are not the studio's
  CHECK(cli.err.rfind("LANDMARK_UNRESOLVED ", 0) == 0);
  CHECK(cli.err.find("map studio tried: root_hip") != std::string::npos);
  CHECK(cli.err.find("cannot be derived; give a JSON naming map (pass --map)\n") != std::string::npos);
}

TEST_CASE("naming maps: a landmark no joint matches asks for a naming map by field, and each caller names its own option") {
  // anatomy/ names no flag: the error says what to give and which field of the request gives it.
  const NamingMap mixamo = readNamingMap(test::presetsDir() + "/skeletons/mixamo.json");
  try {
    test::resolveShipped(test::sampleGlbPath(), &mixamo);
    FAIL("the sample's JO* names resolved with the Mixamo map");
  } catch (const FixableByOption& error) {
    CHECK(error.code() == "LANDMARK_UNRESOLVED");
    CHECK(error.field() == "map");
    CHECK(error.message().find("cannot be derived; give a JSON naming map") != std::string::npos);
    CHECK(std::string(error.what()).find("--") == std::string::npos);
  }
  // The command line names its flag: --map, or retarget's --map-from / --map-to for the character it
  // resolves with that map.
  test::TempDir dir;
  const std::string glb = test::sampleGlbPathForCli();
  const test::CliResult bake = test::runCli("bake " + glb + " --map mixamo -o " + (dir / "b.glb"));
  CHECK(bake.exit_code == 3);
  CHECK(bake.err.find("give a JSON naming map (pass --map)\n") != std::string::npos);
  const test::CliResult from =
      test::runCli("retarget " + (dir / "m.json") + " --from " + glb + " --to " + glb + " --map-from mixamo -o " + (dir / "r.json"));
  CHECK(from.exit_code == 3);
  CHECK(from.err.find("give a JSON naming map (pass --map-from)\n") != std::string::npos);
  CHECK(!std::filesystem::exists(dir / "b.glb"));
  CHECK(!std::filesystem::exists(dir / "r.json"));
}
