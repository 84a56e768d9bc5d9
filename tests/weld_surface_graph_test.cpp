// The weld (pipeline/weld.h) and the surface graph built on it (pipeline/surface_graph.h) as modules:
// cells by rounding, both of the weld's paths (the hash table and the sort) against a brute-force
// reference, and the graph's one-rings on a hand-made seam and on CesiumMan's real meshes.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "formats/gltf_document.h"
#include "pipeline/surface_graph.h"
#include "pipeline/weld.h"
#include "test_support.h"

using namespace rigbake;

namespace {

// For every vertex the lowest vertex whose coordinates round to the same cell: O(n²), no hashing, no
// sorting, the definition itself.
std::vector<int> weldByDefinition(const std::vector<Eigen::Vector3d>& positions, double tolerance) {
  std::vector<int> first(positions.size());
  auto cell = [&](size_t v, int k) { return std::llround(positions[v][k] / tolerance); };
  for (size_t v = 0; v < positions.size(); ++v) {
    first[v] = static_cast<int>(v);
    for (size_t u = 0; u < v; ++u) {
      if (cell(u, 0) == cell(v, 0) && cell(u, 1) == cell(v, 1) && cell(u, 2) == cell(v, 2)) {
        first[v] = static_cast<int>(u);
        break;
      }
    }
  }
  return first;
}

// Random positions on a coarse lattice (so that many share a cell) spread over `extent`.
std::vector<Eigen::Vector3d> latticePoints(size_t count, double extent, double spacing, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> step(0, static_cast<int>(extent / spacing));
  std::uniform_real_distribution<double> jitter(-0.2 * spacing, 0.2 * spacing);
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < count; ++i)
    points.emplace_back(step(random) * spacing + jitter(random), step(random) * spacing + jitter(random),
                        step(random) * spacing + jitter(random));
  return points;
}

// Every welded vertex's one-ring is ascending, without itself, and symmetric.
void checkOneRings(const SurfaceGraph& graph) {
  std::set<std::pair<int, int>> edges;
  for (int w = 0; w < graph.weldedCount(); ++w) {
    for (std::uint32_t i = graph.first_neighbour[w]; i < graph.first_neighbour[w + 1]; ++i) {
      const int n = graph.neighbours[i];
      REQUIRE(n != w);
      REQUIRE(n >= 0);
      REQUIRE(n < graph.weldedCount());
      if (i > graph.first_neighbour[w]) REQUIRE(graph.neighbours[i - 1] < n);
      edges.emplace(w, n);
    }
  }
  for (const auto& [a, b] : edges) REQUIRE(edges.count({b, a}) == 1);
}

}  // namespace

TEST_CASE("weld: vertices whose coordinates round to one cell join its lowest vertex, and no others", "[weld]") {
  const double tolerance = 1e-3;
  const std::vector<Eigen::Vector3d> positions = {
      {0.0, 0.0, 0.0},         // 0
      {0.0004, 0.0, 0.0},      // 1: rounds to cell 0 on x: joins 0
      {1.0, 2.0, 3.0},         // 2
      {0.0006, 0.0, 0.0},      // 3: rounds to cell 1 on x, though 0.2 mm from vertex 1: its own
      {1.0, 2.0, 3.0},         // 4: a split copy of 2 (a UV seam)
      {0.0, 0.0, -0.0004},     // 5: -0 rounds to 0: joins 0
      {0.00055, 0.0, 0.0},     // 6: joins 3, not the lower 0
  };
  const std::vector<int> first = firstVertexOfCell(positions, tolerance);
  CHECK(first == std::vector<int>{0, 0, 2, 3, 2, 0, 3});
  CHECK(firstVertexOfCell({}, tolerance).empty());
}

