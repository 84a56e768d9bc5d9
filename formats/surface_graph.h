// The mesh surface as a plain graph for smoothing weights: split vertices (UV seams, hard normals) are
// welded by position, and each welded vertex knows its one-ring neighbours. Built with OpenMesh's
// half-edge mesh, which stays inside formats/.
#pragma once

#include <vector>

#include "anatomy/character.h"

namespace rigbake {

struct SurfaceGraph {
  std::vector<int> weld_of_vertex;           // part vertex -> welded vertex
  std::vector<std::vector<int>> neighbours;  // welded vertex -> one-ring, ascending
  int weldedCount() const { return static_cast<int>(neighbours.size()); }
};

// Vertices closer than `weld_tolerance` (scene units, per axis after rounding to that grid) are one.
SurfaceGraph buildSurfaceGraph(const MeshPart& part, double weld_tolerance);

}  // namespace rigbake
