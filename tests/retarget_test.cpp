// Retargeting (anatomy/retarget.cpp, `rigbake retarget`) over every ordered pair of the sample and the
// shared characters: the accuracy issue 5 asks for against the preset placed directly on the target,
// the round trip, the identity, invariance to scale and facing, the talk's positions-only files, and
// the CLI's failures.
#include "anatomy/retarget.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy_fixture.h"
#include "character_variants.h"
#include "cli_support.h"
#include "formats/muscle_json.h"

using namespace rigbake;

namespace {

struct Placed {
  std::string name;
  std::string path;
  test::Resolved resolved;
  MuscleSet muscles;
};

// A new armature root joint at `at` (scene space), under which the old roots hang: Blender's armature
// origin at the feet, or a root bone a rig moved away.
Character withRootAt(const Character& c, const Eigen::Vector3d& at) {
  Trs root_local;
  root_local.translation = c.skeleton.root_parent_world[0].inverse() * at;
  return test::withNewRoot(c, root_local);
}

// The sample's joints under Blender/Rigify names (spine, spine.001, ..., upper_arm.L, forearm.L.001);
// Rigify has no acromion or scapula bone, so those become names no map knows and are derived.
Character withRigifyNames(Character c) {
  const std::map<std::string, std::string> central = {{"JOPelvis1", "spine"},   {"JOBack1", "spine.001"},
                                                      {"JOBack2", "spine.002"}, {"JOBack3", "spine.003"},
                                                      {"JONeck1", "spine.004"}, {"JOHead1", "spine.006"}};
  // The sample's sided names after JOLeft/JORight/Left/Right; Rigify puts the side before a numbered
  // suffix (upper_arm.L.001).
  const std::map<std::string, std::string> sided = {
      {"Clavicle1", "shoulder"},        {"Acromion1", "acromion_helper"}, {"Scapula1", "scapula_helper"},
      {"UpperArm1", "upper_arm"},       {"UpperArm1Twist0", "upper_arm.001"}, {"LowerArm1", "forearm"},
      {"LowerArm1Twist0", "forearm.001"}, {"Hand1", "hand"},             {"UpLeg1", "thigh"},
      {"Leg1", "shin"},                 {"Foot1", "foot"},                 {"Toe1", "toe"}};
  for (std::string& name : c.skeleton.names) {
    if (auto it = central.find(name); it != central.end()) {
      name = it->second;
      continue;
    }
    bool renamed = false;
    for (const char* side : {"Left", "Right"}) {
      for (const std::string& prefix : {std::string("JO") + side, std::string(side)}) {
        if (renamed || name.rfind(prefix, 0) != 0) continue;
        auto it = sided.find(name.substr(prefix.size()));
        REQUIRE(it != sided.end());
        const std::string suffix = side[0] == 'L' ? ".L" : ".R";
        const size_t dot = it->second.find('.');
        name = dot == std::string::npos ? it->second + suffix : it->second.substr(0, dot) + suffix + it->second.substr(dot);
        renamed = true;
      }
    }
    INFO(name);
    REQUIRE(renamed);
  }
  return c;
}

Placed placed(const std::string& name, const std::string& path, Character character) {
  Placed p;
  p.name = name;
  p.path = path;
  p.resolved = test::resolveWithShippedPresets(std::move(character));
  p.muscles = placeMuscles(p.resolved.character, p.resolved.landmarks, test::gowPreset(), Sides::kBoth);
  return p;
}

// The sample, its VRM variants (with and without upperChest in the humanoid map), every shared asset
// present (glTF and FBX), and variants that change what a retarget must not depend on: a quarter turn
// about up, an armature root far below the hips, Rigify names, a scale of 100.
const std::vector<Placed>& characters() {
  static const std::vector<Placed> kCharacters = [] {
    std::vector<std::pair<std::string, std::string>> paths = {
        {"sample", test::sampleGlbPath()},
        {"sample VRM 0.x", test::sampleGlbPath(SampleVrm::kVrm0)},
        {"sample VRM 1.0", test::sampleGlbPath(SampleVrm::kVrm1)},
        {"sample VRM 0.x without upperChest", test::sampleVrmWithoutUpperChestPath(SampleVrm::kVrm0)},
        {"sample VRM 1.0 without upperChest", test::sampleVrmWithoutUpperChestPath(SampleVrm::kVrm1)}};
    for (const std::string& name : test::sharedAssetNames()) {
      std::string path = test::requireAsset(name);
      if (!path.empty()) paths.emplace_back(name, path);
    }
    for (const std::string name : {"fbx/Male_Casual.fbx", "fbx/Female_Casual.fbx", "fbx/Cowboy.fbx"}) {
      std::string path = test::requireAsset(name);
      if (!path.empty()) paths.emplace_back(name, path);
    }
    std::vector<Placed> all;
    for (const auto& [name, path] : paths) all.push_back(placed(name, path, loadCharacter(path).character));

    // Variants. Each is the body of a loaded character, so where `place` puts the preset on it is known.
    const Eigen::Affine3d quarter_turn(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()));
    auto body = [&](const std::string& name) -> const Placed* {
      for (const Placed& p : all)
        if (p.name == name) return &p;
      return nullptr;
    };
    std::vector<Placed> variants;
    auto add = [&](const std::string& from, const std::string& name, auto&& make) {
      const Placed* base = body(from);
      if (!base) return;
      // No path: a variant exists only in memory.
      variants.push_back(placed(base->name + ", " + name, "", make(base->resolved.character, base->resolved.landmarks)));
    };
    // A metre below the hips on a 1.8 m body.
    auto below_hips = [](const LandmarkSet& l) {
      return Eigen::Vector3d(l.get("pelvis").position - l.body.up * l.body.height / 1.8);
    };
    // The issue's case: a Rigify-named body whose armature root is a metre below the hips.
    add("sample", "Rigify names, root 1 m below the hips", [&](const Character& c, const LandmarkSet& l) {
      return withRootAt(withRigifyNames(c), below_hips(l));
    });
    add("sample VRM 0.x", "turned 90 degrees", [&](const Character& c, const LandmarkSet&) { return test::movedBy(c, quarter_turn); });
    add("sample VRM 0.x without upperChest", "root 1 m below the hips", [&](const Character& c, const LandmarkSet& l) {
      return withRootAt(c, below_hips(l));
    });
    add("CesiumMan.glb", "turned 90 degrees, scaled 100", [&](const Character& c, const LandmarkSet&) {
      return test::movedBy(c, quarter_turn * Eigen::Scaling(100.0));
    });
    add("RobotExpressive.glb", "root 1 m below the hips", [&](const Character& c, const LandmarkSet& l) {
      return withRootAt(c, below_hips(l));
    });
    add("fbx/Male_Casual.fbx", "turned -90 degrees, root 1 m below the hips", [&](const Character& c, const LandmarkSet& l) {
      return withRootAt(test::movedBy(c, quarter_turn.inverse()), quarter_turn.inverse() * below_hips(l));
    });
    for (Placed& v : variants) all.push_back(std::move(v));
    return all;
  }();
  return kCharacters;
}

