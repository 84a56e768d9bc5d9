// Issue 29 asks that the skin be judged on variants no weight was tuned for. The coarse variant: the
// mannequin simplified by meshoptimizer to about 1,200 vertices (meshopt_simplify keeps its topology and
// its vertices' own positions and weights). What holds there is asserted; the figures that do not yet
// meet the goals (roughness) are printed by the test's INFO and listed in docs/deformation-quality.md.
#include <catch2/catch.hpp>

#include <map>
#include <meshoptimizer.h>

#include "anatomy_fixture.h"
#include "formats/preset_json.h"
#include "pipeline/bake.h"

using namespace rigbake;

namespace {

// Every skinned part simplified to about `vertices` vertices, its used vertices renumbered in order.
Character coarseVariant(const Character& input, size_t vertices) {
  Character coarse = input;
  for (MeshPart& mesh : coarse.meshes) {
    if (!mesh.skinned || mesh.triangles.empty()) continue;
    std::vector<unsigned> indices;
    for (const auto& triangle : mesh.triangles)
      for (int corner : triangle) indices.push_back(static_cast<unsigned>(corner));
    std::vector<float> positions;
    for (const Eigen::Vector3d& p : mesh.positions)
      for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(p[k]));
    std::vector<unsigned> kept(indices.size());
    // A closed body has about two triangles per vertex: six indices per vertex wanted.
    kept.resize(meshopt_simplify(kept.data(), indices.data(), indices.size(), positions.data(), mesh.positions.size(),
                                 3 * sizeof(float), vertices * 6, 1.0f, 0, nullptr));
    MeshPart out = mesh;
    out.positions.clear();
    out.joints.clear();
    out.weights.clear();
    out.triangles.clear();
    std::map<unsigned, int> renumbered;
    const int slots = mesh.influences_per_vertex;
    for (size_t i = 0; i < kept.size(); i += 3) {
      std::array<int, 3> triangle;
      for (int c = 0; c < 3; ++c) {
        auto [it, added] = renumbered.emplace(kept[i + c], static_cast<int>(out.positions.size()));
        if (added) {
          out.positions.push_back(mesh.positions[kept[i + c]]);
          for (int k = 0; k < slots; ++k) {
            out.joints.push_back(mesh.joints[kept[i + c] * slots + k]);
            out.weights.push_back(mesh.weights[kept[i + c] * slots + k]);
          }
        }
        triangle[c] = it->second;
      }
      out.triangles.push_back(triangle);
    }
    mesh = std::move(out);
  }
  return coarse;
}

}  // namespace

TEST_CASE("coarse variant: the mannequin at about 1,200 vertices keeps its regions and more elbow volume than plain skinning") {
  const test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const Character coarse = coarseVariant(r.character, 1200);
  REQUIRE(coarse.meshes[0].positions.size() > 1000);
  REQUIRE(coarse.meshes[0].positions.size() < 1500);
  const MuscleSet muscles = placeMuscles(coarse, r.landmarks, test::gowPreset(), Sides::kBoth);
  BakeOptions options;
  options.influences = 10;
  options.regions = resolveBodyRegions(coarse, r.landmarks, readRegionPreset(test::presetsDir() + "/regions/body.json"));
  const BakeResult bake = bakeCharacter(coarse, muscles, options);
  REQUIRE(bake.quality.clips.size() == 3);
  for (const ClipQuality& clip : bake.quality.clips) {
    const double* rise = clip.surface.roughness_rise;
    INFO(clip.clip << ": volume input " << 100.0 * clip.body.input.change << " %, dual quaternions "
                   << 100.0 * clip.body.dual_quaternion.change << " %, centres of rotation "
                   << 100.0 * clip.surface.centre_of_rotation.change << " %, rig " << 100.0 * clip.body.rig.change
                   << " %; roughness rise input " << 1000.0 * rise[0] << " mm, rig " << 1000.0 * rise[3] << " mm");
    // The rig keeps more of the body's volume than plain skinning on every clip of the coarse body.
    CHECK(std::abs(clip.body.rig.change) < std::abs(clip.body.input.change));
    const VolumeExtreme* occupied = clip.surface.occupied;
    INFO("occupied volume input " << 100.0 * occupied[0].change << " %, dual quaternions " << 100.0 * occupied[1].change
                                  << " %, centres of rotation " << 100.0 * occupied[2].change << " %, rig " << 100.0 * occupied[3].change << " %");
    // And by the occupied volume, which a fit cannot keep by pushing skin into a fold (ElbowFlexion
    // -0.52 % against plain skinning's -1.04 %, ArmRaise +0.80 % against +1.15 %).
    CHECK(std::abs(occupied[3].change) < std::abs(occupied[0].change));
    // No region loses more than 1 point beyond plain skinning (SKIN_REGION_VOLUME_LOSS).
    for (size_t i = 0; i < clip.regions.size(); ++i) {
      INFO(bake.quality.regions[i]);
      CHECK(100.0 * (std::min(clip.regions[i].input.change, 0.0) - clip.regions[i].rig.change) <= 1.0);
    }
  }
  const ClipQuality& elbow = bake.quality.clips[0];
  REQUIRE(elbow.clip == "ElbowFlexion");
  // Centres of rotation, the yardstick, round the coarse elbow out too.
  CHECK(std::abs(elbow.surface.centre_of_rotation.change) < std::abs(elbow.body.input.change));
}
