// Split vertices (UV seams, hard edges) of one surface point must get the same muscle weights, or the
// seam would open when the muscles move.
#include "anatomy_fixture.h"
#include "pipeline/bake.h"

using namespace rigbake;

TEST_CASE("bake: split vertices at a seam get identical muscle weights") {
  std::vector<std::string> paths = test::sampleAndAssetPaths();
  for (const std::string& path : paths) {
    INFO(path);
    test::Resolved r = test::resolveShipped(path);
    MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
    BakeOptions options;
    options.influences = 10;
    BakeResult bake = bakeCharacter(r.character, muscles, options);
    int seams = 0;
    for (const BakedPart& part : bake.parts) {
      const MeshPart& mesh = r.character.meshes[part.mesh_part];
      std::map<std::tuple<double, double, double>, int> first_at;
      auto weightsOf = [&](const InfluenceSet& set, int v) {
        std::map<int, double> weights;
        for (int k = 0; k < set.slots_per_vertex; ++k) {
          double w = set.weights[v * set.slots_per_vertex + k];
          if (w > 0) weights[set.joints[v * set.slots_per_vertex + k]] += w;
        }
        return weights;
      };
      const InfluenceSet original = influencesFromMesh(mesh);
      for (int v = 0; v < static_cast<int>(mesh.positions.size()); ++v) {
        auto key = std::make_tuple(mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z());
        auto [it, inserted] = first_at.emplace(key, v);
        if (inserted) continue;
        const int twin = it->second;
        // Only where the input itself gave both copies the same skin.
        auto a = weightsOf(original, v), b = weightsOf(original, twin);
        bool same_input = a.size() == b.size();
        for (auto& [joint, w] : a) same_input = same_input && b.count(joint) && std::abs(b[joint] - w) < 1e-12;
        if (!same_input) continue;
        ++seams;
        auto baked_a = weightsOf(part.full, v), baked_b = weightsOf(part.full, twin);
        REQUIRE(baked_a.size() == baked_b.size());
        for (auto& [joint, w] : baked_a) CHECK(std::abs(baked_b[joint] - w) < 1e-12);
      }
    }
    // Every shared asset has split vertices (the generated sample is one welded surface): count them so
    // that the test cannot pass on none.
    if (path != test::sampleGlbPath()) CHECK(seams > 0);
  }
}
