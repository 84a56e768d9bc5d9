// Placement of the gow_biped preset on the sample character and on every shared asset: the checks
// issue 3 asks for (landmarks resolve, locators near the body surface and on their own side, mirror
// exactness) and the talk's trapezius Python recomputed independently.
#include <array>
#include <map>

#include "anatomy/formula_eval.h"
#include "anatomy/surface_distance.h"
#include "anatomy_fixture.h"
#include "core/error.h"

using namespace rigbake;

namespace {

std::vector<std::string> allCharacterPaths() {
  std::vector<std::string> paths = test::sampleAndAssetPaths();
  return paths;
}

const MusclePart& findPart(const MuscleSet& set, const std::string& full_name) {
  for (const MusclePart& part : set.parts) {
    if (part.fullName() == full_name) return part;
  }
  FAIL("no muscle part " << full_name);
  throw;
}

}  // namespace

TEST_CASE("every character resolves every required landmark") {
  for (const std::string& path : allCharacterPaths()) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    for (const auto& [name, landmark] : r.landmarks.landmarks) {
      const std::string base = name.size() > 2 && (name.substr(name.size() - 2) == "_l" || name.substr(name.size() - 2) == "_r")
                                   ? name.substr(0, name.size() - 2)
                                   : name;
      bool optional = isOptionalLandmark(base);
      if (!optional) CHECK(landmark.resolved);
      if (landmark.resolved) {
        CHECK(landmark.joint >= 0);
        CHECK(landmark.position.allFinite());
      }
    }
    CHECK(r.landmarks.body.height > 0.5);
    CHECK(std::abs(r.landmarks.body.up.dot(r.landmarks.body.lateral)) < 1e-12);
  }
}

TEST_CASE("every shared character resolves hip, knee and ankle per side, and the toe where the rig has one") {
  // name -> {upper_leg_l, lower_leg_l, foot_l, toe_l ("" when the rig has no toe joint)}
  const std::map<std::string, std::array<std::string, 4>> expected = {
      {"sample", {"JOLeftUpLeg1", "JOLeftLeg1", "JOLeftFoot1", "JOLeftToe1"}},
      {"CesiumMan.glb", {"leg_joint_L_1", "leg_joint_L_2", "leg_joint_L_3", "leg_joint_L_5"}},
      {"RobotExpressive.glb", {"UpperLegL", "LowerLegL", "FootL", ""}},
      {"KayKit_Mannequin/manny_med_mod.gltf", {"upperleg.l", "lowerleg.l", "foot.l", "toes.l"}},
      {"Quaternius_Cyberpunk_Character.glb", {"UpperLeg.L", "LowerLeg.L", "Foot.L", ""}},
      {"Quaternius_ModularWomen_Soldier.glb", {"UpperLeg.L", "LowerLeg.L", "Foot.L", ""}},
  };
  for (const auto& [name, joints] : expected) {
    const std::string path = name == "sample" ? test::sampleGlbPath() : test::requireAsset(name);
    if (path.empty()) continue;
    INFO(name);
    test::Resolved r = test::resolveShipped(path);
    const char* bases[] = {"upper_leg", "lower_leg", "foot", "toe"};
    for (int k = 0; k < 4; ++k) {
      const std::string left = std::string(bases[k]) + "_l", right = std::string(bases[k]) + "_r";
      INFO(left);
      if (joints[k].empty()) {
        CHECK_FALSE(r.landmarks.has(left));
        continue;
      }
      REQUIRE(r.landmarks.has(left));
      REQUIRE(r.landmarks.has(right));
      CHECK(r.landmarks.get(left).from_joint == joints[k]);
      // Each leg on its own side of the sagittal plane.
      CHECK(r.landmarks.body.lateralOffset(r.landmarks.get(left).position) > 0.0);
      CHECK(r.landmarks.body.lateralOffset(r.landmarks.get(right).position) < 0.0);
    }
  }
}