MuscleSet retarget(const MuscleSet& muscles, const Placed& from, const Placed& to) {
  return retargetMuscles(muscles, from.resolved.character, from.resolved.landmarks, to.resolved.character,
                         to.resolved.landmarks, test::gowPreset());
}

struct Distances {
  double mean = 0.0;
  double max = 0.0;
  std::string worst;
};

// The parts of `b` in the order of `a`'s, matched by name. Every muscle must be in both; a corrective
// may be missing from one side only, where a character lacks its carrier landmark or carries it on a
// joint another carrier has (placement and retarget then make no part), and is then left out.
std::vector<std::pair<const MusclePart*, const MusclePart*>> matchedParts(const MuscleSet& a, const MuscleSet& b) {
  std::vector<std::pair<const MusclePart*, const MusclePart*>> pairs;
  auto find = [](const MuscleSet& set, const std::string& name) -> const MusclePart* {
    for (const MusclePart& part : set.parts)
      if (part.fullName() == name) return &part;
    return nullptr;
  };
  for (const MusclePart& part : a.parts) {
    const MusclePart* other = find(b, part.fullName());
    INFO(part.fullName());
    if (!other) REQUIRE(part.kind == PartKind::kCorrective);
    if (other) pairs.emplace_back(&part, other);
  }
  for (const MusclePart& part : b.parts) {
    INFO(part.fullName());
    if (!find(a, part.fullName())) REQUIRE(part.kind == PartKind::kCorrective);
  }
  return pairs;
}

