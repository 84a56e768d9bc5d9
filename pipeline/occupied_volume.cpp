#include "pipeline/occupied_volume.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdint>
#include <utility>

namespace rigbake {
namespace {

// Where one column (grid cell (i, j)) passes through one triangle, and which way the winding number
// steps there along the axis: +1 entering (the triangle faces against the axis), −1 leaving.
struct Crossing {
  std::int64_t i, j;
  double depth;
  int delta;
  int surface = -1, triangle = -1;  // -1: a hole's cap
};

struct Point2 {
  double u, v;
};

// Which side of the edge p -> q a point lies on (positive: left), computed from the edge's
// lexicographically first end, so the two triangles that share an edge get exactly opposite values
// and a column on the edge is counted by one of them, never both or neither. Of a counter-clockwise
// triangle, the edge owns the columns exactly on it by the top-left rule (an edge going down, or going
// left along a row).
struct Edge {
  Point2 from, along;
  double sign;
  bool owns;
  Edge(const Point2& p, const Point2& q) {
    const bool swapped = q.u < p.u || (q.u == p.u && q.v < p.v);
    from = swapped ? q : p;
    const Point2& to = swapped ? p : q;
    along = {to.u - from.u, to.v - from.v};
    sign = swapped ? -1.0 : 1.0;
    owns = q.v < p.v || (q.v == p.v && q.u < p.u);
  }
  bool holds(const Point2& x) const {
    const double side = sign * (along.u * (x.v - from.v) - along.v * (x.u - from.u));
    return side > 0.0 || (side == 0.0 && owns);
  }
};

void addTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, int axis, double step,
                 std::vector<Crossing>* out, int surface, int triangle) {
  const int iu = (axis + 1) % 3, iv = (axis + 2) % 3;
  const Point2 pa{a[iu], a[iv]}, pb{b[iu], b[iv]}, pc{c[iu], c[iv]};
  // Most triangles of a fine mesh cover no column centre: the columns first.
  const double u_min = std::min({pa.u, pb.u, pc.u}), u_max = std::max({pa.u, pb.u, pc.u});
  const double v_min = std::min({pa.v, pb.v, pc.v}), v_max = std::max({pa.v, pb.v, pc.v});
  const auto i0 = static_cast<std::int64_t>(std::ceil(u_min / step - 0.5)), i1 = static_cast<std::int64_t>(std::floor(u_max / step - 0.5));
  if (i0 > i1) return;
  const auto j0 = static_cast<std::int64_t>(std::ceil(v_min / step - 0.5)), j1 = static_cast<std::int64_t>(std::floor(v_max / step - 0.5));
  if (j0 > j1) return;
  // The axis component of the triangle's (unnormalized) normal, in the right-handed (u, v, axis) frame.
  const double facing = (pb.u - pa.u) * (pc.v - pa.v) - (pb.v - pa.v) * (pc.u - pa.u);
  if (facing == 0.0 || !std::isfinite(facing)) return;  // seen edge on: no column passes through it
  const int delta = facing < 0.0 ? 1 : -1;
  // Counter-clockwise in (u, v) for the inclusion test.
  const Point2 p0 = pa, p1 = facing > 0.0 ? pb : pc, p2 = facing > 0.0 ? pc : pb;
  const Edge e01(p0, p1), e12(p1, p2), e20(p2, p0);
  for (std::int64_t i = i0; i <= i1; ++i) {
    for (std::int64_t j = j0; j <= j1; ++j) {
      const Point2 x{(static_cast<double>(i) + 0.5) * step, (static_cast<double>(j) + 0.5) * step};
      if (!e01.holds(x) || !e12.holds(x) || !e20.holds(x)) continue;
      // Barycentric coordinates of x in the original corner order: the depth of the plane there.
      const double lb = ((x.u - pa.u) * (pc.v - pa.v) - (x.v - pa.v) * (pc.u - pa.u)) / facing;
      const double lc = ((pb.u - pa.u) * (x.v - pa.v) - (pb.v - pa.v) * (x.u - pa.u)) / facing;
      out->push_back({i, j, a[axis] + lb * (b[axis] - a[axis]) + lc * (c[axis] - a[axis]), delta, surface, triangle});
    }
  }
}

// One crossing within its column: its depth, winding step, and the triangle it crosses (surface -1 for a
// hole's cap).
struct ColumnCrossing {
  double depth;
  int delta, surface, triangle;
  bool operator<(const ColumnCrossing& o) const {
    if (depth != o.depth) return depth < o.depth;
    if (delta != o.delta) return delta < o.delta;
    if (surface != o.surface) return surface < o.surface;
    return triangle < o.triangle;
  }
};

// Every column's crossings with every triangle and hole cap of `surfaces`, grouped by column with a
// counting sort (a global sort of every crossing took most of a bake's figures), columns in (i, j)
// order, each column's crossings sorted by depth (ties in a fixed order: the same bits every run).
// `visit(first, last)` sees each column with two or more crossings. Buffers kept per thread: a bake
// measures hundreds of poses.
template <typename Visit>
void forEachColumn(const std::vector<PosedPatch>& surfaces, int axis, double step, Visit visit) {
  thread_local std::vector<Crossing> crossings;
  thread_local std::vector<size_t> start, next;
  thread_local std::vector<ColumnCrossing> sorted;
  crossings.clear();
  for (size_t s = 0; s < surfaces.size(); ++s) {
    const std::vector<Eigen::Vector3d>& welded = *surfaces[s].welded;
    const std::vector<std::array<int, 3>>& triangles = surfaces[s].patch->triangles;
    for (size_t t = 0; t < triangles.size(); ++t)
      addTriangle(welded[static_cast<size_t>(triangles[t][0])], welded[static_cast<size_t>(triangles[t][1])],
                  welded[static_cast<size_t>(triangles[t][2])], axis, step, &crossings, static_cast<int>(s), static_cast<int>(t));
    // The caps enclosedVolume() closes each hole with: the fan from the loop's mean position.
    for (const std::vector<int>& hole : surfaces[s].patch->holes) {
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int w : hole) centre += welded[static_cast<size_t>(w)];
      centre /= static_cast<double>(hole.size());
      for (size_t k = 0; k < hole.size(); ++k)
        addTriangle(welded[static_cast<size_t>(hole[k])], welded[static_cast<size_t>(hole[(k + 1) % hole.size()])], centre, axis, step,
                    &crossings, -1, -1);
    }
  }
  if (crossings.empty()) return;
  std::int64_t i_low = crossings[0].i, i_high = i_low, j_low = crossings[0].j, j_high = j_low;
  for (const Crossing& c : crossings) {
    i_low = std::min(i_low, c.i);
    i_high = std::max(i_high, c.i);
    j_low = std::min(j_low, c.j);
    j_high = std::max(j_high, c.j);
  }
  const std::int64_t rows = j_high - j_low + 1;
  const size_t columns = static_cast<size_t>((i_high - i_low + 1) * rows);
  auto column = [&](const Crossing& c) { return static_cast<size_t>((c.i - i_low) * rows + (c.j - j_low)); };
  start.assign(columns + 1, 0);
  for (const Crossing& c : crossings) ++start[column(c) + 1];
  for (size_t k = 0; k < columns; ++k) start[k + 1] += start[k];
  sorted.resize(crossings.size());
  next.assign(start.begin(), start.end() - 1);
  for (const Crossing& c : crossings) sorted[next[column(c)]++] = {c.depth, c.delta, c.surface, c.triangle};
  for (size_t k = 0; k < columns; ++k) {
    ColumnCrossing* first = sorted.data() + start[k];
    ColumnCrossing* last = sorted.data() + start[k + 1];
    if (last - first < 2) continue;
    std::sort(first, last);
    visit(first, last);
  }
}

}  // namespace