TEST_CASE("a skeleton without legs still resolves, with its leg landmarks unresolved") {
  test::Resolved full = test::resolveShipped(test::sampleGlbPath());
  Character legless = test::withoutLegs(full.character);
  test::Resolved r = test::resolveWithShippedPresets(legless);
  CHECK(r.landmarks.map_name == "gow");
  for (const char* name : {"upper_leg_l", "lower_leg_r", "foot_l", "toe_r"}) CHECK_FALSE(r.landmarks.has(name));
  for (const char* name : {"pelvis", "chest", "upper_arm_l", "hand_r"})
    CHECK(r.landmarks.get(name).from_joint == full.landmarks.get(name).from_joint);
}

TEST_CASE("landmark sources: maps where names fit, structure for CesiumMan, derivations for missing joints") {
  auto source_of = [](const test::Resolved& r, const std::string& name) { return r.landmarks.get(name).source; };
  test::Resolved sample = test::resolveShipped(test::sampleGlbPath());
  CHECK(sample.landmarks.map_name == "gow");
  CHECK(source_of(sample, "acromion_l") == "map:gow");
  CHECK(sample.landmarks.get("upper_arm_twist_l").from_joint == "LeftUpperArm1Twist0");
  if (std::string cesium = test::requireAsset("CesiumMan.glb"); !cesium.empty()) {
    test::Resolved r = test::resolveShipped(cesium);
    CHECK(r.landmarks.map_name == "structure");
    // Left and right arm joints are numbered in opposite orders; the hierarchy decides.
    CHECK(r.landmarks.get("upper_arm_l").from_joint == "Skeleton_arm_joint_L__4_");
    CHECK(r.landmarks.get("hand_l").from_joint == "Skeleton_arm_joint_L__2_");
    CHECK(r.landmarks.get("upper_arm_r").from_joint == "Skeleton_arm_joint_R");
    CHECK(r.landmarks.get("hand_r").from_joint == "Skeleton_arm_joint_R__3_");
    CHECK(source_of(r, "clavicle_l") == "derived");  // CesiumMan has no clavicle
  }
  if (std::string kaykit = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf"); !kaykit.empty()) {
    test::Resolved r = test::resolveShipped(kaykit);
    CHECK(r.landmarks.map_name == "blender");
    CHECK(r.landmarks.get("pelvis").from_joint == "hips");
    CHECK(source_of(r, "neck") == "derived");  // KayKit has no neck joint
    CHECK(source_of(r, "clavicle_r") == "derived");
  }
  if (std::string robot = test::requireAsset("RobotExpressive.glb"); !robot.empty()) {
    test::Resolved r = test::resolveShipped(robot);
    CHECK(r.landmarks.map_name == "quaternius");
    CHECK(r.landmarks.get("clavicle_l").from_joint == "ShoulderL");
    CHECK(r.landmarks.get("hand_l").from_joint == "Palm2L");
  }
}

TEST_CASE("the VRM humanoid extension maps joints whose names say nothing") {
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    test::Resolved r = test::resolveShipped(test::sampleGlbPath(vrm));
    INFO("vrm variant " << static_cast<int>(vrm));
    CHECK(r.landmarks.map_name == "vrm_humanoid");
    CHECK(r.landmarks.get("upper_arm_l").source == "vrm");
    CHECK(r.landmarks.get("upper_arm_l").from_joint.rfind("bone_", 0) == 0);
    // The VRM body frame still finds the character's left, whichever way the file faces.
    Eigen::Vector3d left_hand = r.landmarks.get("hand_l").position;
    CHECK(r.landmarks.body.lateralOffset(left_hand) > 0.5);
  }
}

