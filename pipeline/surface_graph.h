// The mesh surface as a plain graph for smoothing weights: split vertices (UV seams, hard normals) are
// welded by position, and each welded vertex knows its one-ring neighbours: the welded vertices it
// shares a triangle edge with.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "anatomy/character.h"

namespace rigbake {

struct SurfaceGraph {
  std::vector<int> weld_of_vertex;  // part vertex -> welded vertex
  // Welded vertex w's one-ring, ascending: neighbours[first_neighbour[w] .. first_neighbour[w + 1]).
  std::vector<std::uint32_t> first_neighbour;
  std::vector<int> neighbours;
  int weldedCount() const { return first_neighbour.empty() ? 0 : static_cast<int>(first_neighbour.size()) - 1; }
};

// Vertices closer than `weld_tolerance` (scene units, per axis after rounding to that grid) are one,
// numbered in the order of their first vertex. Triangles that welding makes degenerate add no edge.
SurfaceGraph buildSurfaceGraph(const MeshPart& part, double weld_tolerance);

// Each of `vertex_count` vertices' one-ring over `triangles` (indices into those vertices), ascending:
// the vertices it shares a triangle with. The roughness figure's umbrella Laplacian and the response
// fit's smoothness term take their means over these.
std::vector<std::vector<int>> oneRings(const std::vector<std::array<int, 3>>& triangles, size_t vertex_count);

}  // namespace rigbake