// Distances between the same locators of two sets, parts matched by name.
Distances locatorDistances(const MuscleSet& a, const MuscleSet& b) {
  Distances d;
  int count = 0;
  for (const auto& [pa, pb] : matchedParts(a, b)) {
    const MuscleLocator* la[3] = {&pa->origin, &pa->insertion, &pa->driver};
    const MuscleLocator* lb[3] = {&pb->origin, &pb->insertion, &pb->driver};
    const char* which[3] = {"origin", "insertion", "driver"};
    for (int k = 0; k < 3; ++k) {
      double distance = (la[k]->world - lb[k]->world).norm();
      d.mean += distance;
      ++count;
      if (distance > d.max) {
        d.max = distance;
        d.worst = pa->fullName() + "." + which[k];
      }
    }
  }
  d.mean /= count;
  return d;
}

bool sameAttachJoints(const MuscleSet& a, const MuscleSet& b) {
  for (const auto& [pa, pb] : matchedParts(a, b)) {
    if (pa->origin.joint != pb->origin.joint || pa->insertion.joint != pb->insertion.joint || pa->driver.joint != pb->driver.joint ||
        pa->carrier != pb->carrier)
      return false;
  }
  return true;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// The talk's export shape: the muscle file without its rigbake block.
std::string positionsOnly(const MuscleSet& muscles, const Skeleton& skeleton) {
  nlohmann::json json = nlohmann::json::parse(muscleJson(muscles, skeleton, "gow_biped"));
  json.erase("rigbake");
  return json.dump(2);
}

}  // namespace

TEST_CASE("retargeting the preset placement lands near the direct placement for every ordered pair", "[shared:placed-characters]") {
  const std::vector<Placed>& all = characters();
  REQUIRE(all.size() >= 2);
  // Set RIGBAKE_PRINT_RETARGET_TABLE=1 to print the figures docs/retarget.md quotes.
  const bool print = std::getenv("RIGBAKE_PRINT_RETARGET_TABLE") != nullptr;
  for (const Placed& a : all) {
    for (const Placed& b : all) {
      if (&a == &b) continue;
      INFO(a.name << " -> " << b.name);
      const double height_b = b.resolved.landmarks.body.height;
      const double height_a = a.resolved.landmarks.body.height;
      MuscleSet moved = retarget(a.muscles, a, b);
      Distances d = locatorDistances(moved, b.muscles);
      MuscleSet back = retarget(moved, b, a);
      Distances round_trip = locatorDistances(back, a.muscles);
      if (print) {
        std::cout << std::fixed << std::setprecision(2) << "| " << a.name << " | " << b.name << " | "
                  << 100.0 * d.mean / height_b << "% | " << 100.0 * d.max / height_b << "% (" << d.worst << ") | "
                  << std::scientific << std::setprecision(1) << round_trip.max / height_a << " |\n";
      }
      INFO("mean " << d.mean / height_b << " max " << d.max / height_b << " of height at " << d.worst);
      CHECK(d.mean <= 0.02 * height_b);
      CHECK(d.max <= 0.04 * height_b);
      // The preset's attach landmarks decide the destination joints, as a direct placement does.
      CHECK(sameAttachJoints(moved, b.muscles));
      INFO("round trip max " << round_trip.max / height_a << " of height at " << round_trip.worst);
      CHECK(round_trip.max <= 1e-4 * height_a);
      CHECK(sameAttachJoints(back, a.muscles));
      // Lengths on the body scale with it.
      for (const auto& [pm, pb] : matchedParts(moved, b.muscles)) {
        CHECK(pm->bulge.isApprox(pb->bulge, 1e-9));
        CHECK(pm->compression == pb->compression);
      }
      CHECK(moved.body_height == height_b);
    }
  }
}

