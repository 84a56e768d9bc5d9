// Motion-aware rounding. With weights w_i rounded to q_i = w_i + e_i (sum e_i = 0), the skinned vertex
// moves by sum_i e_i M_i(t) v = sum_i e_i (M_i(t) v - M_0(t) v) at frame t.
//
// Every weight is rounded down or up, never further: then |e_i| < 0.001 and the error in any pose, not
// only the sampled ones, stays within the bound largest remainder guarantees (docs/muscle-weights.md),
// which matters because a game blends and poses characters beyond their clips. A vertex has at most 10
// slots and at most 9 units to hand out after rounding down, so there are at most C(10, 5) = 252 such
// roundings, and they are searched in two passes:
//  1. Every vertex takes the rounding whose error summed in squares over the frames is smallest. That
//     sum is e^T G e with the Gram matrix G_ij = sum_t d_i(t) . d_j(t), d_i(t) = (M_i - M_0)(t) v, so a
//     candidate costs O(n^2) once G is built.
//  2. The figure a user sees is the worst single frame of the worst vertex. Every vertex whose pass-1
//     error comes within kRefineShare of its part's worst is rounded again, now by its worst frame,
//     each candidate skinned over the frames (stopping at the first frame worse than the best so far).
// Pass 2 makes the part's worst error the least any down-or-up rounding can give, whenever the refined
// vertices' best stays above kRefineShare of pass 1's worst (so the vertices left alone cannot
// decide it); the tests check that it does on every shared asset.
#include "pipeline/quantize_for_motion.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>

#include "pipeline/pose.h"

namespace rigbake {
namespace {

constexpr double kRefineShare = 0.5;

struct RoundingSlot {
  int joint = 0;
  int units = 0;
};

void writeCanonical(std::vector<RoundingSlot> slots, int slots_per_vertex, int vertex, QuantizedInfluences* out) {
  std::sort(slots.begin(), slots.end(), [](const RoundingSlot& a, const RoundingSlot& b) {
    if ((a.units == 0) != (b.units == 0)) return a.units != 0;
    if (a.units != b.units) return a.units > b.units;
    return a.joint < b.joint;
  });
  for (int k = 0; k < slots_per_vertex; ++k) {
    const size_t at = static_cast<size_t>(vertex) * slots_per_vertex + k;
    out->joints[at] = slots[k].units == 0 ? 0 : slots[k].joint;
    out->weights[at] = static_cast<std::uint16_t>(slots[k].units);
  }
}

// One vertex's influences merged by joint, the exact shares in thousandths, and where each joint
// carries the vertex at every frame.
struct VertexMotion {
  std::vector<int> joints;
  std::vector<double> exact;
  std::vector<int> floor_units;
  int missing = 0;  // thousandths still to hand out after rounding every share down
  std::vector<Eigen::Vector3d> moved;  // frame-major: moved[t * joints.size() + i]
};

VertexMotion vertexMotion(const InfluenceSet& set, int v, const Eigen::Vector3d& position,
                          const std::vector<SkinFrame>& frames) {
  VertexMotion motion;
  const int slots = set.slots_per_vertex;
  double sum = 0.0;
  for (int k = 0; k < slots; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * slots + k];
    if (w <= 0.0) continue;
    const int joint = set.joints[static_cast<size_t>(v) * slots + k];
    auto it = std::find(motion.joints.begin(), motion.joints.end(), joint);
    if (it == motion.joints.end()) {
      motion.joints.push_back(joint);
      motion.exact.push_back(w);
    } else {
      motion.exact[it - motion.joints.begin()] += w;
    }
    sum += w;
  }
  const int n = static_cast<int>(motion.joints.size());
  int handed = 0;
  for (int i = 0; i < n; ++i) {
    motion.exact[i] = motion.exact[i] / sum * kMilliScale;
    motion.floor_units.push_back(static_cast<int>(std::floor(motion.exact[i])));
    handed += motion.floor_units[i];
  }
  motion.missing = kMilliScale - handed;
  if (n <= 1 || motion.missing <= 0 || motion.missing >= n) return motion;  // nothing to choose
  motion.moved.reserve(frames.size() * n);
  for (const SkinFrame& frame : frames)
    for (int joint : motion.joints) motion.moved.push_back(transformPoint(frame[joint], position));
  return motion;
}

bool hasChoice(const VertexMotion& motion) { return !motion.moved.empty(); }

std::vector<int> unitsOf(const VertexMotion& motion, unsigned mask) {
  std::vector<int> units = motion.floor_units;
  for (size_t i = 0; i < units.size(); ++i) units[i] += static_cast<int>((mask >> i) & 1u);
  return units;
}

// Every way of handing out the missing units, one per share that is not already an integer, the
// largest-remainder choice first.
std::vector<unsigned> candidateMasks(const VertexMotion& motion) {
  const int n = static_cast<int>(motion.joints.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return motion.exact[a] - motion.floor_units[a] > motion.exact[b] - motion.floor_units[b];
  });
  unsigned largest_remainder = 0;
  for (int i = 0; i < motion.missing; ++i) largest_remainder |= 1u << order[i];
  std::vector<unsigned> masks{largest_remainder};
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    if (mask == largest_remainder || __builtin_popcount(mask) != motion.missing) continue;
    bool possible = true;  // a share already on an integer cannot round up
    for (int i = 0; i < n && possible; ++i)
      possible = !((mask >> i) & 1u) || motion.exact[i] > motion.floor_units[i];
    if (possible) masks.push_back(mask);
  }
  return masks;
}

