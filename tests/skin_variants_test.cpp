// Issue 29 asks that the skin be judged on variants of the characters: turned and moved in its scene, or
// hung under a new armature root. Nothing about a body's skin depends on where the scene puts it or how
// many nodes sit above its pelvis. Each variant (tests/character_variants.h) is placed and baked as the
// original is, and every skin figure must come out as the original's.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "character_variants.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"
#include "pipeline/muscle_weights.h"
#include "pipeline/rom.h"
#include "skin_bake_fixture.h"

using namespace rigbake;

namespace {

// The bakes' skin figures agree, the variant's lengths `length_scale` times the original's: the skinnings
// of the input's weights to 1e-3, the rig's (whose rounded weights may break a few near ties the other
// way) to 1 %.
void checkSameFigures(const BakeResult& a, const BakeResult& b, double length_scale, double occupied_margin = 2e-4) {
  REQUIRE(b.quality.clips.size() == a.quality.clips.size());
  for (size_t c = 0; c < a.quality.clips.size(); ++c) {
    const ClipQuality& x = a.quality.clips[c];
    const ClipQuality& y = b.quality.clips[c];
    INFO(x.clip);
    CHECK(y.body.input.change == Approx(x.body.input.change).margin(1e-6));
    // The fit takes 64 poses of many samples by farthest-point sampling, where last bits can break a
    // near tie the other way: the Cowboy re-rooted (20 clips) took 1 pose of 64 elsewhere, and its rig's
    // change moved by up to 0.22 % of itself.
    CHECK(y.body.rig.change == Approx(x.body.rig.change).epsilon(1e-2).margin(1e-5));
    REQUIRE(x.surface.measured);
    REQUIRE(y.surface.measured);
    CHECK(y.surface.roughness_floor == Approx(length_scale * x.surface.roughness_floor).epsilon(1e-6));
    CHECK(roughnessRatio(y.surface) == Approx(roughnessRatio(x.surface)).epsilon(1e-2));
    // Where plain skinning leaves the skin as smooth as at bind (a limb one joint holds), the ratio is
    // taken against the floor, which scales with the body: the same in any unit.
    SurfaceFigures rigid_x = x.surface, rigid_y = y.surface;
    rigid_x.roughness_rise[0] = rigid_y.roughness_rise[0] = 0.0;
    CHECK(roughnessRatio(rigid_y) == Approx(roughnessRatio(rigid_x)).epsilon(1e-2));
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      INFO("skinning " << s);
      const double relative = s == 3 ? 1e-2 : 1e-3;
      CHECK(y.surface.roughness_rise[s] == Approx(length_scale * x.surface.roughness_rise[s]).epsilon(relative).margin(1e-7));
      CHECK(y.surface.edge_strain[s] == Approx(x.surface.edge_strain[s]).epsilon(relative));
      CHECK(y.surface.area_strain[s] == Approx(x.surface.area_strain[s]).epsilon(relative));
      // The occupied volume is sampled on a grid along the scene's axes, which cuts a turned body
      // elsewhere: measured within 0.008 points on the mannequin.
      CHECK(y.surface.occupied[s].change == Approx(x.surface.occupied[s].change).margin(occupied_margin));
    }
    REQUIRE(y.creases.size() == x.creases.size());
    for (size_t k = 0; k < x.creases.size(); ++k) {
      INFO(x.creases[k].crease);
      CHECK(y.creases[k].crease == x.creases[k].crease);
      for (int s = 0; s < kSurfaceSkinnings; ++s) CHECK(std::abs(y.creases[k].skinning[s].through - x.creases[k].skinning[s].through) <= 2);
    }
  }
}

// The scene carried 70 degrees about a slanted axis and moved 1.2 m.
Eigen::Affine3d turnedAndMoved() {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.rotate(Eigen::AngleAxisd(70.0 * M_PI / 180.0, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()));
  t.pretranslate(Eigen::Vector3d(0.3, -0.2, 1.1));
  return t;
}

