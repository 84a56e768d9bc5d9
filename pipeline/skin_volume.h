// Volume of a skinned surface, the figure that says whether skinning keeps the body's volume
// (docs/deformation-quality.md gives the equations). Split vertices (UV seams, hard edges) are welded
// by position, and every opening of a surface is closed by a fan around its boundary's centroid, so
// that open meshes, multi-part characters and pieces cut out of a body (a region: the upper arm is a
// tube, closed at both ends) all enclose a volume.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <vector>

#include "anatomy/character.h"

namespace rigbake {

// Triangles over welded vertices with the boundary loops that close them.
struct ClosedPatch {
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::vector<int>> holes;  // boundary loops, welded indices, ordered so caps face outwards
};

// A mesh part's triangles over welded vertices.
struct VolumeSurface {
  std::vector<int> weld_of_vertex;    // part vertex -> welded vertex
  std::vector<int> vertex_of_weld;    // welded vertex -> its first part vertex
  std::vector<int> part_triangle;     // welded triangle -> index in MeshPart::triangles
  ClosedPatch whole;                  // every non-degenerate triangle, and the part's own holes
  std::vector<Eigen::Vector3d> bind;  // welded vertex -> its first part vertex's bind position
  int weldedCount() const { return static_cast<int>(vertex_of_weld.size()); }
};

// Welds vertices closer than `weld_tolerance` (scene units, on a grid of that size, as
// pipeline/surface_graph.h does); drops triangles that welding makes degenerate.
VolumeSurface buildVolumeSurface(const MeshPart& part, double weld_tolerance);

// The weld tolerance of a body `body_height` tall (scene units): 1e-6 of its height, taken as at least
// 1 mm. Every skin figure, the fit's surfaces and the muscle weights weld at it, so they join the same
// vertices in any unit.
inline double bodyWeldTolerance(double body_height) { return 1e-6 * std::max(body_height, 1e-3); }

// The given welded triangles (indices into surface.whole.triangles) and their boundary loops: edges
// used by one of them only. Edges shared by three or more triangles are left as they are. Where
// openings touch at a vertex, each step into it goes on by the step out of it across the same opening,
// found by turning about the vertex at the bind pose (docs/deformation-quality.md, "Holes are capped"):
// the loops do not depend on the numbering, and two meshes that share a border close it with the same
// loops.
ClosedPatch closePatch(const VolumeSurface& surface, const std::vector<int>& triangles);

// The vertices (indices below `count`) a patch's triangles and holes use, each once, ascending.
std::vector<int> patchVertices(const ClosedPatch& patch, size_t count);

// Posed positions of the welded vertices, from the part's per-vertex positions.
std::vector<Eigen::Vector3d> weldedPositions(const VolumeSurface& surface, const std::vector<Eigen::Vector3d>& positions);

// Signed enclosed volume: sum over triangles and cap triangles of a . (b x c) / 6 (about the patch's
// first vertex), each hole capped by the fan from its boundary's mean position. Positive for
// counter-clockwise (outward-facing) triangles.
double enclosedVolume(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded);

// The same sum about a given point. Split a closed patch's triangles and holes into pieces and the
// pieces' sums about one point add up to the whole's volume: the response fit keeps the sum of the
// pieces its unknowns cannot move and re-sums only the rest.
double enclosedVolumeAbout(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded, const Eigen::Vector3d& origin);

// enclosedVolume() of one patch under three posings of its vertices, in one pass over its triangles:
// each the same sum, to the bit.
std::array<double, 3> enclosedVolumes(const ClosedPatch& patch, const std::array<const std::vector<Eigen::Vector3d>*, 3>& welded);

// dV/dp for every welded vertex: the gradient of enclosedVolume(), for fitting. A cap's centre moves
// with its loop, so each loop vertex gets its share of the centre's gradient.
void addVolumeGradient(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded, double factor,
                       std::vector<Eigen::Vector3d>* gradient);

// Its terms for a piece of a patch about a given point: addVolumeGradient() is this about the first
// vertex. Each vertex's gradient adds its triangles' terms in triangle order, then its holes', so a
// piece that keeps every triangle and hole around some vertices, in order, gives those vertices the
// whole patch's gradient to the bit.
void addVolumeGradientAbout(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded,
                            const Eigen::Vector3d& origin, double factor, std::vector<Eigen::Vector3d>* gradient);

// Surface area of the patch, caps included.
double patchArea(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded);

// A region is measured only when, at the bind pose, its closed piece encloses a positive volume that is
// not negligible for its area: the isoperimetric quotient 36 pi V^2 / A^3 (1 for a ball, 0.6 for a
// limb segment three radii long) at least this. A thin flap of skin (a shoulder strap cut between two
// shells) has a volume that sign and rounding dominate, and its percentages mean nothing.
constexpr double kMinRegionCompactness = 0.02;

// The measured parts' welded surfaces, each body region cut out of them and closed, and the bind
// volumes; shared by the deformation-quality figures and the response fit so they measure the same.
struct MeasuredSurfaces {
  std::vector<VolumeSurface> surfaces;          // per measured part
  std::vector<std::vector<ClosedPatch>> regions;  // [part][region]
  double body_volume = 0.0;
  std::vector<double> region_volumes;            // bind, summed over parts
  std::vector<char> region_measured;             // passes kMinRegionCompactness
};
// The regions are closed on up to `threads` threads (pipeline/parallel.h); the result does not depend on it.
MeasuredSurfaces measuredSurfaces(const Character& character, const std::vector<int>& mesh_parts,
                                  const std::vector<std::vector<std::vector<int>>>& region_triangles, double weld_tolerance,
                                  int threads = 1);

// Area-weighted vertex normals of the welded triangles (unit; zero for a vertex on no triangle).
std::vector<Eigen::Vector3d> vertexNormals(const ClosedPatch& patch, const std::vector<Eigen::Vector3d>& welded);

}  // namespace rigbake