TEST_CASE("weld: the hash table and the sorted path both give the definition's cells", "[weld]") {
  // 2 m at 1 mm is about 2000 cells per axis: the packed key, hashed. At 1e-7 m it is 2e7 cells, past
  // the key's 2^21 per axis: the sorted path.
  for (double tolerance : {1e-3, 1e-7}) {
    INFO("tolerance " << tolerance);
    // Each lattice point is a cell of its own at either tolerance only if exactly repeated, so repeat
    // some points exactly, as a mesh's split vertices are.
    std::vector<Eigen::Vector3d> points = latticePoints(1500, 2.0, 0.05, 7);
    std::mt19937 random(11);
    for (int i = 0; i < 500; ++i) points.push_back(points[std::uniform_int_distribution<size_t>(0, points.size() - 1)(random)]);
    const std::vector<int> first = firstVertexOfCell(points, tolerance);
    CHECK(first == weldByDefinition(points, tolerance));
    CHECK(std::set<int>(first.begin(), first.end()).size() < points.size());  // the repeats did weld
  }
}

TEST_CASE("surface graph: a quad split along a seam welds to four vertices with symmetric one-rings", "[surface-graph]") {
  // Two triangles sharing the diagonal 0-2, the second one's corners split copies (4 = 0, 5 = 2), as a
  // UV seam stores them; vertex 6 is a copy of 1 in a triangle that welding makes degenerate.
  MeshPart part;
  part.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}, {1, 1, 0}, {1, 0, 0}};
  part.triangles = {{0, 1, 2}, {4, 5, 3}, {1, 6, 2}};
  const SurfaceGraph graph = buildSurfaceGraph(part, 1e-6);
  REQUIRE(graph.weldedCount() == 4);
  CHECK(graph.weld_of_vertex == std::vector<int>{0, 1, 2, 3, 0, 2, 1});
  auto ring = [&](int w) {
    return std::vector<int>(graph.neighbours.begin() + graph.first_neighbour[w], graph.neighbours.begin() + graph.first_neighbour[w + 1]);
  };
  CHECK(ring(0) == std::vector<int>{1, 2, 3});
  CHECK(ring(1) == std::vector<int>{0, 2});  // the degenerate triangle adds no 1-1 edge
  CHECK(ring(2) == std::vector<int>{0, 1, 3});
  CHECK(ring(3) == std::vector<int>{0, 2});
  checkOneRings(graph);
}

TEST_CASE("surface graph: CesiumMan's meshes weld as the definition does and every one-ring is symmetric", "[surface-graph]") {
  const std::string path = test::requireAsset("CesiumMan.glb");
  if (path.empty()) return;
  const Character character = loadCharacter(path).character;
  REQUIRE(!character.meshes.empty());
  int split_vertices = 0;
  for (const MeshPart& part : character.meshes) {
    INFO(part.name);
    const double tolerance = 1e-6;
    const SurfaceGraph graph = buildSurfaceGraph(part, tolerance);
    const std::vector<int> first = weldByDefinition(part.positions, tolerance);
    // Welded vertices are numbered in the order of their first vertex.
    std::vector<int> expected(part.positions.size());
    int next = 0;
    std::vector<int> number_of_first(part.positions.size(), -1);
    for (size_t v = 0; v < part.positions.size(); ++v) {
      if (first[v] == static_cast<int>(v)) number_of_first[v] = next++;
      expected[v] = number_of_first[first[v]];
    }
    CHECK(graph.weld_of_vertex == expected);
    CHECK(graph.weldedCount() == next);
    split_vertices += static_cast<int>(part.positions.size()) - next;
    checkOneRings(graph);
    // Every triangle edge that welding keeps is in both one-rings.
    for (const auto& t : part.triangles) {
      for (int k = 0; k < 3; ++k) {
        const int a = graph.weld_of_vertex[t[k]], b = graph.weld_of_vertex[t[(k + 1) % 3]];
        if (a == b) continue;
        CHECK(std::binary_search(graph.neighbours.begin() + graph.first_neighbour[a],
                                 graph.neighbours.begin() + graph.first_neighbour[a + 1], b));
      }
    }
  }
  CHECK(split_vertices > 0);  // CesiumMan's UV seams split vertices: the weld had work to do
}