double windingExcess(const std::vector<PosedPatch>& surfaces, int axis, double step) {
  double excess = 0.0;
  forEachColumn(surfaces, axis, step, [&](const ColumnCrossing* first, const ColumnCrossing* last) {
    int winding = first->delta;
    for (const ColumnCrossing* at = first + 1; at != last; ++at) {
      excess += static_cast<double>(winding - std::clamp(winding, 0, 1)) * (at->depth - (at - 1)->depth);
      winding += at->delta;
    }
  });
  return excess * step * step;
}

std::vector<std::vector<float>> exposedShare(const std::vector<PosedPatch>& surfaces, int axis, double step) {
  std::vector<std::vector<float>> exposed(surfaces.size()), hits(surfaces.size());
  for (size_t s = 0; s < surfaces.size(); ++s) {
    exposed[s].assign(surfaces[s].welded->size(), 0.0f);
    hits[s].assign(surfaces[s].welded->size(), 0.0f);
  }
  forEachColumn(surfaces, axis, step, [&](const ColumnCrossing* first, const ColumnCrossing* last) {
    int winding = 0;
    for (const ColumnCrossing* at = first; at != last; ++at) {
      // The winding on the side the triangle faces: before it when the column enters, after it when it
      // leaves. Zero: the triangle bounds the occupied space.
      const int faced = at->delta > 0 ? winding : winding + at->delta;
      winding += at->delta;
      if (at->surface < 0) continue;
      const size_t s = static_cast<size_t>(at->surface);
      for (int corner : surfaces[s].patch->triangles[static_cast<size_t>(at->triangle)]) {
        exposed[s][static_cast<size_t>(corner)] += faced == 0 ? 1.0f : 0.0f;
        hits[s][static_cast<size_t>(corner)] += 1.0f;
      }
    }
  });
  for (size_t s = 0; s < surfaces.size(); ++s)
    for (size_t w = 0; w < hits[s].size(); ++w) exposed[s][w] = hits[s][w] > 0.0f ? exposed[s][w] / hits[s][w] : 1.0f;
  return exposed;
}

double occupiedVolume(const std::vector<PosedPatch>& surfaces, int axis, double step) {
  double volume = 0.0;
  for (const PosedPatch& surface : surfaces) volume += enclosedVolume(*surface.patch, *surface.welded);
  return volume - windingExcess(surfaces, axis, step);
}

OccupancyGrid occupancyGrid(const Eigen::Vector3d& low, const Eigen::Vector3d& high, double columns) {
  OccupancyGrid grid;
  const Eigen::Vector3d extent = high - low;
  if (!extent.allFinite() || !(extent.maxCoeff() > 0.0)) return grid;
  extent.minCoeff(&grid.axis);
  grid.step = extent.maxCoeff() / columns;
  return grid;
}

}  // namespace rigbake