// The variant's landmarks ride the same joints (by name) at the original's places carried by `motion`,
// and its bake's figures equal the original's bake `a`.
void checkSameSkin(const test::Resolved& original, const BakeResult& a, const test::Resolved& variant,
                   const Eigen::Affine3d& motion = Eigen::Affine3d::Identity(), double occupied_margin = 2e-4) {
  for (const auto& [name, landmark] : original.landmarks.landmarks) {
    INFO("landmark " << name);
    REQUIRE(variant.landmarks.has(name) == original.landmarks.has(name));
    if (!landmark.resolved) continue;
    const Landmark& other = variant.landmarks.get(name);
    CHECK(variant.character.skeleton.names[other.joint] == original.character.skeleton.names[landmark.joint]);
    CHECK((other.position - motion * landmark.position).norm() < 1e-9);
  }
  const BakeResult b = test::bakeWithBodyRegions(variant);
  size_t differing = 0, total = 0;
  for (size_t p = 0; p < a.parts.size(); ++p)
    for (size_t i = 0; i < a.parts[p].quantized.weights.size(); ++i, ++total)  // skin-local joints: same order
      differing += a.parts[p].quantized.weights[i] != b.parts[p].quantized.weights[i] || a.parts[p].quantized.joints[i] != b.parts[p].quantized.joints[i];
  // Distances and turns move in their last bits when the scene turns, so the rounding of the weights to
  // 0.001 breaks a few near ties the other way (turned: measured 155 of 120,160 slots). The skinnings of
  // the input's weights agree to 1e-3 of their figures; the rig's, which those few vertices move, to 1 %
  // (turned, measured: ForearmTwist's roughness 0.46 %, its edge strain 0.13 %).
  INFO("rounded weight slots differing: " << differing << " of " << total);
  CHECK(differing * 200 < total);
  checkSameFigures(a, b, 1.0, occupied_margin);
}

void checkSameSkin(const test::Resolved& original, const test::Resolved& variant,
                   const Eigen::Affine3d& motion = Eigen::Affine3d::Identity()) {
  checkSameSkin(original, test::bakeWithBodyRegions(original), variant, motion);
}

}  // namespace

TEST_CASE("skin figures: the mannequin turned 70 degrees about a slanted axis and moved 1.2 m gives the same figures") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  const Eigen::Affine3d t = turnedAndMoved();
  checkSameSkin(original, test::resolveWithShippedPresets(test::movedBy(original.character, t)), t);
}

TEST_CASE("skin figures: the mannequin hung under a new root joint, turned a quarter about X at its feet, gives the same figures") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  // Blender's armature object: Z up turned into glTF's Y up, its origin on the floor below the pelvis.
  Trs root_local;
  root_local.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2.0, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d pelvis = original.landmarks.get("pelvis").position;
  root_local.translation = original.character.skeleton.root_parent_world[0].inverse() *
                           Eigen::Vector3d(pelvis.x(), pelvis.y() - 0.95, pelvis.z());
  test::Resolved rerooted = test::resolveWithShippedPresets(test::withNewRoot(original.character, root_local));
  REQUIRE(rerooted.character.skeleton.size() == original.character.skeleton.size() + 1);
  REQUIRE(rerooted.character.skeleton.names[0] == "root");
  // With range-of-motion clips too: they are built on the skeleton's hierarchy and the body's frame, which
  // the new root's quarter turn must not tilt.
  static const RomPreset rom = readRomPreset(test::presetsDir() + "/rom/default.json");
  const std::vector<std::string> moves = {"elbow_flexion", "shoulder_abduction", "hip_flexion"};
  test::Resolved with_rom = original;
  appendMeasureOnlyClips(&with_rom.character, buildRom(with_rom.character, with_rom.landmarks, rom, moves));
  appendMeasureOnlyClips(&rerooted.character, buildRom(rerooted.character, rerooted.landmarks, rom, moves));
  REQUIRE(with_rom.character.clips.size() == original.character.clips.size() + moves.size());
  checkSameSkin(with_rom, rerooted);
}

// The response fit weighs lengths (how far a muscle's skin may go in, how rough the move is) against
// volume ratios: per body height, so that a character's unit does not change its rig. Per metre, the
// mannequin in centimetres kept almost none of its volume (ElbowFlexion -0.48 % against -0.02 %).
TEST_CASE("skin figures: the mannequin in centimetres (its scene scaled 100 times) gives the same figures, lengths times 100") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  const Eigen::Affine3d t(Eigen::Scaling(100.0));
  const test::Resolved scaled = test::resolveWithShippedPresets(test::movedBy(original.character, t));
  for (const double smoothness : {0.0, 1000.0}) {
    INFO("fit smoothness " << smoothness);
    const BakeResult a = test::bakeWithBodyRegions(original, ResponseMode::kAuto, smoothness);
    const BakeResult b = test::bakeWithBodyRegions(scaled, ResponseMode::kAuto, smoothness);
    checkSameFigures(a, b, 100.0);
  }
}

