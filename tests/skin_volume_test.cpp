// Closed patches and their volumes (pipeline/skin_volume.h) on the sample and every shared character:
// a patch cut out of a surface is closed by exactly its boundary, and the volume sums give the bits of
// the plain one-triangle-at-a-time sum, which the fit and the figures rely on to agree.
#include <catch2/catch.hpp>

#include <algorithm>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "formats/gltf_document.h"
#include "pipeline/skin_volume.h"
#include "anatomy_fixture.h"

namespace rigbake {
namespace {

// The reference: every triangle, then every cap triangle, one after the other, in double.
double volumeOneByOne(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded, const Eigen::Vector3d& origin) {
  double volume = 0.0;
  for (const auto& t : patch.triangles) {
    const Eigen::Vector3d a = welded[t[0]] - origin, b = welded[t[1]] - origin, c = welded[t[2]] - origin;
    volume += a.dot(b.cross(c));
  }
  for (const std::vector<int>& hole : patch.holes) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int w : hole) centre += welded[w];
    centre = centre / static_cast<double>(hole.size()) - origin;
    for (size_t k = 0; k < hole.size(); ++k) {
      const Eigen::Vector3d a = welded[hole[k]] - origin, b = welded[hole[(k + 1) % hole.size()]] - origin;
      volume += a.dot(b.cross(centre));
    }
  }
  return volume / 6.0;
}

// Some cuts of a surface's triangles: all, the first half and a third (odd and even counts), the
// triangles on one side of a plane through the middle (a cut across the body with long boundaries).
std::vector<std::vector<int>> cuts(const VolumeSurface& surface, const std::vector<Eigen::Vector3d>& welded) {
  const size_t count = surface.whole.triangles.size();
  std::vector<int> all(count), half, third, above;
  std::iota(all.begin(), all.end(), 0);
  for (size_t t = 0; t < count; ++t) {
    if (t < count / 2 + 1) half.push_back(static_cast<int>(t));
    if (t % 3 == 0) third.push_back(static_cast<int>(t));
  }
  double low = 1e30, high = -1e30;
  for (const Eigen::Vector3d& p : welded) {
    low = std::min(low, p.y());
    high = std::max(high, p.y());
  }
  for (size_t t = 0; t < count; ++t) {
    const auto& w = surface.whole.triangles[t];
    if (welded[w[0]].y() + welded[w[1]].y() + welded[w[2]].y() > 1.5 * (low + high)) above.push_back(static_cast<int>(t));
  }
  return {all, half, third, above};
}

// Every cut of every skinned part of the sample and the shared characters, closed: `visit` gets the
// file, the welded surface and positions, the cut and its patch.
void forEachCut(const std::function<void(const std::string& path, const VolumeSurface& surface, const std::vector<Eigen::Vector3d>& welded,
                                         const std::vector<int>& cut, const ClosedPatch& patch)>& visit) {
  for (const std::string& path : test::sampleAndAssetPaths()) {
    const Character character = loadCharacter(path).character;
    for (const MeshPart& mesh : character.meshes) {
      if (!mesh.skinned || mesh.positions.empty()) continue;
      INFO(path << " mesh " << mesh.name);
      const VolumeSurface surface = buildVolumeSurface(mesh, 1e-6);
      const std::vector<Eigen::Vector3d> welded = weldedPositions(surface, mesh.positions);
      for (const std::vector<int>& cut : cuts(surface, welded)) {
        const ClosedPatch patch = closePatch(surface, cut);
        INFO(patch.triangles.size() << " triangles, " << patch.holes.size() << " holes");
        visit(path, surface, welded, cut, patch);
      }
    }
  }
}

TEST_CASE("skin volume: a patch's volume is the one-triangle-at-a-time sum to the bit, about any point") {
  forEachCut([](const std::string&, const VolumeSurface&, const std::vector<Eigen::Vector3d>& welded, const std::vector<int>&,
                const ClosedPatch& patch) {
    if (patch.triangles.empty()) return;
    // Moved and scaled copies stand in for two other posings.
    std::vector<Eigen::Vector3d> moved = welded, scaled = welded;
    for (Eigen::Vector3d& p : moved) p += Eigen::Vector3d(0.3, -1.7, 2.1);
    for (Eigen::Vector3d& p : scaled) p *= 1.25;
    const Eigen::Vector3d first = welded[patch.triangles[0][0]];
    CHECK(enclosedVolume(patch, welded) == volumeOneByOne(patch, welded, first));
    for (const Eigen::Vector3d& origin : {Eigen::Vector3d::Zero().eval(), Eigen::Vector3d(10.0, -3.0, 7.5)})
      CHECK(enclosedVolumeAbout(patch, welded, origin) == volumeOneByOne(patch, welded, origin));
    const std::array<double, 3> three = enclosedVolumes(patch, {&welded, &moved, &scaled});
    CHECK(three[0] == enclosedVolume(patch, welded));
    CHECK(three[1] == enclosedVolume(patch, moved));
    CHECK(three[2] == enclosedVolume(patch, scaled));
  });
}

