// The occupied volume (pipeline/occupied_volume.h): known solids whose windings overlap, turn inside
// out, or have edges exactly on the sampling grid; then the mannequin, whose folded elbow the signed
// volume counts twice.
#include <catch2/catch.hpp>

#include <vector>

#include "anatomy_fixture.h"
#include "pipeline/bake.h"
#include "pipeline/occupied_volume.h"

using namespace rigbake;

namespace {

// An axis-aligned box from `low` to `high`, its triangles facing out (or in, `inside_out`); `open_top`
// leaves its top face off, as a hole to cap.
struct Box {
  ClosedPatch patch;
  std::vector<Eigen::Vector3d> corners;
};

Box box(const Eigen::Vector3d& low, const Eigen::Vector3d& high, bool inside_out = false, bool open_top = false) {
  Box out;
  for (int k = 0; k < 8; ++k)
    out.corners.emplace_back(k & 1 ? high.x() : low.x(), k & 2 ? high.y() : low.y(), k & 4 ? high.z() : low.z());
  // Each face's corners counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; ++f) {
    const int* q = faces[f];
    if (open_top && f == 1) {
      out.patch.holes.push_back({q[0], q[1], q[2], q[3]});  // the missing face's order: its cap faces out
      continue;
    }
    std::array<int, 3> first = {q[0], q[1], q[2]}, second = {q[0], q[2], q[3]};
    if (inside_out) {
      std::swap(first[1], first[2]);
      std::swap(second[1], second[2]);
    }
    out.patch.triangles.push_back(first);
    out.patch.triangles.push_back(second);
  }
  return out;
}

}  // namespace

TEST_CASE("occupied volume: overlapping, inside-out, open and grid-aligned boxes") {
  const Box unit = box({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0});
  for (int axis = 0; axis < 3; ++axis) {
    INFO("axis " << axis);
    CHECK(windingExcess({{&unit.patch, &unit.corners}}, axis, 0.01) == Approx(0.0).margin(1e-12));
    CHECK(occupiedVolume({{&unit.patch, &unit.corners}}, axis, 0.01) == Approx(1.0));
    // A second box over half of the first: the half counted twice is the excess.
    const Box shifted = box({0.5, 0.0, 0.0}, {1.5, 1.0, 1.0});
    CHECK(windingExcess({{&unit.patch, &unit.corners}, {&shifted.patch, &shifted.corners}}, axis, 0.01) == Approx(0.5));
    CHECK(occupiedVolume({{&unit.patch, &unit.corners}, {&shifted.patch, &shifted.corners}}, axis, 0.01) == Approx(1.5));
    // Turned inside out: the signed volume is -1, and nothing is occupied.
    const Box inverted = box({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, true);
    CHECK(windingExcess({{&inverted.patch, &inverted.corners}}, axis, 0.01) == Approx(-1.0));
    CHECK(occupiedVolume({{&inverted.patch, &inverted.corners}}, axis, 0.01) == Approx(0.0).margin(1e-12));
    // Its top left open: the cap closes it, as the signed volume closes it.
    const Box open = box({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, false, true);
    CHECK(occupiedVolume({{&open.patch, &open.corners}}, axis, 0.01) == Approx(1.0));
  }
  // Faces and diagonals exactly on the columns' centres: each column that touches an edge is counted
  // by one triangle, never two, so a box within a box still counts each point once.
  const Box outer = box({0.005, 0.005, 0.005}, {0.805, 0.805, 0.805});
  const Box inner = box({0.105, 0.105, 0.105}, {0.705, 0.705, 0.705});
  for (int axis = 0; axis < 3; ++axis) {
    INFO("axis " << axis);
    const double excess = windingExcess({{&outer.patch, &outer.corners}, {&inner.patch, &inner.corners}}, axis, 0.01);
    CHECK(excess == Approx(0.6 * 0.6 * 0.6).epsilon(0.05));
  }
}

TEST_CASE("occupied volume: the mannequin's folded elbow occupies less than its signed volume says, under every skinning") {
  const test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  BakeOptions options;
  options.influences = 10;
  options.measure_skin = true;
  const BakeResult bake = bakeCharacter(r.character, muscles, options);
  REQUIRE(bake.quality.clips.size() == 3);
  const ClipQuality& elbow = bake.quality.clips[0];
  REQUIRE(elbow.clip == "ElbowFlexion");
  REQUIRE(elbow.surface.measured);
  const VolumeExtreme* occupied = elbow.surface.occupied;
  INFO("occupied volume change: plain " << 100.0 * occupied[0].change << " %, dual quaternions " << 100.0 * occupied[1].change
                                        << " %, centres of rotation " << 100.0 * occupied[2].change << " %, rig "
                                        << 100.0 * occupied[3].change << " %; signed: plain " << 100.0 * elbow.body.input.change
                                        << " %, rig " << 100.0 * elbow.body.rig.change << " %");
  // The rig folds more skin through at the elbow than plain skinning (docs/deformation-quality.md,
  // Creases): the space it occupies shrinks by more than its signed volume says, and by more than dual
  // quaternions' does, though less than plain skinning's.
  CHECK(occupied[3].change < elbow.body.rig.change - 0.0005);
  CHECK(occupied[3].change < occupied[1].change);
  CHECK(std::abs(occupied[3].change) < 0.5 * std::abs(occupied[0].change));
  // The figure is a volume change of a whole body, not noise: within a few percent.
  for (int s = 0; s < kSurfaceSkinnings; ++s) CHECK(std::abs(occupied[s].change) < 0.05);
}

TEST_CASE("occupied volume: the exposed share of skin inside other skin, for the fit's --fit-volume occupied") {
  const Box outer = box({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0});
  const Box inner = box({0.3, 0.3, 0.3}, {0.6, 0.6, 0.6});
  const Box apart = box({2.0, 0.0, 0.0}, {3.0, 1.0, 1.0});
  for (int axis = 0; axis < 3; ++axis) {
    INFO("axis " << axis);
    const std::vector<std::vector<float>> share =
        exposedShare({{&outer.patch, &outer.corners}, {&inner.patch, &inner.corners}, {&apart.patch, &apart.corners}}, axis, 0.01);
    REQUIRE(share.size() == 3);
    // The box inside another bounds nothing it occupies: every corner 0; the others bound it: 1.
    for (int k = 0; k < 8; ++k) {
      CHECK(share[0][static_cast<size_t>(k)] == 1.0f);
      CHECK(share[1][static_cast<size_t>(k)] == 0.0f);
      CHECK(share[2][static_cast<size_t>(k)] == 1.0f);
    }
  }
  // A box half inside the first, seen along x: the columns cross only its two x faces, the one inside
  // (x = 0.5) buried, the one outside (x = 1.5) bounding the occupied space.
  const Box shifted = box({0.5, 0.2, 0.2}, {1.5, 0.8, 0.8});
  const std::vector<std::vector<float>> half = exposedShare({{&outer.patch, &outer.corners}, {&shifted.patch, &shifted.corners}}, 0, 0.01);
  for (int k = 0; k < 8; ++k) {
    INFO("corner " << k);
    CHECK(half[1][static_cast<size_t>(k)] == (k & 1 ? 1.0f : 0.0f));
  }
}
