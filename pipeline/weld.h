// Welding a mesh part's split vertices (UV seams, hard edges) by position: vertices whose coordinates
// round to the same multiple of the tolerance, per axis, are one. Shared by the surfaces that weights
// are smoothed over (pipeline/surface_graph.h) and those whose volume is measured
// (pipeline/skin_volume.h), so both weld alike.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rigbake {

// For every vertex, the first (lowest-index) vertex of its cell.
std::vector<int> firstVertexOfCell(const std::vector<Eigen::Vector3d>& positions, double tolerance);

}  // namespace rigbake
