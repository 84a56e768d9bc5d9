// Motion-aware rounding. With weights w_i rounded to q_i = w_i + e_i (sum e_i = 0), the skinned vertex
// moves by sum_i e_i M_i(t) v = sum_i e_i (M_i(t) v - M_0(t) v) at frame t. Summing its squared length
// over frames gives e^T G e with the Gram matrix G_ij = sum_t d_i(t) . d_j(t), d_i(t) = (M_i - M_0)(t) v,
// so each candidate rounding costs O(n^2) once G is built. A vertex has at most 10 slots and at most
// 9 units to hand out after rounding down, so every candidate (at most C(10, 5) = 252) is tried. (Moving
// further from the exact weights by extra units between joints lowers this sum a little more but
// raised the worst single-frame error on the shared assets, which is the figure that matters.)
#include "pipeline/quantize_for_motion.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "pipeline/pose.h"

namespace rigbake {
namespace {

struct Slot {
  int joint = 0;
  int units = 0;
};

void writeCanonical(std::vector<Slot> slots, int slots_per_vertex, int vertex, QuantizedInfluences* out) {
  std::sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) {
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

}  // namespace

QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames) {
  QuantizedInfluences largest_remainder = quantizeInfluences(set, kMilliScale);
  if (frames.empty()) return largest_remainder;
  const int slots = set.slots_per_vertex;
  QuantizedInfluences out = largest_remainder;
  for (int v = 0; v < set.vertexCount(); ++v) {
    // The vertex's influences, merged by joint, as the exact shares the rounding approximates.
    std::vector<int> joints;
    std::vector<double> exact;
    double sum = 0.0;
    for (int k = 0; k < slots; ++k) {
      const double w = set.weights[static_cast<size_t>(v) * slots + k];
      if (w <= 0.0) continue;
      const int joint = set.joints[static_cast<size_t>(v) * slots + k];
      auto it = std::find(joints.begin(), joints.end(), joint);
      if (it == joints.end()) {
        joints.push_back(joint);
        exact.push_back(w);
      } else {
        exact[it - joints.begin()] += w;
      }
      sum += w;
    }
    const int n = static_cast<int>(joints.size());
    if (n <= 1) continue;
    std::vector<int> floor_units(n);
    int handed = 0;
    for (int i = 0; i < n; ++i) {
      exact[i] = exact[i] / sum * kMilliScale;
      floor_units[i] = static_cast<int>(std::floor(exact[i]));
      handed += floor_units[i];
    }
    const int missing = kMilliScale - handed;
    if (missing <= 0 || missing >= n) continue;

    // Gram matrix of the per-joint displacements relative to the first joint.
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
    std::vector<Eigen::Vector3d> moved(n);
    for (const SkinFrame& frame : frames) {
      for (int i = 0; i < n; ++i) moved[i] = transformPoint(frame[joints[i]], bind_positions[v]);
      for (int i = 1; i < n; ++i) {
        const Eigen::Vector3d di = moved[i] - moved[0];
        for (int j = i; j < n; ++j) gram(i, j) += di.dot(moved[j] - moved[0]);
      }
    }
    for (int i = 1; i < n; ++i)
      for (int j = i + 1; j < n; ++j) gram(j, i) = gram(i, j);

    auto cost = [&](unsigned mask) {
      Eigen::VectorXd error(n);
      for (int i = 0; i < n; ++i) error[i] = floor_units[i] + ((mask >> i) & 1u) - exact[i];
      return error.dot(gram * error);
    };
    // Start from the largest-remainder choice so that ties keep it.
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return exact[a] - floor_units[a] > exact[b] - floor_units[b];
    });
    unsigned best_mask = 0;
    for (int i = 0; i < missing; ++i) best_mask |= 1u << order[i];
    double best_cost = cost(best_mask);
    const double tolerance = 1e-12 * std::max(1.0, best_cost);
    for (unsigned mask = 0; mask < (1u << n); ++mask) {
      if (__builtin_popcount(mask) != missing) continue;
      bool possible = true;  // a slot already on an integer cannot round up
      for (int i = 0; i < n && possible; ++i) possible = !((mask >> i) & 1u) || exact[i] > floor_units[i];
      if (!possible) continue;
      const double c = cost(mask);
      if (c < best_cost - tolerance) {
        best_cost = c;
        best_mask = mask;
      }
    }
    std::vector<Slot> chosen(slots);
    for (int i = 0; i < n; ++i) chosen[i] = Slot{joints[i], floor_units[i] + static_cast<int>((best_mask >> i) & 1u)};
    writeCanonical(chosen, slots, v, &out);
  }
  return out;
}

}  // namespace rigbake