// Pass 1: the candidate with the least error summed in squares over the frames (the first wins ties).
unsigned leastSquaresMask(const VertexMotion& motion, const std::vector<unsigned>& masks) {
  const int n = static_cast<int>(motion.joints.size());
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
  for (size_t at = 0; at < motion.moved.size(); at += n) {
    const Eigen::Vector3d* moved = &motion.moved[at];
    for (int i = 1; i < n; ++i) {
      const Eigen::Vector3d di = moved[i] - moved[0];
      for (int j = i; j < n; ++j) gram(i, j) += di.dot(moved[j] - moved[0]);
    }
  }
  for (int i = 1; i < n; ++i)
    for (int j = i + 1; j < n; ++j) gram(j, i) = gram(i, j);
  Eigen::VectorXd error(n);
  auto cost = [&](unsigned mask) {
    for (int i = 0; i < n; ++i) error[i] = motion.floor_units[i] + ((mask >> i) & 1u) - motion.exact[i];
    return error.dot(gram * error);
  };
  unsigned best = masks.front();
  double best_cost = cost(best);
  const double tolerance = 1e-12 * std::max(1.0, best_cost);
  for (unsigned mask : masks) {
    const double c = cost(mask);
    if (c < best_cost - tolerance) {
      best_cost = c;
      best = mask;
    }
  }
  return best;
}

// The largest distance over the frames between skinning with `units` and with the exact shares, in
// the positions' units; stops early, returning a value above `give_up`, once a frame exceeds it.
double worstFrameError(const VertexMotion& motion, const std::vector<int>& units,
                       double give_up = std::numeric_limits<double>::infinity()) {
  double worst = 0.0;
  for (size_t at = 0; at < motion.moved.size(); at += units.size()) {
    const Eigen::Vector3d* moved = &motion.moved[at];
    Eigen::Vector3d error = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < units.size(); ++i) error += (units[i] - motion.exact[i]) * moved[i];
    worst = std::max(worst, error.norm() / kMilliScale);
    if (worst > give_up) break;
  }
  return worst;
}

void writeUnits(const VertexMotion& motion, const std::vector<int>& units, int slots, int v,
                QuantizedInfluences* out) {
  std::vector<RoundingSlot> chosen(slots);
  for (size_t i = 0; i < units.size(); ++i) chosen[i] = RoundingSlot{motion.joints[i], units[i]};
  writeCanonical(chosen, slots, v, out);
}

}  // namespace

QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames) {
  QuantizedInfluences out = quantizeInfluences(set, kMilliScale);
  if (frames.empty()) return out;
  const int slots = set.slots_per_vertex;

  // Pass 1, and each vertex's worst frame under it.
  std::vector<double> worst(set.vertexCount(), 0.0);
  for (int v = 0; v < set.vertexCount(); ++v) {
    const VertexMotion motion = vertexMotion(set, v, bind_positions[v], frames);
    if (!hasChoice(motion)) continue;
    const std::vector<int> units = unitsOf(motion, leastSquaresMask(motion, candidateMasks(motion)));
    worst[v] = worstFrameError(motion, units);
    writeUnits(motion, units, slots, v, &out);
  }

  // Pass 2 on the vertices that could decide the part's worst error.
  const double part_worst = worst.empty() ? 0.0 : *std::max_element(worst.begin(), worst.end());
  for (int v = 0; v < set.vertexCount(); ++v) {
    if (worst[v] <= kRefineShare * part_worst) continue;
    const VertexMotion motion = vertexMotion(set, v, bind_positions[v], frames);
    // Pass 1's rounding is already in `out`; only a strictly better worst frame replaces it.
    std::vector<int> best;
    double best_worst = worst[v];
    for (unsigned mask : candidateMasks(motion)) {
      std::vector<int> units = unitsOf(motion, mask);
      const double w = worstFrameError(motion, units, best_worst);
      if (w < best_worst) {
        best_worst = w;
        best = std::move(units);
      }
    }
    if (!best.empty()) writeUnits(motion, best, slots, v, &out);
  }
  return out;
}

}  // namespace rigbake
