// Issue 29 asks that the skin be judged on variants of the characters, among them one turned and moved
// in its scene: nothing about a body's skin depends on where the scene puts it. The whole character is
// carried by one rigid transform (its meshes, bind pose and the frame its root joints are animated in),
// placed and baked as the original is, and every skin figure must come out as the original's.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cmath>

#include "skin_bake_fixture.h"

using namespace rigbake;

namespace {

// The character with every bind-pose and scene position carried by `t`; the joints' local transforms
// (and so every clip) are unchanged, because a root joint's frame is its parent node's world transform.
Character turned(Character character, const Eigen::Affine3d& t) {
  for (MeshPart& mesh : character.meshes)
    for (Eigen::Vector3d& p : mesh.positions) p = t * p;
  for (Eigen::Affine3d& bind : character.skeleton.bind_world) bind = t * bind;
  for (Eigen::Affine3d& frame : character.skeleton.root_parent_world) frame = t * frame;
  for (Eigen::Affine3d& placement : character.skin_placement) placement = t * placement;
  return character;
}

}  // namespace

TEST_CASE("skin figures: the mannequin turned 70 degrees about a slanted axis and moved 1.2 m gives the same figures") {
  const test::Resolved original = test::resolveShipped(test::sampleGlbPath());
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.rotate(Eigen::AngleAxisd(70.0 * M_PI / 180.0, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()));
  t.pretranslate(Eigen::Vector3d(0.3, -0.2, 1.1));
  const test::Resolved moved = test::resolveWithShippedPresets(turned(original.character, t));
  const BakeResult a = test::bakeWithBodyRegions(original);
  const BakeResult b = test::bakeWithBodyRegions(moved);
  size_t differing = 0, total = 0;
  for (size_t p = 0; p < a.parts.size(); ++p)
    for (size_t i = 0; i < a.parts[p].quantized.weights.size(); ++i, ++total)
      differing += a.parts[p].quantized.weights[i] != b.parts[p].quantized.weights[i] || a.parts[p].quantized.joints[i] != b.parts[p].quantized.joints[i];
  // Distances and turns move in their last bits when the scene turns, so the rounding of the weights to
  // 0.001 breaks a few near ties the other way: measured 155 of 120,160 slots. The skinnings of the
  // input's weights agree to 1e-3 of their figures; the rig's, which those few vertices move, to 1 %
  // (measured: ForearmTwist's roughness 0.46 %, its edge strain 0.13 %).
  INFO("rounded weight slots differing: " << differing << " of " << total);
  CHECK(differing * 200 < total);
  REQUIRE(a.quality.clips.size() == 3);
  REQUIRE(b.quality.clips.size() == a.quality.clips.size());
  for (size_t c = 0; c < a.quality.clips.size(); ++c) {
    const ClipQuality& x = a.quality.clips[c];
    const ClipQuality& y = b.quality.clips[c];
    INFO(x.clip);
    CHECK(y.body.input.change == Approx(x.body.input.change).margin(1e-6));
    CHECK(y.body.rig.change == Approx(x.body.rig.change).margin(1e-5));
    REQUIRE(x.surface.measured);
    REQUIRE(y.surface.measured);
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      INFO("skinning " << s);
      const double relative = s == 3 ? 1e-2 : 1e-3;
      CHECK(y.surface.roughness_rise[s] == Approx(x.surface.roughness_rise[s]).epsilon(relative).margin(1e-7));
      CHECK(y.surface.edge_strain[s] == Approx(x.surface.edge_strain[s]).epsilon(relative));
      CHECK(y.surface.area_strain[s] == Approx(x.surface.area_strain[s]).epsilon(relative));
      // The occupied volume is sampled on a grid along the scene's axes, which the turn moves through the
      // body: measured within 0.008 points.
      CHECK(y.surface.occupied[s].change == Approx(x.surface.occupied[s].change).margin(2e-4));
    }
    REQUIRE(y.creases.size() == x.creases.size());
    for (size_t k = 0; k < x.creases.size(); ++k) {
      INFO(x.creases[k].crease);
      CHECK(y.creases[k].crease == x.creases[k].crease);
      for (int s = 0; s < kSurfaceSkinnings; ++s) CHECK(std::abs(y.creases[k].skinning[s].through - x.creases[k].skinning[s].through) <= 2);
    }
  }
}
