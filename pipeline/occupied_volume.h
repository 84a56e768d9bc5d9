// The space a posed body occupies, each point once (issue 29: "measures that a fit cannot game"). The
// signed enclosed volume (pipeline/skin_volume.h) integrates the winding number W: where skin passes
// through opposing skin (an elbow's fold, an armpit) the overlap lies inside both sides and counts
// twice, so a rig that pushes skin into the fold keeps "volume" that no longer exists. The occupied
// volume counts every point inside the skin once, ∫ clamp(W, 0, 1) dV: the signed volume less the
// excess ∫ (W − clamp(W, 0, 1)) dV. The excess is found on columns along one axis, each column exact in
// depth (its crossings with every triangle, sorted), the columns `step` apart on a grid anchored at the
// origin: only the fold's lens is sampled, the rest of the volume stays exact. docs/deformation-quality.md.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "pipeline/skin_volume.h"

namespace rigbake {

// One closed surface posed: its triangles and capped holes (as enclosedVolume() closes them) over its
// welded positions.
struct PosedPatch {
  const ClosedPatch* patch = nullptr;
  const std::vector<Eigen::Vector3d>* welded = nullptr;
};

// ∫ (W − clamp(W, 0, 1)) dV over all of `surfaces` together (their windings add), sampled on columns
// along `axis` (0, 1 or 2) at the centres of a `step`-sized grid. Positive where space is wrapped more
// than once, negative where the skin is turned inside out (W < 0). Scene units cubed; the same bits
// for the same input.
double windingExcess(const std::vector<PosedPatch>& surfaces, int axis, double step);

// Per surface and welded vertex, the share of its triangles' column crossings that bound the occupied
// space (winding 0 on the side the triangle faces): 0 for skin inside other skin (a fold's), 1 for skin
// with nothing over it; 1 where no column crosses its triangles. What the response fit's body row
// counts with `--fit-volume occupied` (pipeline/response_fit.h).
std::vector<std::vector<float>> exposedShare(const std::vector<PosedPatch>& surfaces, int axis, double step);

// Signed enclosed volume of all of `surfaces`, less their winding excess.
double occupiedVolume(const std::vector<PosedPatch>& surfaces, int axis, double step);

// Columns along the axis a body's bounding box [low, high] is thinnest in (the most columns cross it),
// `columns` of them across its largest extent; step 0 for an empty or degenerate box.
struct OccupancyGrid {
  int axis = 2;
  double step = 0.0;
};
OccupancyGrid occupancyGrid(const Eigen::Vector3d& low, const Eigen::Vector3d& high, double columns);

}  // namespace rigbake