// `p`'s placement with every locator moved by `fraction` of its body height, each in another direction
// of the body frame: a hand-tuned edit of every point.
MuscleSet editedPlacement(const Placed& p, double fraction) {
  MuscleSet muscles = p.muscles;
  const BodyFrame& body = p.resolved.landmarks.body;
  int i = 0;
  for (MusclePart& part : muscles.parts) {
    for (MuscleLocator* locator : {&part.origin, &part.insertion, &part.driver}) {
      const Eigen::Vector3d d = Eigen::Vector3d(std::sin(1.0 + i), std::cos(2.0 + 3.0 * i), std::sin(5.0 * i)).normalized();
      ++i;
      const Eigen::Vector3d edit = body.lateral * d.x() + body.up * d.y() + body.forward * d.z();
      *locator = locatorOn(p.resolved.character.skeleton, locator->joint, locator->world + fraction * body.height * edit);
    }
  }
  return muscles;
}

TEST_CASE("retargeting lands every part within 2% of body height of the target's own placement over every pair", "[shared:placed-characters]") {
  // Issue 33: whatever the facing (+Z, -Z, turned), armature root, scale or joint names, over every ordered
  // pair of the sample's variants, the shared glTF and FBX characters and the variants made of them. The
  // preset's placement lands where `place` puts it on the target; a hand-tuned edit of every locator by
  // 1.5% of body height lands 1.5% of the target's height from there: edits keep their size on the body.
  const std::vector<Placed>& all = characters();
  REQUIRE(all.size() >= 2);
  const bool print = std::getenv("RIGBAKE_PRINT_RETARGET_TABLE") != nullptr;
  constexpr double kEdit = 0.015;
  double worst = 0.0, worst_edited = 0.0, edit_error = 0.0;
  std::string worst_at, worst_edited_at;
  int pairs = 0;
  for (const Placed& a : all) {
    const MuscleSet edited = editedPlacement(a, kEdit);
    for (const Placed& b : all) {
      if (&a == &b) continue;
      ++pairs;
      const double height_b = b.resolved.landmarks.body.height;
      const Distances d = locatorDistances(retarget(a.muscles, a, b), b.muscles);
      if (d.max / height_b > worst || worst_at.empty()) {
        worst = d.max / height_b;
        worst_at = a.name + " -> " + b.name + " at " + d.worst;
      }
      const MuscleSet moved = retarget(edited, a, b);
      for (const auto& [pm, pb] : matchedParts(moved, b.muscles)) {
        for (auto [x, y] : {std::pair{&pm->origin, &pb->origin}, {&pm->insertion, &pb->insertion}, {&pm->driver, &pb->driver}}) {
          const double distance = (x->world - y->world).norm() / height_b;
          edit_error = std::max(edit_error, std::abs(distance - kEdit));
          if (distance > worst_edited) {
            worst_edited = distance;
            worst_edited_at = a.name + " -> " + b.name + " at " + pm->fullName();
          }
        }
      }
    }
  }
  if (print)
    std::cout << std::setprecision(3) << all.size() << " characters, " << pairs << " pairs: worst part " << 100.0 * worst
              << "% of height (" << (worst > 0.0 ? worst_at : "every part exactly") << "); edited by " << 100.0 * kEdit << "%: worst " << 100.0 * worst_edited
              << "% (" << worst_edited_at << "), edit size kept to " << edit_error << " of height\n";
  INFO("worst " << worst << " of height at " << worst_at << "; edited: worst " << worst_edited << " at " << worst_edited_at);
  CHECK(worst <= 0.02);
  CHECK(worst_edited <= 0.02);
  CHECK(edit_error <= 1e-9);
}

TEST_CASE("retargeting a character onto itself is the identity", "[shared:placed-characters]") {
  for (const Placed& a : characters()) {
    INFO(a.name);
    MuscleSet same = retarget(a.muscles, a, a);
    CHECK(locatorDistances(same, a.muscles).max <= 1e-9);
    CHECK(sameAttachJoints(same, a.muscles));
  }
}

