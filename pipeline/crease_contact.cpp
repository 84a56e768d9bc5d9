#include "pipeline/crease_contact.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace rigbake {
namespace {

constexpr double kCreaseFacing = -0.3;

// A uniform grid over one side's posed positions, for the nearest opposing vertex within a reach.
class CreasePointGrid {
 public:
  CreasePointGrid(const std::vector<Eigen::Vector3d>& points, double cell) : points_(points), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i) cells_[key(cellOf(points[i]))].push_back(static_cast<int>(i));
  }
  // Calls visit(i) for every point within the cells that `reach` around `p` covers.
  template <typename Visit>
  void near(const Eigen::Vector3d& p, double reach, Visit visit) const {
    const Eigen::Vector3i low = cellOf(p - Eigen::Vector3d::Constant(reach)), high = cellOf(p + Eigen::Vector3d::Constant(reach));
    for (int x = low.x(); x <= high.x(); ++x)
      for (int y = low.y(); y <= high.y(); ++y)
        for (int z = low.z(); z <= high.z(); ++z) {
          const auto it = cells_.find(key({x, y, z}));
          if (it == cells_.end()) continue;
          for (int i : it->second) visit(i);
        }
  }

 private:
  Eigen::Vector3i cellOf(const Eigen::Vector3d& p) const {
    return {static_cast<int>(std::floor(p.x() / cell_)), static_cast<int>(std::floor(p.y() / cell_)),
            static_cast<int>(std::floor(p.z() / cell_))};
  }
  static long long key(const Eigen::Vector3i& c) {
    return (static_cast<long long>(c.x() & 0x1fffff) << 42) | (static_cast<long long>(c.y() & 0x1fffff) << 21) |
           static_cast<long long>(c.z() & 0x1fffff);
  }
  const std::vector<Eigen::Vector3d>& points_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

// Each vertex of `from` against its nearest opposing vertex of `to`, folded into `out`.
void creaseOneWay(const CreaseSide& from, const CreaseSide& to, const CreasePointGrid& grid, double reach, double min_bind_apart,
            CreaseMethodContact* out, double* closest) {
  const double apart_squared = min_bind_apart * min_bind_apart;
  for (size_t a = 0; a < from.posed.size(); ++a) {
    int nearest = -1;
    double best = reach * reach;
    grid.near(from.posed[a], reach, [&](int b) {
      // First whether b comes before the nearest found so far in (distance, index) order (at the start:
      // within the reach), which most of the cells' points do not. The least (distance, index) wins
      // whatever order the cells are visited in, so a point that passes all three tests is the nearest.
      const double d = (from.posed[a] - to.posed[static_cast<size_t>(b)]).squaredNorm();
      if (d > best || (d == best && b >= nearest)) return;
      if ((from.bind[a] - to.bind[static_cast<size_t>(b)]).squaredNorm() < apart_squared) return;
      if (from.normal[a].dot(to.normal[static_cast<size_t>(b)]) > kCreaseFacing) return;
      best = d;
      nearest = b;
    });
    if (nearest < 0) continue;
    *closest = std::min(*closest, std::sqrt(best));
    const double side = (from.posed[a] - to.posed[static_cast<size_t>(nearest)]).dot(to.normal[static_cast<size_t>(nearest)]);
    if (side < 0.0) {
      ++out->through;
      out->deepest = std::max(out->deepest, -side);
    }
  }
}

}  // namespace

CreaseMethodContact creaseContact(const CreaseSide& proximal, const CreaseSide& distal, double min_bind_apart) {
  CreaseMethodContact out;
  if (proximal.posed.empty() || distal.posed.empty() || !(min_bind_apart > 0.0)) return out;
  // Opposing skin is looked for within the distance that separates it at bind: skin farther apart than
  // that when posed has not come together.
  const double reach = min_bind_apart;
  // Cells as wide as the reach: a query looks in 27 of them, not the 125 of half-width cells (a hash
  // lookup each); the points it visits are a superset of those within reach either way.
  const double cell = reach;
  double closest = std::numeric_limits<double>::infinity();
  creaseOneWay(distal, proximal, CreasePointGrid(proximal.posed, cell), reach, min_bind_apart, &out, &closest);
  creaseOneWay(proximal, distal, CreasePointGrid(distal.posed, cell), reach, min_bind_apart, &out, &closest);
  out.opposed = std::isfinite(closest);
  out.closest = out.opposed ? closest : 0.0;
  return out;
}

double relativeTurn(const Eigen::Affine3d& proximal, const Eigen::Affine3d& distal) {
  auto rigid = [](const Eigen::Matrix3d& m) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
    if (r.determinant() < 0.0) {
      Eigen::Matrix3d u = svd.matrixU();
      u.col(2) = -u.col(2);
      r = u * svd.matrixV().transpose();
    }
    return r;
  };
  const Eigen::Matrix3d relative = rigid(proximal.linear()).transpose() * rigid(distal.linear());
  const double c = std::clamp((relative.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

}  // namespace rigbake