TEST_CASE("skin volume: a cut patch's holes are its boundary edges reversed, each once, in closed loops") {
  forEachCut([](const std::string& path, const VolumeSurface& surface, const std::vector<Eigen::Vector3d>&, const std::vector<int>& cut,
                const ClosedPatch& patch) {
    REQUIRE(patch.triangles.size() == cut.size());
    for (size_t i = 0; i < cut.size(); ++i) CHECK(patch.triangles[i] == surface.whole.triangles[static_cast<size_t>(cut[i])]);
    // Boundary edges: a -> b used once and b -> a never.
    std::map<std::pair<int, int>, int> directed;
    for (const auto& t : patch.triangles)
      for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    std::set<std::pair<int, int>> boundary;
    for (const auto& [edge, uses] : directed)
      if (uses == 1 && directed.count({edge.second, edge.first}) == 0) boundary.insert(edge);
    // Each step of a hole b -> a runs against a boundary edge a -> b, and no boundary edge twice. The
    // step from a loop's last vertex back to its first is apart: where the boundary does not close (a
    // non-manifold opening of a shared character) the walk stops and that step is the cap's, not an
    // edge.
    std::set<std::pair<int, int>> covered;
    std::vector<std::pair<int, int>> closing;
    bool every_step_on_boundary = true, none_twice = true;
    for (const std::vector<int>& hole : patch.holes) {
      CHECK(hole.size() >= 3);
      for (size_t k = 0; k + 1 < hole.size(); ++k) {
        const std::pair<int, int> edge{hole[k + 1], hole[k]};
        every_step_on_boundary = every_step_on_boundary && boundary.count(edge) == 1;
        none_twice = none_twice && covered.insert(edge).second;
      }
      closing.emplace_back(hole.front(), hole.back());
    }
    CHECK(every_step_on_boundary);
    CHECK(none_twice);
    // A cut of the sample's closed, manifold parts is closed by every boundary edge, once.
    if (path == test::sampleGlbPath()) {
      for (const auto& edge : closing) {
        CHECK(boundary.count(edge) == 1);
        CHECK(covered.insert(edge).second);
      }
      CHECK(covered.size() == boundary.size());
      if (cut.size() < surface.whole.triangles.size()) CHECK(!patch.holes.empty());
    }
  });
}

}  // namespace
}  // namespace rigbake

namespace rigbake {
namespace {

// A curved sheet of n x n squares (two triangles each) over x, y in [0, n], its vertices numbered by
// `number` (a permutation of the row-major order): the openings and the caps must not depend on it.
MeshPart curvedSheet(int n, const std::vector<int>& number) {
  MeshPart sheet;
  sheet.positions.resize(static_cast<size_t>((n + 1) * (n + 1)));
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      sheet.positions[static_cast<size_t>(number[static_cast<size_t>(y * (n + 1) + x)])] =
          Eigen::Vector3d(x, y, 0.3 * std::sin(0.7 * x) * std::cos(0.5 * y) + 0.05 * x * y);
  auto at = [&](int x, int y) { return number[static_cast<size_t>(y * (n + 1) + x)]; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      sheet.triangles.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      sheet.triangles.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  return sheet;
}

}  // namespace

// Two square openings that touch at a corner (the sheet pinched there): each is its own loop of 4 in
// any numbering, and the two squares closed on their own cancel the sheet's caps, as two meshes on
// either side of a border must (docs/deformation-quality.md, "Holes are capped"). With the smallest-
// numbered step the openings were one loop of 8 in several of these numberings, and the sums missed by
// the two caps' difference (0.492 against 0.462).
TEST_CASE("skin volume: openings that touch at a vertex are closed one by one, in any vertex order") {
  const int n = 6;
  const int count = (n + 1) * (n + 1);
  // Row-major, reversed, and v -> (m v + 5) mod 49 for multipliers prime to 49.
  std::vector<std::vector<int>> numberings;
  for (int m : {1, -1, 2, 3, 5, 8, 11, 13, 17, 19, 23, 30}) {
    std::vector<int> number(static_cast<size_t>(count));
    for (int v = 0; v < count; ++v) number[static_cast<size_t>(v)] = m < 0 ? count - 1 - v : m == 1 ? v : (v * m + 5) % count;
    numberings.push_back(number);
  }
  for (const std::vector<int>& number : numberings) {
    const MeshPart sheet = curvedSheet(n, number);
    const VolumeSurface surface = buildVolumeSurface(sheet, 1e-9);
    // The squares (2, 2) and (3, 3): triangles 2 (n y + x) and 2 (n y + x) + 1; they share the vertex (3, 3).
    const std::vector<int> first_square = {2 * (n * 2 + 2), 2 * (n * 2 + 2) + 1}, second_square = {2 * (n * 3 + 3), 2 * (n * 3 + 3) + 1};
    std::vector<int> rest;
    for (int t = 0; t < 2 * n * n; ++t)
      if (t / 2 != first_square[0] / 2 && t / 2 != second_square[0] / 2) rest.push_back(t);
    const ClosedPatch sheet_with_openings = closePatch(surface, rest);
    std::multiset<size_t> loops;
    for (const std::vector<int>& hole : sheet_with_openings.holes) loops.insert(hole.size());
    CHECK(loops == std::multiset<size_t>{4, 4, static_cast<size_t>(4 * n)});
    std::vector<int> all(static_cast<size_t>(2 * n * n));
    std::iota(all.begin(), all.end(), 0);
    const Eigen::Vector3d origin(-2.0, 1.5, -3.0);
    const double whole = enclosedVolumeAbout(closePatch(surface, all), surface.bind, origin);
    const double parts = enclosedVolumeAbout(sheet_with_openings, surface.bind, origin) +
                         enclosedVolumeAbout(closePatch(surface, first_square), surface.bind, origin) +
                         enclosedVolumeAbout(closePatch(surface, second_square), surface.bind, origin);
    CHECK(parts == Approx(whole).epsilon(1e-12));
  }
}

}  // namespace rigbake