TEST_CASE("retargeting onto a scaled turned and moved copy applies that similarity", "[shared:placed-characters]") {
  // A character exported in centimetres, facing the other way and standing elsewhere is the same body:
  // retargeting onto it must give exactly the transformed locators.
  static const std::vector<NamingMap> maps = readNamingMaps(test::presetsDir() + "/skeletons");
  static const LandmarkRules rules = readLandmarkRules(test::presetsDir() + "/landmarks.json");
  Eigen::Affine3d similarity = Eigen::Translation3d(3.0, -1.0, 2.0) *
                               Eigen::AngleAxisd(2.5, Eigen::Vector3d(0.2, 1.0, -0.3).normalized()) *
                               Eigen::Scaling(100.0);
  for (const Placed& a : characters()) {
    INFO(a.name);
    Placed moved_character;
    moved_character.resolved.character = a.resolved.character;
    Character& c = moved_character.resolved.character;
    for (Eigen::Affine3d& bind : c.skeleton.bind_world) bind = similarity * bind;
    for (MeshPart& part : c.meshes) {
      for (Eigen::Vector3d& p : part.positions) p = similarity * p;
    }
    LandmarkInputs inputs;
    inputs.maps = &maps;
    inputs.rules = &rules;
    moved_character.resolved.landmarks = resolveLandmarks(c, inputs);
    MuscleSet moved = retarget(a.muscles, a, moved_character);
    double worst = 0.0;
    for (size_t i = 0; i < moved.parts.size(); ++i) {
      const MusclePart& p = a.muscles.parts[i];
      const MusclePart& q = moved.parts[i];
      for (auto [before, after] : {std::pair{&p.origin, &q.origin}, {&p.insertion, &q.insertion}, {&p.driver, &q.driver}}) {
        worst = std::max(worst, (similarity * before->world - after->world).norm());
        CHECK(before->joint == after->joint);
      }
    }
    CHECK(worst <= 1e-9 * moved_character.resolved.landmarks.body.height);
  }
}

TEST_CASE("the talk's positions-only files retarget like full rigbake files", "[shared:placed-characters]") {
  test::TempDir dir;
  const std::vector<Placed>& all = characters();
  for (const Placed& a : all) {
    const Placed& b = all[(&a - all.data() + 1) % all.size()];
    INFO(a.name << " -> " << b.name);
    const std::string talk = dir / "talk.json";
    writeText(talk, positionsOnly(a.muscles, a.resolved.character.skeleton));
    MuscleSet read = readMuscleJson(talk, a.resolved.character, a.resolved.landmarks, test::gowPreset());
    MuscleSet from_talk = retarget(read, a, b);
    MuscleSet from_full = retarget(a.muscles, a, b);
    CHECK(locatorDistances(from_talk, from_full).max <= 1e-9 * b.resolved.landmarks.body.height);
    CHECK(sameAttachJoints(from_talk, from_full));
  }
  // And through the CLI, whose output then reads back on the target character (the last one with a file).
  const Placed& a = all.front();
  const Placed& b = *std::find_if(all.rbegin(), all.rend(), [](const Placed& p) { return !p.path.empty(); });
  const std::string talk = dir / "talk.json";
  const std::string out = dir / "moved.json";
  writeText(talk, positionsOnly(a.muscles, a.resolved.character.skeleton));
  test::CliResult r = test::runCli("retarget " + talk + " --from " + a.path + " --to '" + b.path + "' -o " + out);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  MuscleSet reread = readMuscleJson(out, b.resolved.character, b.resolved.landmarks, test::gowPreset());
  CHECK(locatorDistances(reread, retarget(a.muscles, a, b)).max <= 1e-9 * b.resolved.landmarks.body.height);
}

TEST_CASE("a locator on a joint with no landmark on or above it is refused before anything moves", "[shared:placed-characters]") {
  const Placed& a = characters().front();
  Placed with_prop = a;
  Skeleton& skeleton = with_prop.resolved.character.skeleton;
  // A second root (a prop or weapon joint) that no landmark rides on.
  skeleton.names.push_back("Prop");
  skeleton.parents.push_back(-1);
  skeleton.nodes.push_back(-1);
  skeleton.bind_world.push_back(Eigen::Affine3d(Eigen::Translation3d(0.5, 1.0, 0.3)));
  skeleton.rest_local.push_back(Trs{});
  skeleton.root_parent_world.push_back(Eigen::Affine3d::Identity());
  MuscleSet muscles = a.muscles;
  muscles.parts.back().insertion = locatorOn(skeleton, skeleton.size() - 1, muscles.parts.back().insertion.world);
  try {
    retargetMuscles(muscles, with_prop.resolved.character, with_prop.resolved.landmarks, a.resolved.character,
                    a.resolved.landmarks, test::gowPreset(), "tuned.json");
    FAIL("expected RETARGET_LOCATOR_UNANCHORED");
  } catch (const Error& e) {
    CHECK(e.code() == "RETARGET_LOCATOR_UNANCHORED");
    CHECK(e.where() == "tuned.json#/rigbake/muscles/" + muscles.parts.back().fullName() + "/insertion");
    CHECK(std::string(e.what()).find("'Prop'") != std::string::npos);
    CHECK(e.exitCode() == ExitCode::kInvalidInput);
  }
}