TEST_CASE("a VRM humanoid without upperChest keeps chest on its chest bone and derives spine_t12 below it") {
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    INFO("vrm variant " << static_cast<int>(vrm));
    test::Resolved r = test::resolveShipped(test::sampleVrmWithoutUpperChestPath(vrm));
    CHECK(r.landmarks.map_name == "vrm_humanoid");
    // The map names the chest bone for both spine_t12 (its first choice) and chest (its fallback for
    // upperChest); chest has no derivation and keeps the bone, spine_t12 has one and is derived.
    const Landmark& chest = r.landmarks.get("chest");
    const Landmark& t12 = r.landmarks.get("spine_t12");
    const Landmark& l5 = r.landmarks.get("spine_l5");
    CHECK(chest.source == "vrm");
    CHECK(chest.from_joint == "bone_02");  // JOBack2, the humanoid "chest"
    CHECK(t12.source == "derived");
    CHECK(t12.derived == "lerp(pelvis, chest, 0.6)");
    CHECK(l5.source == "vrm");
    const Eigen::Vector3d up = r.landmarks.body.up;
    CHECK(l5.position.dot(up) < t12.position.dot(up));
    CHECK(t12.position.dot(up) < chest.position.dot(up));
  }
}

TEST_CASE("no two spine landmarks coincide on any character") {
  std::vector<std::string> paths = test::sampleAndAssetPaths();
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    paths.push_back(test::sampleGlbPath(vrm));
    paths.push_back(test::sampleVrmWithoutUpperChestPath(vrm));
  }
  const std::vector<std::string>& spine = centralLandmarks();
  for (const std::string& path : paths) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    for (size_t a = 0; a < spine.size(); ++a) {
      for (size_t b = a + 1; b < spine.size(); ++b) {
        INFO(spine[a] << " and " << spine[b]);
        const double apart = (r.landmarks.get(spine[a]).position - r.landmarks.get(spine[b]).position).norm();
        CHECK(apart > 0.01 * r.landmarks.body.height);
      }
    }
  }
}

TEST_CASE("placed locators sit within 8% of body height of the surface and on their own side") {
  const MusclePreset& preset = test::gowPreset();
  // The talk's 14 muscles and the armpit corrective (one part per carrier the skeleton resolves).
  REQUIRE(preset.parts.size() == 15);
  for (const std::string& path : allCharacterPaths()) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    MuscleSet muscles = placeMuscles(r.character, r.landmarks, preset, Sides::kBoth);
    int muscle_parts = 0, corrective_parts = 0;
    for (const MusclePart& part : muscles.parts) {
      INFO(part.fullName());
      if (part.kind == PartKind::kMuscle) {
        ++muscle_parts;
        CHECK(part.carrier < 0);  // chosen by the bake from the weights
        continue;
      }
      ++corrective_parts;
      REQUIRE(r.landmarks.has(part.carrier_landmark));
      CHECK(part.carrier == r.landmarks.get(part.carrier_landmark).joint);
      // A sided carrier is on the part's own side (clavicle_l for the left); a central one is shared.
      const std::string suffix = part.carrier_landmark.substr(part.carrier_landmark.size() - 2);
      if (suffix == "_l" || suffix == "_r") CHECK(suffix == (part.side == "Left" ? "_l" : "_r"));
    }
    REQUIRE(muscle_parts == 28);
    // Chest, spine_t12 and the upper arm resolve on every character; clavicle and scapula may share a
    // joint with another carrier (one part then).
    CHECK(corrective_parts >= 6);
    CHECK(corrective_parts <= 10);
    CHECK(corrective_parts % 2 == 0);
    const double h = r.landmarks.body.height;
    double worst = 0.0;
    for (const MusclePart& part : muscles.parts) {
      for (const MuscleLocator* locator : {&part.origin, &part.insertion, &part.driver}) {
        INFO(part.fullName());
        double distance = distanceToBodySurface(r.character, locator->world);
        worst = std::max(worst, distance / h);
        CHECK(distance < 0.08 * h);
        double lateral = r.landmarks.body.lateralOffset(locator->world);
        if (part.side == "Left") CHECK(lateral > -0.01 * h);
        else CHECK(lateral < 0.01 * h);
        // The local position re-creates the world one through the attach joint's bind frame.
        CHECK((r.character.skeleton.bind_world[locator->joint] * locator->local - locator->world).norm() < 1e-9 * h);
      }
    }
    WARN(path << ": farthest locator from the surface " << worst * 100 << "% of body height");
  }
}

