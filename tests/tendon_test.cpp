// The muscles' shares faded over their tendons (MuscleWeightOptions::tendon_fraction; docs/muscle-weights.md,
// "Tendons", measured and not the default). Issue 29's own finding, the mannequin's forearm skin losing
// 3.5 points more than plain skinning at full ElbowFlexion, is the biceps' share past its insertion: the
// skinned joint rides the upper arm, so its bulge moves forearm skin in the upper arm's frame.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>

#include "anatomy_fixture.h"
#include "pipeline/bake.h"
#include "skin_bake_fixture.h"

using namespace rigbake;

namespace {

// The left forearm's joint region at full ElbowFlexion: points lost beyond plain skinning.
double forearmLoss(const BakeResult& bake) {
  const auto& names = bake.quality.joint_regions;
  const auto region = std::find(names.begin(), names.end(), "JOLeftLowerArm1") - names.begin();
  REQUIRE(static_cast<size_t>(region) < names.size());
  for (const ClipQuality& clip : bake.quality.clips)
    if (clip.clip == "ElbowFlexion") return 100.0 * clip.joint_regions[static_cast<size_t>(region)].loss;
  FAIL("no ElbowFlexion clip");
  return 0.0;
}

}  // namespace

TEST_CASE("tendons: with the muscles' shares faded over their tendons the mannequin's forearm keeps plain skinning's volume at full elbow flexion") {
  const test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  BakeOptions options;
  options.influences = 4;
  const double round_ends = forearmLoss(test::bakeWithBodyRegions(r, options));
  options.weights.tendon_fraction = 0.2;
  const double tendons = forearmLoss(test::bakeWithBodyRegions(r, options));
  INFO("forearm's loss beyond plain skinning: " << round_ends << " -> " << tendons << " points");
  // Measured: 3.54 -> 0.07 points.
  CHECK(round_ends > 3.0);
  CHECK(tendons < 0.5);
}