TEST_CASE("hand-tuned parts the preset lacks ride on the landmark of their joint", "[shared:placed-characters]") {
  const std::vector<Placed>& all = characters();
  const Placed& a = all.front();
  const Placed& b = all.back();
  // A part named nothing the preset knows, with the bicep's locators: without the preset's placement to
  // carry it is anchored by its joints' landmark frames alone, and lands within the issue's 2 % of body
  // height of where the bicep lands (the bicep itself lands exactly on the target's own placement;
  // measured: at most 1.3 % on this pair).
  MuscleSet tuned = a.muscles;
  for (MusclePart& part : tuned.parts) part.name = "Tuned" + part.name;
  MuscleSet moved_tuned = retarget(tuned, a, b);
  MuscleSet moved = retarget(a.muscles, a, b);
  for (size_t i = 0; i < moved.parts.size(); ++i) {
    const MusclePart& p = moved.parts[i];
    const MusclePart& q = moved_tuned.parts[i];
    if (p.name != "Bicep" && p.name != "TricepLateral" && p.name != "TricepMedial") continue;
    INFO(p.fullName());
    CHECK((p.origin.world - q.origin.world).norm() <= 0.02 * b.resolved.landmarks.body.height);
    CHECK((p.insertion.world - q.insertion.world).norm() <= 0.02 * b.resolved.landmarks.body.height);
  }
}

namespace {
// Every failure: one line on stderr starting with the code, the given exit status, no output file.
void expectFailure(const test::CliResult& result, const std::string& code, int exit_code, const std::string& output) {
  INFO("stderr: " << result.err);
  CHECK(result.exit_code == exit_code);
  // "CODE where: message", or "CODE: message" when there is no where (usage errors).
  CHECK((result.err.rfind(code + " ", 0) == 0 || result.err.rfind(code + ": ", 0) == 0));
  CHECK(test::lineCount(result.err) == 1);
  CHECK_FALSE(test::fileExists(output));
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(output).parent_path()))
    CHECK(entry.path().filename().string().find("rigbake-tmp") == std::string::npos);
}
}  // namespace

TEST_CASE("cli: retarget failures give a stable code and exit status and write nothing") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  const std::string muscles = dir / "muscles.json";
  REQUIRE(test::runCli("place " + sample + " -o " + muscles).exit_code == 0);
  const std::string out = dir / "moved.json";

  SECTION("missing muscle file") {
    test::CliResult r = test::runCli("retarget " + (dir / "nope.json") + " --from " + sample + " --to " + sample + " -o " + out);
    expectFailure(r, "IO_FILE_NOT_FOUND", 2, out);
    CHECK(r.err.find("nope.json") != std::string::npos);
  }
  SECTION("missing target character") {
    expectFailure(test::runCli("retarget " + muscles + " --from " + sample + " --to " + (dir / "nope.glb") + " -o " + out),
                  "IO_FILE_NOT_FOUND", 2, out);
  }
  SECTION("muscles that were not made for --from") {
    std::string other = test::requireAsset("CesiumMan.glb");
    if (other.empty()) return;
    test::CliResult r = test::runCli("retarget " + muscles + " --from " + other + " --to " + sample + " -o " + out);
    expectFailure(r, "MUSCLES_MISMATCH", 3, out);
    CHECK(r.err.find("muscles.json") != std::string::npos);
  }
  SECTION("a naming map that does not exist") {
    expectFailure(test::runCli("retarget " + muscles + " --from " + sample + " --to " + sample + " --map-to nosuchmap -o " + out),
                  "MAP_NOT_FOUND", 3, out);
  }
  SECTION("no target") {
    expectFailure(test::runCli("retarget " + muscles + " --from " + sample + " -o " + out), "USAGE", 1, out);
  }
}