TEST_CASE("the right side is the exact mirror of the left") {
  const MusclePreset& preset = test::gowPreset();
  for (const std::string& path : allCharacterPaths()) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    MuscleSet muscles = placeMuscles(r.character, r.landmarks, preset, Sides::kBoth);
    const double h = r.landmarks.body.height;
    for (const MusclePart& left : muscles.parts) {
      if (left.side != "Left") continue;
      INFO(left.name);
      const MusclePart& right = findPart(muscles, "Right" + left.name);
      CHECK(right.kind == left.kind);
      if (left.kind == PartKind::kCorrective) {
        const std::string& l = left.carrier_landmark;
        const bool sided = l.size() > 2 && l.compare(l.size() - 2, 2, "_l") == 0;
        CHECK(right.carrier_landmark == (sided ? l.substr(0, l.size() - 2) + "_r" : l));
        CHECK(right.carrier == r.landmarks.get(right.carrier_landmark).joint);
      }
      CHECK((r.landmarks.body.mirror(right.origin.world) - left.origin.world).norm() < 1e-5 * h);
      CHECK((r.landmarks.body.mirror(right.insertion.world) - left.insertion.world).norm() < 1e-5 * h);
      CHECK((r.landmarks.body.mirror(right.driver.world) - left.driver.world).norm() < 1e-5 * h);
      CHECK(right.compression == left.compression);
      CHECK(right.stretch == left.stretch);
    }
  }
}

TEST_CASE("a right-side locator mirrored out of reach is refused, though its left twin is within reach") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const double h = r.landmarks.body.height;
  // A sagittal plane 50.2 body heights to the character's left of the scene's origin: the left locators
  // (within a body height of the origin) stay within the 100 body heights a muscle may lie in, their
  // mirror images land about 100.4 away.
  r.landmarks.body.midline += 50.2 * h * r.landmarks.body.lateral;
  CHECK_NOTHROW(placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kLeft));
  try {
    placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
    FAIL("placed a mirrored locator out of reach");
  } catch (const Error& error) {
    CHECK(error.code() == "PRESET_INVALID");
    CHECK(std::string(error.what()).find("places the mirrored origin of ") != std::string::npos);
  }
  CHECK_THROWS_AS(placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kRight), Error);
}

TEST_CASE("on the symmetric sample, placing the right side directly equals mirroring the left") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const MusclePreset& preset = test::gowPreset();
  MuscleSet muscles = placeMuscles(r.character, r.landmarks, preset, Sides::kBoth);
  std::map<std::string, Eigen::Vector3d> placed;
  double worst = 0.0;
  for (const PresetPart& spec : preset.parts) {
    FormulaContext context{&r.character.skeleton, &r.landmarks, "r", preset.reference_height, &placed, preset.file};
    Eigen::Vector3d origin = evaluateFormula(spec.origin, context);
    placed[spec.name + ".origin"] = origin;
    Eigen::Vector3d insertion = evaluateFormula(spec.insertion, context);
    placed[spec.name + ".insertion"] = insertion;
    // A corrective's parts (one per carrier) share its locators.
    const std::string name = spec.kind == PartKind::kMuscle ? spec.name : correctivePartName(spec.name, spec.carriers.front());
    const MusclePart& mirrored = findPart(muscles, "Right" + name);
    worst = std::max({worst, (origin - mirrored.origin.world).norm(), (insertion - mirrored.insertion.world).norm()});
  }
  // Joint axes (trapezius A's neck Z offset) are not mirrored by a formula, but the sample's neck Z
  // points straight back, so it lies in the sagittal plane.
  CHECK(worst < 1e-5 * r.landmarks.body.height);
}

