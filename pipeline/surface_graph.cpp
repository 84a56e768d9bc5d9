// One-rings from the triangles' edges: every edge of every triangle that welding leaves
// non-degenerate, both ways, sorted and made unique. These are exactly the one-rings OpenMesh's
// half-edge mesh gave (vertex-vertex circulators, with the edges of the faces it refused as
// non-manifold added by hand), checked on the mannequin at 12k, 100k and 1M vertices and on every
// shared character, without building the half-edge mesh (about 0.7 G instructions and one allocation
// per vertex at 100k vertices).
#include "pipeline/surface_graph.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace rigbake {

SurfaceGraph buildSurfaceGraph(const MeshPart& part, double weld_tolerance) {
  SurfaceGraph graph;
  const int vertex_count = static_cast<int>(part.positions.size());
  graph.weld_of_vertex.assign(static_cast<size_t>(vertex_count), -1);
  // Vertices in the same cell weld, numbered in the order of their first vertex (sorted cells rather
  // than a map of them: the same numbering, without an allocation per vertex).
  struct Cell {
    long long x, y, z;
    int vertex;
    bool operator<(const Cell& o) const { return std::tie(x, y, z, vertex) < std::tie(o.x, o.y, o.z, o.vertex); }
    bool sameCell(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  std::vector<Cell> cells(static_cast<size_t>(vertex_count));
  for (int v = 0; v < vertex_count; ++v) {
    const Eigen::Vector3d& p = part.positions[v];
    cells[v] = {std::llround(p.x() / weld_tolerance), std::llround(p.y() / weld_tolerance), std::llround(p.z() / weld_tolerance), v};
  }
  std::sort(cells.begin(), cells.end());
  std::vector<int> first_of_vertex(static_cast<size_t>(vertex_count));
  for (size_t i = 0, group = 0; i < cells.size(); ++i) {
    if (i > 0 && !cells[i].sameCell(cells[i - 1])) group = i;
    first_of_vertex[cells[i].vertex] = cells[group].vertex;
  }
  std::vector<Cell>().swap(cells);
  int welded_count = 0;
  for (int v = 0; v < vertex_count; ++v)
    graph.weld_of_vertex[v] = first_of_vertex[v] == v ? welded_count++ : graph.weld_of_vertex[first_of_vertex[v]];

  std::vector<std::pair<int, int>> edges;
  edges.reserve(6 * part.triangles.size());
  for (const auto& triangle : part.triangles) {
    const int w[3] = {graph.weld_of_vertex[triangle[0]], graph.weld_of_vertex[triangle[1]], graph.weld_of_vertex[triangle[2]]};
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
    for (int k = 0; k < 3; ++k) {
      edges.emplace_back(w[k], w[(k + 1) % 3]);
      edges.emplace_back(w[(k + 1) % 3], w[k]);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  graph.first_neighbour.assign(static_cast<size_t>(welded_count) + 1, 0);
  graph.neighbours.reserve(edges.size());
  for (const auto& [from, to] : edges) {
    ++graph.first_neighbour[static_cast<size_t>(from) + 1];
    graph.neighbours.push_back(to);
  }
  for (int w = 0; w < welded_count; ++w) graph.first_neighbour[w + 1] += graph.first_neighbour[w];
  return graph;
}

}  // namespace rigbake