TEST_CASE("cli: retarget writes byte-identical JSON and reports each locator's frame") {
  std::string other = test::requireAsset("Quaternius_Cyberpunk_Character.glb");
  if (other.empty()) return;
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  const std::string muscles = dir / "muscles.json";
  REQUIRE(test::runCli("place " + sample + " -o " + muscles).exit_code == 0);
  test::CliResult first = test::runCli("retarget " + muscles + " --from " + sample + " --to " + other + " -o " + (dir / "a.json") + " --json");
  test::CliResult second = test::runCli("retarget " + muscles + " --from " + sample + " --to " + other + " -o " + (dir / "b.json"));
  REQUIRE(first.exit_code == 0);
  REQUIRE(second.exit_code == 0);
  CHECK(test::slurp(dir / "a.json") == test::slurp(dir / "b.json"));
  nlohmann::json summary = nlohmann::json::parse(first.out);
  CHECK(summary["to"] == "Quaternius_Cyberpunk_Character.glb");
  // As many parts as a placement on Cyberpunk makes: the 28 muscles and the armpit correctives whose
  // carriers its skeleton resolves on distinct joints.
  REQUIRE(test::runCli("place " + other + " -o " + (dir / "placed.json")).exit_code == 0);
  const nlohmann::json placed = nlohmann::json::parse(test::slurp(dir / "placed.json"));
  CHECK(summary["muscle_parts"] == placed["rigbake"]["muscles"].size());
  CHECK(summary["muscle_parts"].get<int>() > 28);
  bool found_bicep_origin = false;
  for (const nlohmann::json& entry : summary["locators"]) {
    if (entry["part"] == "LeftBicep" && entry["locator"] == "origin") {
      found_bicep_origin = true;
      CHECK(entry["frame"] == "upper_arm_l->forearm_l");
      CHECK(entry["from_joint"] == "LeftUpperArm1Twist0");
      CHECK(entry["to_joint"] == "UpperArm.L");
    }
  }
  CHECK(found_bicep_origin);
  nlohmann::json written = nlohmann::json::parse(test::slurp(dir / "a.json"));
  CHECK(written["rigbake"]["character"] == "Quaternius_Cyberpunk_Character.glb");
  // A corrective keeps what it is and its carrier landmark, found again on the new skeleton.
  const nlohmann::json& armpit = written["rigbake"]["muscles"]["LeftAxillaUpperArm"];
  CHECK(armpit["kind"] == "corrective");
  CHECK(armpit["carrier_landmark"] == "upper_arm_l");
  CHECK(placed["rigbake"]["muscles"]["LeftAxillaUpperArm"]["carrier_landmark"] == "upper_arm_l");
}

TEST_CASE("cli: a VRM 0.x avatar without upperChest places and retargets both ways") {
  test::TempDir dir;
  const std::string sample = test::sampleGlbPathForCli();
  const std::string avatar = dir / "avatar.vrm";
  test::CliResult made = test::runCli("sample --vrm 0 --no-upper-chest -o " + avatar);
  INFO(made.err);
  REQUIRE(made.exit_code == 0);
  REQUIRE(test::runCli("place " + sample + " -o " + (dir / "sample_muscles.json")).exit_code == 0);
  REQUIRE(test::runCli("place " + avatar + " -o " + (dir / "avatar_muscles.json")).exit_code == 0);
  // Before landmark resolution kept spine_t12 off the chest bone, both failed with
  // RETARGET_SEGMENT_DEGENERATE: landmarks 'spine_t12' and 'chest' coincide.
  test::CliResult onto = test::runCli("retarget " + (dir / "sample_muscles.json") + " --from " + sample + " --to " +
                                      avatar + " -o " + (dir / "onto.json"));
  INFO(onto.err);
  CHECK(onto.exit_code == 0);
  test::CliResult from = test::runCli("retarget " + (dir / "avatar_muscles.json") + " --from " + avatar + " --to " +
                                      sample + " -o " + (dir / "from.json"));
  INFO(from.err);
  CHECK(from.exit_code == 0);
  // The option only makes sense for a VRM humanoid map.
  expectFailure(test::runCli("sample --no-upper-chest -o " + (dir / "plain.glb")), "USAGE", 1, dir / "plain.glb");
}
