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

// 3ds Max's Biped, the skeleton of many studios' game characters: "Bip01 L UpperArm" as Max names it,
// "Bip001" in later Max versions, underscores where an exporter replaced the spaces, and the Source
// engine's "ValveBiped.Bip01_" prefix. Max names the upper arm's twist link without a space after the
// side ("Bip01 LUpArmTwist") and the forearm's with one ("Bip01 L ForeTwist").
TEST_CASE("naming maps: 3ds Max Biped, with spaces, Bip001, underscores and the ValveBiped prefix") {
  struct Spelling {
    std::string prefix, gap;
  };
  for (const Spelling& spelling : {Spelling{"Bip01 ", " "}, Spelling{"Bip001 ", " "}, Spelling{"Bip01_", "_"},
                                   Spelling{"ValveBiped.Bip01_", "_"}}) {
    INFO(spelling.prefix);
    const std::string& p = spelling.prefix;
    const std::string& g = spelling.gap;
    test::Resolved r = renamed({{"JOPelvis1", p + "Pelvis"}, {"JOBack1", p + "Spine"}, {"JOBack2", p + "Spine1"},
                                {"JOBack3", p + "Spine2"}, {"JONeck1", p + "Neck"}, {"JOHead1", p + "Head"},
                                {"JOLeftClavicle1", p + "L" + g + "Clavicle"}, {"JOLeftUpperArm1", p + "L" + g + "UpperArm"},
                                {"LeftUpperArm1Twist0", p + (g == " " ? "LUpArmTwist" : "L_UpArmTwist")},
                                {"JOLeftLowerArm1", p + "L" + g + "Forearm"}, {"LeftLowerArm1Twist0", p + "L" + g + "ForeTwist"},
                                {"JOLeftHand1", p + "L" + g + "Hand"}, {"JORightClavicle1", p + "R" + g + "Clavicle"},
                                {"JORightUpperArm1", p + "R" + g + "UpperArm"}, {"JORightLowerArm1", p + "R" + g + "Forearm"},
                                {"JORightHand1", p + "R" + g + "Hand"}, {"JOLeftUpLeg1", p + "L" + g + "Thigh"},
                                {"JOLeftLeg1", p + "L" + g + "Calf"}, {"JOLeftFoot1", p + "L" + g + "Foot"},
                                {"JOLeftToe1", p + "L" + g + "Toe0"}});
    CHECK(r.landmarks.map_name == "max_biped");
    expectJoint(r, "pelvis", p + "Pelvis");
    expectJoint(r, "spine_t12", p + "Spine1");
    expectJoint(r, "chest", p + "Spine2");
    expectJoint(r, "clavicle_r", p + "R" + g + "Clavicle");
    expectJoint(r, "upper_arm_twist_l", p + (g == " " ? "LUpArmTwist" : "L_UpArmTwist"));
    expectJoint(r, "forearm_twist_l", p + "L" + g + "ForeTwist");
    expectJoint(r, "hand_r", p + "R" + g + "Hand");
    expectJoint(r, "lower_leg_l", p + "L" + g + "Calf");
    expectJoint(r, "toe_l", p + "L" + g + "Toe0");
  }
}

// A VRoid Studio avatar exported without its VRM extension keeps VRoid's joint names.
TEST_CASE("naming maps: VRoid joint names without the VRM extension") {
  test::Resolved r = renamed({{"JOPelvis1", "J_Bip_C_Hips"}, {"JOBack1", "J_Bip_C_Spine"}, {"JOBack2", "J_Bip_C_Chest"},
                              {"JOBack3", "J_Bip_C_UpperChest"}, {"JONeck1", "J_Bip_C_Neck"}, {"JOHead1", "J_Bip_C_Head"},
                              {"JOLeftClavicle1", "J_Bip_L_Shoulder"}, {"JOLeftUpperArm1", "J_Bip_L_UpperArm"},
                              {"JOLeftLowerArm1", "J_Bip_L_LowerArm"}, {"JOLeftHand1", "J_Bip_L_Hand"},
                              {"JORightClavicle1", "J_Bip_R_Shoulder"}, {"JORightUpperArm1", "J_Bip_R_UpperArm"},
                              {"JORightLowerArm1", "J_Bip_R_LowerArm"}, {"JORightHand1", "J_Bip_R_Hand"},
                              {"JOLeftUpLeg1", "J_Bip_L_UpperLeg"}, {"JOLeftLeg1", "J_Bip_L_LowerLeg"},
                              {"JOLeftFoot1", "J_Bip_L_Foot"}, {"JOLeftToe1", "J_Bip_L_ToeBase"}});
  CHECK(r.landmarks.map_name == "vroid");
  expectJoint(r, "spine_l5", "J_Bip_C_Spine");
  expectJoint(r, "spine_t12", "J_Bip_C_Chest");
  expectJoint(r, "chest", "J_Bip_C_UpperChest");
  expectJoint(r, "clavicle_l", "J_Bip_L_Shoulder");
  expectJoint(r, "forearm_r", "J_Bip_R_LowerArm");
  expectJoint(r, "toe_l", "J_Bip_L_ToeBase");
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

// presets/landmarks.json "limb_roots" names a sided limb, a central anchor and central trunk landmarks;
// a rule that mixes them up is refused with its JSON pointer, before any character is read.
TEST_CASE("naming maps: a limb_roots rule naming the wrong kind of landmark is a preset error with its pointer") {
  TempDir dir;
  nlohmann::json rules = nlohmann::json::parse(slurp(test::presetsDir() + "/landmarks.json"));
  REQUIRE(rules["limb_roots"].size() == 2);
  const auto refusal = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json changed = rules;
    changed["limb_roots"][1][key] = value;
    std::ofstream(dir / "landmarks.json") << changed.dump();
    try {
      readLandmarkRules(dir / "landmarks.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(refusal("limb", {"chest"}).find("/limb_roots/1/limb: 'chest' is not a sided landmark") != std::string::npos);
  CHECK(refusal("anchor", "clavicle").find("/limb_roots/1/anchor: 'clavicle' is not a central landmark") != std::string::npos);
  CHECK(refusal("not_under", {"hip"}).find("PRESET_LANDMARK_UNKNOWN") == 0);
  CHECK(refusal("limb", nlohmann::json::array()).find("/limb_roots/1/limb: needs at least one landmark") != std::string::npos);
  CHECK(refusal("not_under", {"spine_l5"}) == "no error");
}
