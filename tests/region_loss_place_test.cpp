// Where a region's loss beyond plain skinning comes from (pipeline/region_loss_place.h), on a sphere
// whose moves and volumes are known.
#include <catch2/catch.hpp>

#include <cmath>

#include "pipeline/region_loss_place.h"

namespace rigbake {
namespace {

// A unit sphere as a latitude-longitude grid (poles single vertices), triangles facing out.
MeshPart sphere(int rings, int segments) {
  MeshPart part;
  const double pi = 3.14159265358979323846;
  part.positions.push_back({0.0, 1.0, 0.0});
  for (int r = 1; r < rings; ++r) {
    const double polar = pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double around = 2.0 * pi * s / segments;
      part.positions.push_back({std::sin(polar) * std::cos(around), std::cos(polar), -std::sin(polar) * std::sin(around)});
    }
  }
  part.positions.push_back({0.0, -1.0, 0.0});
  const int south = static_cast<int>(part.positions.size()) - 1;
  auto at = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) part.triangles.push_back({0, at(1, s), at(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      part.triangles.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      part.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) part.triangles.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
  return part;
}

// Every vertex on joint 0, but `moved` on joint 1.
InfluenceSet oneJointEach(size_t count, const std::vector<int>& moved) {
  InfluenceSet set;
  set.slots_per_vertex = 1;
  set.joints.assign(count, 0);
  set.weights.assign(count, 1.0);
  for (int v : moved) set.joints[static_cast<size_t>(v)] = 1;
  return set;
}

struct Scene {
  Character character;  // its one mesh part
  MeshPart mesh;
  VolumeSurface surface;
  ClosedPatch patch;
  InfluenceSet plain, rig;
  double bind_volume = 0.0;
  RegionPiece piece(const InfluenceSet* full = nullptr) const { return RegionPiece{0, &surface, &patch, &plain, &rig, full}; }
};

}  // namespace

TEST_CASE("region loss place: the vertex the rig pulls in is named, with its share of the volume the region loses") {
  Scene scene;
  scene.mesh = sphere(12, 16);
  scene.mesh.name = "ball";
  scene.character.meshes = {scene.mesh};
  scene.surface = buildVolumeSurface(scene.mesh, 1e-9);
  scene.patch = scene.surface.whole;
  scene.bind_volume = enclosedVolume(scene.patch, scene.surface.bind);
  const int moved = 1 + 5 * 16 + 3;  // a vertex on the sixth ring, away from the poles
  scene.plain = oneJointEach(scene.mesh.positions.size(), {});
  scene.rig = oneJointEach(scene.mesh.positions.size(), {moved});
  // Joint 1 pulls its vertex 5 % of the radius towards the centre.
  const Eigen::Vector3d in = -0.05 * scene.mesh.positions[static_cast<size_t>(moved)];
  std::vector<Eigen::Affine3d> frame = {Eigen::Affine3d::Identity(), Eigen::Affine3d(Eigen::Translation3d(in))};
  RegionLossScratch scratch;
  const RegionLossPlace place = regionLossPlace(scene.character, {scene.piece()}, frame, scene.bind_volume, 0.5, &scratch);
  REQUIRE(place.at.found);
  CHECK(place.at.vertex == moved);
  CHECK(place.at.mesh_part == 0);
  CHECK(place.at.mesh == "ball");
  CHECK(place.time == 0.5);
  CHECK((place.at.bind - scene.mesh.positions[static_cast<size_t>(moved)]).norm() == 0.0);
  CHECK(regionLossPlaceText(place).find(" points of it at vertex " + std::to_string(moved) + " of mesh 'ball'") != std::string::npos);
  // The exact difference, from the two posed surfaces' volumes.
  std::vector<Eigen::Vector3d> posed = scene.surface.bind;
  posed[static_cast<size_t>(scene.surface.weld_of_vertex[static_cast<size_t>(moved)])] += in;
  const double exact = 100.0 * (enclosedVolume(scene.patch, posed) / scene.bind_volume - 1.0);
  CHECK(exact < -0.05);
  CHECK(place.difference_points == Approx(exact).epsilon(1e-9));
  // One vertex moves, so it holds the whole first-order difference; about the midpoint the
  // second-order term of its own move is gone, so that is the exact difference to rounding (a single
  // vertex's move changes the volume linearly: its triangles' cones are linear in it).
  CHECK(place.first_order_points == Approx(exact).epsilon(1e-9));
  CHECK(place.points == Approx(-exact).epsilon(1e-9));
  // Without the weights before the cut (validate's case) the cut's share is not known; with them it is
  // the rig's volume less theirs: all of the loss when they are plain skinning's, none when the cut
  // changed nothing.
  CHECK_FALSE(place.cut_measured);
  const RegionLossPlace cut_all = regionLossPlace(scene.character, {scene.piece(&scene.plain)}, frame, scene.bind_volume, 0.5, &scratch);
  CHECK(cut_all.cut_measured);
  CHECK(cut_all.cut_points == Approx(exact).epsilon(1e-12));
  CHECK(cut_all.difference_points == place.difference_points);
  const RegionLossPlace cut_none = regionLossPlace(scene.character, {scene.piece(&scene.rig)}, frame, scene.bind_volume, 0.5, &scratch);
  CHECK(cut_none.cut_measured);
  CHECK(cut_none.cut_points == 0.0);

  // Pushed out instead, nothing is taken: no place.
  frame[1] = Eigen::Affine3d(Eigen::Translation3d(-in));
  const RegionLossPlace out = regionLossPlace(scene.character, {scene.piece()}, frame, scene.bind_volume, 0.5, &scratch);
  CHECK_FALSE(out.at.found);
  CHECK(regionLossPlaceText(out).empty());
  CHECK(out.difference_points > 0.05);
}

TEST_CASE("region loss place: on a capped piece the border's moves count through the cap, and the shares sum to the difference") {
  // The upper half of the sphere, closed by the cap over its equator: a region cut out of a body.
  Scene scene;
  scene.mesh = sphere(12, 16);
  scene.character.meshes = {scene.mesh};
  scene.surface = buildVolumeSurface(scene.mesh, 1e-9);
  std::vector<int> upper;
  for (size_t t = 0; t < scene.surface.whole.triangles.size(); ++t) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int w : scene.surface.whole.triangles[t]) centre += scene.surface.bind[static_cast<size_t>(w)] / 3.0;
    if (centre.y() > 0.0) upper.push_back(static_cast<int>(t));
  }
  scene.patch = closePatch(scene.surface, upper);
  REQUIRE(scene.patch.holes.size() == 1);
  scene.bind_volume = enclosedVolume(scene.patch, scene.surface.bind);
  // Three equator vertices slide up, along the sphere (a move in the surface's tangent plane, which
  // changes the volume only through the cap it lifts), and a vertex above them moves a little out.
  const int equator = 1 + 5 * 16;  // ring 6 of 12 is the equator
  const std::vector<int> moved = {equator + 2, equator + 3, equator + 4, 1 + 2 * 16 + 7};
  scene.plain = oneJointEach(scene.mesh.positions.size(), {});
  scene.rig = InfluenceSet{};
  scene.rig.slots_per_vertex = 2;
  for (size_t v = 0; v < scene.mesh.positions.size(); ++v) {
    const bool is_moved = std::find(moved.begin(), moved.end(), static_cast<int>(v)) != moved.end();
    const bool on_equator = is_moved && static_cast<int>(v) < equator + 16;
    scene.rig.joints.insert(scene.rig.joints.end(), {0, on_equator ? 1 : 2});
    scene.rig.weights.insert(scene.rig.weights.end(), {is_moved ? 0.0 : 1.0, is_moved ? 1.0 : 0.0});
  }
  // Joint 1 lifts by 5 % of the radius, joint 2 by 1 %.
  const std::vector<Eigen::Affine3d> frame = {Eigen::Affine3d::Identity(), Eigen::Affine3d(Eigen::Translation3d(0.0, 0.05, 0.0)),
                                              Eigen::Affine3d(Eigen::Translation3d(0.0, 0.01, 0.0))};
  RegionLossScratch scratch;
  const RegionLossPlace place = regionLossPlace(scene.character, {scene.piece()}, frame, scene.bind_volume, 0.0, &scratch);
  REQUIRE(place.at.found);
  CHECK(place.at.vertex >= equator + 2);
  CHECK(place.at.vertex <= equator + 4);
  CHECK(place.difference_points < -1.0);
  // Several vertices move: the first-order sum is the difference to a small fraction of it.
  CHECK(place.first_order_points == Approx(place.difference_points).epsilon(0.01));
  CHECK(place.points > 0.25 * -place.difference_points);
  CHECK(place.points < -place.difference_points);
}

}  // namespace rigbake
