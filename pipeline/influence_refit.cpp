#include "pipeline/influence_refit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "pipeline/parallel.h"

namespace rigbake {
namespace {

// Rounds of single swaps between a vertex's kept and dropped joints (each round takes the best swap).
// Measured on the eight characters of docs/deformation-quality.md at 4 influences: a fourth round
// changes Cyberpunk's bake, a fifth none (8 rounds give the same bytes on all eight), and searching
// every kept set instead gives the same figures to within a clip.
constexpr int kSwapRounds = 4;

// The kept slots' systems live on the stack: at most kRefitMaxKept unknowns and the sum's multiplier.
using KktMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kRefitMaxKept + 1, kRefitMaxKept + 1>;
using KktVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kRefitMaxKept + 1, 1>;

// One vertex's objective over its full joints (in its full row's order): with e = u - w, the squared
// distance summed over the frames between the blend with weights u and with the full weights w is
// e^T G e, G_ab = sum_t (D_a x).(D_b x), D_a = M_a - M_0 (M_0 the row's first joint; sum e = 0 makes the
// reference free, and differences keep the sums well conditioned where every joint carries the vertex
// far from the origin).
//
// Joints that move alike over the frames make G singular: a face bone or a spring bone that no clip
// moves carries the vertex exactly as the head does. The ridge term ridge |u - w|^2 (ridge a 1e-9 share
// of trace G) keeps every system solvable and settles such ties towards the artist's own weights, so
// two joints the frames cannot tell apart keep the difference the file gave them (towards u = 0 it
// would split them evenly, and the skin would follow a spring twice as much when the game moves it).
struct VertexObjective {
  Eigen::MatrixXd gram;
  Eigen::VectorXd w;       // the full row's weights
  Eigen::VectorXd gram_w;  // G w
  double w_gram_w = 0.0;   // w^T G w
  double ridge = 0.0;
  double scale = 0.0;      // trace G: how far the row's joints carry the vertex apart, summed over the frames
};

// The minimum of the objective with u zero outside `kept` (indices into the full row) and sum u = 1:
// min u^T Q u - 2 r^T u + c with Q = G_kept,kept + ridge I, r = (G w + ridge w)_kept. `support` (a bit mask over
// `kept`) restricts u further; negative entries are allowed. Returns +inf when the system is singular.
double equalityMinimum(const VertexObjective& objective, const int* kept, int m, unsigned support, KktVector* u) {
  int index[kRefitMaxKept];
  int q = 0;
  for (int a = 0; a < m; ++a)
    if (support & (1u << a)) index[q++] = a;
  KktMatrix kkt = KktMatrix::Zero(q + 1, q + 1);
  KktVector rhs = KktVector::Zero(q + 1);
  for (int a = 0; a < q; ++a) {
    for (int c = 0; c < q; ++c) kkt(a, c) = objective.gram(kept[index[a]], kept[index[c]]);
    kkt(a, a) += objective.ridge;
    kkt(a, q) = kkt(q, a) = 1.0;
    rhs[a] = objective.gram_w[kept[index[a]]] + objective.ridge * objective.w[kept[index[a]]];
  }
  rhs[q] = 1.0;
  const KktVector solution = kkt.fullPivLu().solve(rhs);
  *u = KktVector::Zero(m);
  for (int a = 0; a < q; ++a) (*u)[index[a]] = solution[a];
  // (u - w)^T G (u - w) + ridge |u - w|^2, over the whole row (a dropped joint's u is 0).
  double cost = objective.w_gram_w + objective.ridge * objective.w.squaredNorm();
  for (int a = 0; a < q; ++a) {
    const double ua = solution[a];
    cost -= 2.0 * ua * rhs[a];
    for (int c = 0; c < q; ++c) cost += ua * kkt(a, c) * solution[c];
  }
  return std::isfinite(cost) ? std::max(cost, 0.0) : std::numeric_limits<double>::infinity();
}

// The convex least squares on the simplex (u >= 0, sum u = 1) over the kept joints, given the equality
// minimum over the whole kept set (`whole`, with weights `whole_u`). When that is non-negative it is the
// answer (the problem is convex); otherwise every smaller support's equality minimum, the best
// non-negative one (exact; at 4 influences at most 14 more systems of at most 4 unknowns). Returns +inf
// when no support gives a finite answer.
double simplexMinimum(const VertexObjective& objective, const int* kept, int m, double whole, const KktVector& whole_u,
                      KktVector* best_u) {
  if (whole < std::numeric_limits<double>::infinity() && (whole_u.array() >= 0.0).all()) {
    *best_u = whole_u;
    return whole;
  }
  const unsigned all = (1u << m) - 1u;
  KktVector u;
  double best = std::numeric_limits<double>::infinity();
  for (unsigned mask = 1; mask < all; ++mask) {
    const double cost = equalityMinimum(objective, kept, m, mask, &u);
    if (!(cost < best) || !(u.array() >= 0.0).all()) continue;  // also rejects NaN
    best = cost;
    *best_u = u;
  }
  return best;
}

// Which m of the full row's joints to keep: from the m largest weights, the best single swap of a kept
// for a dropped joint while it lowers the simplex minimum, at most kSwapRounds times. The equality
// minimum bounds the simplex minimum from below, so a swap whose bound cannot beat the round's best is
// not solved further (the choice is the same as solving every swap). Returns the kept set's cost.
double chooseKept(const VertexObjective& objective, int full_count, int m, int* kept, KktVector* u) {
  const unsigned all = (1u << m) - 1u;
  KktVector whole_u;
  double best = simplexMinimum(objective, kept, m, equalityMinimum(objective, kept, m, all, &whole_u), whole_u, u);
  for (int round = 0; round < kSwapRounds; ++round) {
    int swap_slot = -1, swap_joint = -1;
    double round_best = best;
    KktVector round_u;
    for (int a = 0; a < m; ++a) {
      for (int d = 0; d < full_count; ++d) {
        if (std::find(kept, kept + m, d) != kept + m) continue;
        int trial[kRefitMaxKept];
        std::copy(kept, kept + m, trial);
        trial[a] = d;
        // A swap must gain more than rounding and the ridge can: joints the frames cannot tell apart
        // (an unanimated chain) tie, and the ridge alone moves a cost by at most 2e-9 of the scale.
        const double needed = round_best - 1e-7 * (round_best + objective.scale);
        KktVector whole_trial_u, trial_u;
        const double whole = equalityMinimum(objective, trial, m, all, &whole_trial_u);
        if (!(whole < needed)) continue;
        const double cost = simplexMinimum(objective, trial, m, whole, whole_trial_u, &trial_u);
        if (cost < needed) {
          round_best = cost;
          round_u = trial_u;
          swap_slot = a;
          swap_joint = d;
        }
      }
    }
    if (swap_slot < 0) break;
    kept[swap_slot] = swap_joint;
    best = round_best;
    *u = round_u;
  }
  return best;
}

}  // namespace

void refitKeptWeights(const InfluenceSet& full, const std::vector<Eigen::Vector3d>& bind, const std::vector<SkinFrame>& frames,
                      InfluenceSet* kept, int threads) {
  if (frames.empty()) return;
  const int n = kept->slots_per_vertex, slots = full.slots_per_vertex;
  const size_t stride = (frames.size() + kRefitFrames - 1) / kRefitFrames;
  parallelFor(threads, static_cast<size_t>(full.vertexCount()), 256, [&](size_t, size_t begin, size_t end) {
    std::vector<int> full_joints;
    std::vector<double> full_weights;
    std::vector<Eigen::Vector3d> moved;
    std::vector<std::pair<int, double>> row;
    VertexObjective objective;
    for (size_t v = begin; v < end; ++v) {
      full_joints.clear();
      full_weights.clear();
      for (int k = 0; k < slots; ++k)
        if (full.weights[v * slots + k] > 0.0) {
          full_joints.push_back(full.joints[v * slots + k]);
          full_weights.push_back(full.weights[v * slots + k]);
        }
      const int full_count = static_cast<int>(full_joints.size());
      int kept_slots[kRefitMaxKept];
      int m = 0;
      for (int k = 0; k < n && m < kRefitMaxKept; ++k)
        if (kept->weights[v * n + k] > 0.0) {
          const auto at = std::find(full_joints.begin(), full_joints.end(), kept->joints[v * n + k]);
          if (at == full_joints.end()) break;  // not pruned from `full`: leave the row alone
          kept_slots[m++] = static_cast<int>(at - full_joints.begin());
        }
      int positive = 0;
      for (int k = 0; k < n; ++k) positive += kept->weights[v * n + k] > 0.0;
      // Nothing dropped, one joint (its weight is 1), or more kept slots than the fit takes.
      if (full_count <= m || m < 2 || m != positive) continue;
      objective.w = Eigen::Map<const Eigen::VectorXd>(full_weights.data(), full_count);
      const Eigen::VectorXd& w = objective.w;
      objective.gram = Eigen::MatrixXd::Zero(full_count, full_count);
      const Eigen::Vector3d& x = bind[v];
      moved.resize(static_cast<size_t>(full_count));
      for (size_t t = 0; t < frames.size(); t += stride) {
        const SkinFrame& frame = frames[t];
        const Eigen::Vector3d reference = frame[static_cast<size_t>(full_joints[0])] * x;
        for (int a = 1; a < full_count; ++a) moved[a] = frame[static_cast<size_t>(full_joints[a])] * x - reference;
        for (int a = 1; a < full_count; ++a)
          for (int c = a; c < full_count; ++c) objective.gram(a, c) += moved[a].dot(moved[c]);
      }
      objective.gram.triangularView<Eigen::StrictlyLower>() = objective.gram.transpose();
      objective.gram_w = objective.gram * w;
      objective.w_gram_w = w.dot(objective.gram_w);
      objective.scale = objective.gram.trace();
      if (!(objective.scale > 0.0)) continue;  // every joint carries the vertex alike: nothing to choose by
      objective.ridge = 1e-9 * objective.scale;
      KktVector u;
      if (!(chooseKept(objective, full_count, m, kept_slots, &u) < std::numeric_limits<double>::infinity()))
        continue;  // no support gave a finite answer: keep the rescaled weights
      row.clear();
      for (int a = 0; a < m; ++a)
        if (u[a] > 0.0) row.emplace_back(full_joints[static_cast<size_t>(kept_slots[a])], u[a]);
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