// A studio's character need not have one armature root: the Cowboy's FBX has two, one under the armature
// node (scaled 3.78 from Blender's export) and one (Bone.001) under an unscaled node. Hung under one new
// root, the second root's rest pose and keys are re-expressed through that scale. Turned, the whole
// scene moves rigidly.
TEST_CASE("skin figures: the Cowboy, whose two armature roots hang under differently scaled nodes, turned and moved or hung under one new root gives the same figures") {
  const std::string path = test::requireAsset("fbx/Cowboy.fbx");
  if (path.empty()) return;
  const test::Resolved original = test::resolveShipped(path);
  const Skeleton& skeleton = original.character.skeleton;
  std::vector<int> roots;
  for (int j = 0; j < skeleton.size(); ++j)
    if (skeleton.parents[j] < 0) roots.push_back(j);
  REQUIRE(roots.size() == 2);
  const double scale_ratio = std::cbrt(skeleton.root_parent_world[roots[0]].linear().determinant() /
                                       skeleton.root_parent_world[roots[1]].linear().determinant());
  REQUIRE(std::abs(scale_ratio - 1.0) > 1.0);  // measured 3.78
  Trs root_local;
  root_local.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2.0, Eigen::Vector3d::UnitX()));
  const test::Resolved rerooted = test::resolveWithShippedPresets(test::withNewRoot(original.character, root_local));
  REQUIRE(rerooted.character.skeleton.size() == skeleton.size() + 1);
  const BakeResult bake = test::bakeWithBodyRegions(original);  // once, for both variants
  {
    INFO("hung under one new root");
    checkSameSkin(original, bake, rerooted);
  }
  {
    // The mannequin's turn, on an FBX body whose armature is Z-up under its scaled node.
    INFO("turned 70 degrees about a slanted axis and moved 1.2 m");
    const Eigen::Affine3d t = turnedAndMoved();
    // The grid cuts the lenses where the Cowboy's skin folds into itself (its idle pose's, under
    // centres of rotation and the rig) elsewhere: measured within 0.035 points.
    checkSameSkin(original, bake, test::resolveWithShippedPresets(test::movedBy(original.character, t)), t, 5e-4);
  }
}

// 3ds Max's Biped (presets/skeletons/max_biped.json) hangs the clavicles from the neck and the thighs
// from the first spine joint unless its Triangle Neck and Triangle Pelvis options say otherwise, where
// the other shipped namings hang them from the chest and the pelvis. The muscles spanning the shoulder
// and the hip must not care: they walk the body's hierarchy (presets/landmarks.json "limb_roots").
TEST_CASE("skin figures: the mannequin with its clavicles under the neck and its thighs under the spine, as 3ds Max's Biped hangs them, gives the same figures") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  const Skeleton& skeleton = original.character.skeleton;
  CHECK(original.landmarks.anatomical_parents == skeleton.parents);
  Character biped = original.character;
  const std::pair<const char*, const char*> moves[] = {{"JOLeftClavicle1", "JONeck1"}, {"JORightClavicle1", "JONeck1"},
                                                       {"JOLeftUpLeg1", "JOBack1"}, {"JORightUpLeg1", "JOBack1"}};
  for (const auto& [limb, trunk] : moves) {
    const int joint = skeleton.find(limb), new_parent = skeleton.find(trunk);
    REQUIRE(skeleton.parents[joint] == skeleton.parents[new_parent]);
    biped = test::withJointUnderSibling(std::move(biped), joint, new_parent);
  }
  const test::Resolved variant = test::resolveWithShippedPresets(std::move(biped));
  for (const auto& [limb, trunk] : moves) REQUIRE(variant.character.skeleton.parents[skeleton.find(limb)] == skeleton.find(trunk));
  // The body's hierarchy is the original's, joint for joint.
  CHECK(variant.landmarks.anatomical_parents == skeleton.parents);
  checkSameSkin(original, variant);
  // gow_biped has no muscle at the hip; gow_fullbody's leg muscles span the same joints as on the original.
  const MusclePreset fullbody = readMusclePreset(test::presetsDir() + "/muscles/gow_fullbody.json");
  const MuscleSet a = placeMuscles(original.character, original.landmarks, fullbody, Sides::kBoth);
  const MuscleSet b = placeMuscles(variant.character, variant.landmarks, fullbody, Sides::kBoth);
  REQUIRE(a.parts.size() == b.parts.size());
  int crossing_hip = 0;
  for (size_t m = 0; m < a.parts.size(); ++m) {
    INFO(a.parts[m].fullName());
    const std::vector<int> spanned = spannedJoints(spannedHierarchy(a, skeleton), a.parts[m]);
    CHECK(spannedJoints(spannedHierarchy(b, variant.character.skeleton), b.parts[m]) == spanned);
    crossing_hip += std::count(spanned.begin(), spanned.end(), skeleton.find("JOLeftUpLeg1")) > 0 &&
                    std::count(spanned.begin(), spanned.end(), skeleton.find("JOPelvis1")) > 0;
  }
  CHECK(crossing_hip >= 2);
}

