// One-rings from the triangles' edges: every edge of every triangle that welding leaves
// non-degenerate, both ways, sorted and made unique. These are exactly the one-rings OpenMesh's
// half-edge mesh gave (vertex-vertex circulators, with the edges of the faces it refused as
// non-manifold added by hand), checked on the mannequin at 12k, 100k and 1M vertices and on every
// shared character, without building the half-edge mesh (about 0.7 G instructions and one allocation
// per vertex at 100k vertices).
#include "pipeline/surface_graph.h"

#include "pipeline/weld.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace rigbake {

SurfaceGraph buildSurfaceGraph(const MeshPart& part, double weld_tolerance) {
  SurfaceGraph graph;
  const int vertex_count = static_cast<int>(part.positions.size());
  graph.weld_of_vertex.assign(static_cast<size_t>(vertex_count), -1);
  // Vertices in the same cell weld, numbered in the order of their first vertex.
  const std::vector<int> first_of_vertex = firstVertexOfCell(part.positions, weld_tolerance);
  int welded_count = 0;
  for (int v = 0; v < vertex_count; ++v)
    graph.weld_of_vertex[v] = first_of_vertex[v] == v ? welded_count++ : graph.weld_of_vertex[first_of_vertex[v]];

  // Each welded vertex's neighbours through the triangles' edges, both ways: counted, filled, then each
  // list sorted and made unique (no sort of all the edges together).
  std::vector<std::uint32_t> first(static_cast<size_t>(welded_count) + 1, 0);
  auto forEachEdge = [&](auto&& visit) {
    for (const auto& triangle : part.triangles) {
      const int w[3] = {graph.weld_of_vertex[triangle[0]], graph.weld_of_vertex[triangle[1]], graph.weld_of_vertex[triangle[2]]};
      if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
      for (int k = 0; k < 3; ++k) {
        visit(w[k], w[(k + 1) % 3]);
        visit(w[(k + 1) % 3], w[k]);
      }
    }
  };
  forEachEdge([&](int from, int) { ++first[static_cast<size_t>(from) + 1]; });
  for (int w = 0; w < welded_count; ++w) first[w + 1] += first[w];
  std::vector<int> all(first.back());
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    forEachEdge([&](int from, int to) { all[fill[from]++] = to; });
  }
  graph.first_neighbour.assign(static_cast<size_t>(welded_count) + 1, 0);
  graph.neighbours.reserve(all.size() / 2);
  for (int w = 0; w < welded_count; ++w) {
    auto begin = all.begin() + first[w], end = all.begin() + first[w + 1];
    std::sort(begin, end);
    graph.neighbours.insert(graph.neighbours.end(), begin, std::unique(begin, end));
    graph.first_neighbour[w + 1] = static_cast<std::uint32_t>(graph.neighbours.size());
  }

  return graph;
}

std::vector<std::vector<int>> oneRings(const std::vector<std::array<int, 3>>& triangles, size_t vertex_count) {
  std::vector<std::vector<int>> rings(vertex_count);
  for (const auto& triangle : triangles) {
    for (int k = 0; k < 3; ++k) {
      rings[static_cast<size_t>(triangle[k])].push_back(triangle[(k + 1) % 3]);
      rings[static_cast<size_t>(triangle[k])].push_back(triangle[(k + 2) % 3]);
    }
  }
  for (std::vector<int>& ring : rings) {
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  }
  return rings;
}

}  // namespace rigbake