TEST_CASE("trapezius locators reproduce the talk's Python exactly on the sample") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const Skeleton& s = r.character.skeleton;
  auto pos = [&](const char* name) {
    int j = s.find(name);
    REQUIRE(j >= 0);
    return Eigen::Vector3d(s.bindPosition(j));
  };
  // The talk's TrapezusMuscles.add(), with Maya's world axes (x lateral, y up, z forward).
  Eigen::Vector3d neck = pos("JONeck1"), head = pos("JOHead1"), clavicle = pos("JOLeftClavicle1"),
                  acromion = pos("JOLeftAcromion1"), scapula = pos("JOLeftScapula1"), spine3 = pos("JOBack3");
  Eigen::Vector3d neck_z_row = s.bind_world[s.find("JONeck1")].linear().col(2);  // worldMatrix[8:11]
  Eigen::Vector3d a_origin = neck_z_row * 0.02 + (neck + head) / 2.0;
  Eigen::Vector3d a_insertion = acromion + (clavicle - acromion) / 6.0;
  Eigen::Vector3d average = (neck + scapula) / 2.0;
  Eigen::Vector3d b_origin(neck.x(), average.y(), average.z());
  Eigen::Vector3d offset = (scapula - acromion) / 4.0;
  Eigen::Vector3d b_insertion = offset + acromion;
  Eigen::Vector3d c_origin(spine3.x(), spine3.y(), b_origin.z());
  Eigen::Vector3d c_insertion = offset * 3 + acromion;

  MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kLeft);
  REQUIRE(r.landmarks.body.height == Approx(1.8).margin(1e-9));
  CHECK((findPart(muscles, "LeftTrapeziusA").origin.world - a_origin).norm() < 1e-6);
  CHECK((findPart(muscles, "LeftTrapeziusA").insertion.world - a_insertion).norm() < 1e-6);
  CHECK((findPart(muscles, "LeftTrapeziusB").origin.world - b_origin).norm() < 1e-6);
  CHECK((findPart(muscles, "LeftTrapeziusB").insertion.world - b_insertion).norm() < 1e-6);
  CHECK((findPart(muscles, "LeftTrapeziusC").origin.world - c_origin).norm() < 1e-6);
  CHECK((findPart(muscles, "LeftTrapeziusC").insertion.world - c_insertion).norm() < 1e-6);
  // Attach joints as in the talk's createFromAttachObjs calls.
  CHECK(s.names[findPart(muscles, "LeftTrapeziusA").origin.joint] == "JONeck1");
  CHECK(s.names[findPart(muscles, "LeftTrapeziusA").insertion.joint] == "JOLeftClavicle1");
  CHECK(s.names[findPart(muscles, "LeftTrapeziusB").origin.joint] == "JOBack3");
  CHECK(s.names[findPart(muscles, "LeftTrapeziusB").insertion.joint] == "JOLeftAcromion1");
  CHECK(s.names[findPart(muscles, "LeftTrapeziusC").origin.joint] == "JOBack2");
  CHECK(s.names[findPart(muscles, "LeftBicep").origin.joint] == "LeftUpperArm1Twist0");
  CHECK(s.names[findPart(muscles, "LeftBicep").insertion.joint] == "LeftLowerArm1Twist0");
}

TEST_CASE("offsets scale with the body: a character scaled by k gets locators scaled by k") {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  test::Resolved scaled = r;
  const double k = 0.01;  // a character modelled in hectometres-per-unit, e.g. centimetres read as metres
  for (auto& bind : scaled.character.skeleton.bind_world) bind.translation() *= k;
  for (auto& part : scaled.character.meshes)
    for (auto& p : part.positions) p *= k;
  static const LandmarkRules rules = readLandmarkRules(test::presetsDir() + "/landmarks.json");
  static const std::vector<NamingMap> maps = readNamingMaps(test::presetsDir() + "/skeletons");
  LandmarkInputs inputs;
  inputs.maps = &maps;
  inputs.rules = &rules;
  scaled.landmarks = resolveLandmarks(scaled.character, inputs);
  MuscleSet a = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  MuscleSet b = placeMuscles(scaled.character, scaled.landmarks, test::gowPreset(), Sides::kBoth);
  REQUIRE(a.parts.size() == b.parts.size());
  for (size_t i = 0; i < a.parts.size(); ++i) {
    CHECK((a.parts[i].origin.world * k - b.parts[i].origin.world).norm() < 1e-9);
    CHECK((a.parts[i].insertion.world * k - b.parts[i].insertion.world).norm() < 1e-9);
  }
}
