#include "pipeline/influence_refit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <utility>

#include "pipeline/parallel.h"

namespace rigbake {
namespace {

// The convex least squares min u^T Q u - 2 r^T u over u >= 0, sum u = 1, for the at most 10 kept slots
// of a vertex: every support set's equality-constrained minimum (the KKT system), the best that is
// non-negative. Exact, and small (at most 2^10 systems of 11 unknowns; at 4 influences 15 of 5).
Eigen::VectorXd simplexLeastSquares(const Eigen::MatrixXd& Q, const Eigen::VectorXd& r) {
  const int m = static_cast<int>(r.size());
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_u;
  for (int mask = 1; mask < (1 << m); ++mask) {
    std::vector<int> support;
    for (int a = 0; a < m; ++a)
      if (mask & (1 << a)) support.push_back(a);
    const int q = static_cast<int>(support.size());
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(q + 1, q + 1);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(q + 1);
    for (int a = 0; a < q; ++a) {
      for (int c = 0; c < q; ++c) kkt(a, c) = Q(support[a], support[c]);
      kkt(a, q) = kkt(q, a) = 1.0;
      rhs[a] = r[support[a]];
    }
    rhs[q] = 1.0;
    const Eigen::VectorXd solution = kkt.fullPivLu().solve(rhs);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(m);
    bool feasible = true;
    for (int a = 0; a < q && feasible; ++a) {
      feasible = solution[a] >= 0.0;  // also false for NaN
      u[support[a]] = solution[a];
    }
    if (!feasible) continue;
    const double cost = u.dot(Q * u) - 2.0 * r.dot(u);
    if (cost < best) {
      best = cost;
      best_u = std::move(u);
    }
  }
  return best_u;
}

}  // namespace

void refitKeptWeights(const InfluenceSet& full, const std::vector<Eigen::Vector3d>& bind, const std::vector<SkinFrame>& frames,
                      InfluenceSet* kept, int threads) {
  if (frames.empty()) return;
  const int n = kept->slots_per_vertex, slots = full.slots_per_vertex;
  const size_t stride = (frames.size() + kRefitFrames - 1) / kRefitFrames;
  parallelFor(threads, static_cast<size_t>(full.vertexCount()), 256, [&](size_t, size_t begin, size_t end) {
    std::vector<Eigen::Vector3d> moved;
    for (size_t v = begin; v < end; ++v) {
      int full_count = 0;
      for (int k = 0; k < slots; ++k) full_count += full.weights[v * slots + k] > 0.0;
      std::vector<int> joints;
      for (int k = 0; k < n; ++k)
        if (kept->weights[v * n + k] > 0.0) joints.push_back(kept->joints[v * n + k]);
      const int m = static_cast<int>(joints.size());
      if (full_count <= m || m < 2) continue;  // nothing dropped, or one joint: its weight is 1
      // The normal equations: Q_ab = sum_t (M_a x).(M_b x), r_a = sum_t (M_a x).(full blend of x).
      Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(m, m);
      Eigen::VectorXd r = Eigen::VectorXd::Zero(m);
      const Eigen::Vector3d& x = bind[v];
      moved.resize(static_cast<size_t>(m));
      for (size_t t = 0; t < frames.size(); t += stride) {
        const SkinFrame& frame = frames[t];
        Eigen::Vector3d target = Eigen::Vector3d::Zero();
        for (int k = 0; k < slots; ++k) {
          const double w = full.weights[v * slots + k];
          if (w > 0.0) target += w * (frame[static_cast<size_t>(full.joints[v * slots + k])] * x);
        }
        for (int a = 0; a < m; ++a) moved[a] = frame[static_cast<size_t>(joints[a])] * x;
        for (int a = 0; a < m; ++a) {
          r[a] += moved[a].dot(target);
          for (int c = 0; c < m; ++c) Q(a, c) += moved[a].dot(moved[c]);
        }
      }
      // Joints that move alike make Q singular; a trace-relative ridge keeps every system solvable
      // without moving a well-posed answer.
      Q.diagonal().array() += 1e-12 * Q.trace();
      const Eigen::VectorXd u = simplexLeastSquares(Q, r);
      if (u.size() == 0) continue;  // no support gave a finite answer: keep the rescaled weights
      std::vector<std::pair<int, double>> row;
      for (int a = 0; a < m; ++a)
        if (u[a] > 0.0) row.emplace_back(joints[a], u[a]);
      std::sort(row.begin(), row.end(), [](const auto& p, const auto& q) {
        return p.second != q.second ? p.second > q.second : p.first < q.first;
      });
      for (int k = 0; k < n; ++k) {
        const bool used = k < static_cast<int>(row.size());
        kept->joints[v * n + k] = used ? row[k].first : 0;
        kept->weights[v * n + k] = used ? row[k].second : 0.0;
      }
    }
  });
}

}  // namespace rigbake
