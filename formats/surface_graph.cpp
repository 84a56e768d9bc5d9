// One-rings from OpenMesh (OpenMesh::TriMesh_ArrayKernelT, vertex-vertex circulators). Faces that would
// make the mesh non-manifold are refused by OpenMesh's add_face; their edges are added to the graph
// directly so that no vertex loses a neighbour it has on the surface.
#include "formats/surface_graph.h"

// OpenMesh 9's property containers trip GCC 12's -Wmaybe-uninitialized inside libstdc++ (a false
// positive in third-party templates); it is silenced for this translation unit only.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace rigbake {
namespace {
using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;

void addEdge(std::vector<std::vector<int>>* neighbours, int a, int b) {
  if (a == b) return;
  (*neighbours)[a].push_back(b);
  (*neighbours)[b].push_back(a);
}
}  // namespace

SurfaceGraph buildSurfaceGraph(const MeshPart& part, double weld_tolerance) {
  SurfaceGraph graph;
  const int vertex_count = static_cast<int>(part.positions.size());
  graph.weld_of_vertex.assign(vertex_count, -1);
  std::map<std::tuple<long long, long long, long long>, int> weld_by_cell;
  std::vector<Eigen::Vector3d> welded_positions;
  for (int v = 0; v < vertex_count; ++v) {
    const Eigen::Vector3d& p = part.positions[v];
    auto cell = std::make_tuple(std::llround(p.x() / weld_tolerance), std::llround(p.y() / weld_tolerance),
                                std::llround(p.z() / weld_tolerance));
    auto [it, inserted] = weld_by_cell.emplace(cell, static_cast<int>(welded_positions.size()));
    if (inserted) welded_positions.push_back(p);
    graph.weld_of_vertex[v] = it->second;
  }
  const int welded_count = static_cast<int>(welded_positions.size());
  graph.neighbours.assign(welded_count, {});

  Mesh mesh;
  std::vector<Mesh::VertexHandle> handles(welded_count);
  for (int w = 0; w < welded_count; ++w) {
    const Eigen::Vector3d& p = welded_positions[w];
    handles[w] = mesh.add_vertex(Mesh::Point(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  }
  // add_face reports each refused face on OpenMesh's error stream; refusals are expected here (welding
  // makes seams and separate shells non-manifold) and handled below, so the stream stays quiet.
  omerr().disable();
  for (const auto& triangle : part.triangles) {
    int a = graph.weld_of_vertex[triangle[0]], b = graph.weld_of_vertex[triangle[1]], c = graph.weld_of_vertex[triangle[2]];
    if (a == b || b == c || a == c) continue;
    Mesh::FaceHandle face = mesh.add_face(handles[a], handles[b], handles[c]);
    if (!face.is_valid()) {
      addEdge(&graph.neighbours, a, b);
      addEdge(&graph.neighbours, b, c);
      addEdge(&graph.neighbours, c, a);
    }
  }
  omerr().enable();
  for (int w = 0; w < welded_count; ++w) {
    for (auto ring = mesh.vv_iter(handles[w]); ring.is_valid(); ++ring) graph.neighbours[w].push_back(ring->idx());
  }
  for (auto& ring : graph.neighbours) {
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  }
  return graph;
}

}  // namespace rigbake