// Exporters write a mesh's vertices and triangles in their own order; the welded surface, the muscles'
// share fields, the fit and the figures must not depend on it. Until the cap loops paired the steps at
// a vertex where openings touch by turning about it (docs/deformation-quality.md, "Holes are capped"),
// the fit did on two shared characters: the regions' caps, and so the fit's region rows, followed the
// numbering, and Male Casual's rig's whole-body change moved by 2.0 points, CesiumMan's by 1.0.
TEST_CASE("skin figures: the mannequin with its vertices and triangles in another order gives the same weights and figures") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  std::vector<std::vector<int>> order;
  const test::Resolved variant = test::resolveWithShippedPresets(test::withVerticesReordered(original.character, &order));
  const BakeResult a = test::bakeWithBodyRegions(original);
  const BakeResult b = test::bakeWithBodyRegions(variant);
  REQUIRE(a.parts.size() == b.parts.size());
  size_t differing = 0, total = 0;
  double full_difference = 0.0;  // the weights with the muscles added, before the fit, pruning and rounding
  for (size_t p = 0; p < a.parts.size(); ++p) {
    REQUIRE(a.parts[p].mesh_part == b.parts[p].mesh_part);
    const std::vector<int>& to = order[a.parts[p].mesh_part];
    const QuantizedInfluences& x = a.parts[p].quantized;
    const QuantizedInfluences& y = b.parts[p].quantized;
    const int slots = x.slots_per_vertex;
    REQUIRE(y.slots_per_vertex == slots);
    for (size_t v = 0; v < to.size(); ++v)
      for (int k = 0; k < slots; ++k, ++total) {
        const size_t i = v * slots + k, j = static_cast<size_t>(to[v]) * slots + k;
        differing += x.weights[i] != y.weights[j] || x.joints[i] != y.joints[j];
      }
    const InfluenceSet& fx = a.parts[p].full;
    const InfluenceSet& fy = b.parts[p].full;
    const int full_slots = fx.slots_per_vertex;
    for (size_t v = 0; v < to.size(); ++v) {
      std::map<int, double> on_x, on_y;  // per joint: slot order may differ
      for (int k = 0; k < full_slots; ++k) {
        on_x[fx.joints[v * full_slots + k]] += fx.weights[v * full_slots + k];
        on_y[fy.joints[static_cast<size_t>(to[v]) * full_slots + k]] += fy.weights[static_cast<size_t>(to[v]) * full_slots + k];
      }
      for (const auto& [joint, weight] : on_x) full_difference = std::max(full_difference, std::abs(weight - on_y[joint]));
      for (const auto& [joint, weight] : on_y) full_difference = std::max(full_difference, std::abs(weight - on_x[joint]));
    }
  }
  CHECK(full_difference < 1e-12);
  // Measured: 58 of 120,160 rounded slots differ (sums in another order break near ties of the rounding).
  INFO("rounded weight slots differing: " << differing << " of " << total);
  CHECK(differing * 200 < total);
  checkSameFigures(a, b, 1.0);
}

namespace {

// `name` (a shared asset) with its vertices and triangles in another order: the same regions, and the
// rig's whole-body and regions' changes as close as the input skinning's are (sums in another order;
// measured: the whole body within 0.0044 points on Male Casual and 1e-6 on CesiumMan, the regions
// within 0.077 and 5e-5; before, 2.0 and 1.0 points apart).
void checkVertexOrderLeavesTheRig(const std::string& name) {
  const std::string path = test::requireAsset(name);
  if (path.empty()) return;
  const test::Resolved original = test::resolveShipped(path);
  std::vector<std::vector<int>> order;
  const test::Resolved variant = test::resolveWithShippedPresets(test::withVerticesReordered(original.character, &order));
  const BakeResult a = test::bakeWithBodyRegions(original);
  const BakeResult b = test::bakeWithBodyRegions(variant);
  REQUIRE(b.quality.regions == a.quality.regions);
  REQUIRE(b.quality.clips.size() == a.quality.clips.size());
  double input = 0.0, rig = 0.0, regions = 0.0;  // points
  for (size_t c = 0; c < a.quality.clips.size(); ++c) {
    const ClipQuality& x = a.quality.clips[c];
    const ClipQuality& y = b.quality.clips[c];
    input = std::max(input, 100.0 * std::abs(x.body.input.change - y.body.input.change));
    rig = std::max(rig, 100.0 * std::abs(x.body.rig.change - y.body.rig.change));
    for (size_t r = 0; r < a.quality.regions.size(); ++r)
      regions = std::max(regions, 100.0 * std::abs(x.regions[r].rig.change - y.regions[r].rig.change));
  }
  INFO(name << ": largest difference of the input's whole-body change " << input << ", the rig's " << rig << ", a region's under the rig "
            << regions << " points");
  CHECK(input < 0.01);
  CHECK(rig < 0.01);
  CHECK(regions < 0.1);
}

}  // namespace

TEST_CASE("skin figures: CesiumMan and Male Casual with their vertices and triangles in another order fit the same rig") {
  checkVertexOrderLeavesTheRig("CesiumMan.glb");
  checkVertexOrderLeavesTheRig("fbx/Male_Casual.fbx");
}
