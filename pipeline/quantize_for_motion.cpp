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
//     error comes within kRefineShare of the character's worst (over all its parts) is rounded again,
//     now by its worst frame, each candidate skinned over the frames (stopping at the first frame worse
//     than the best so far).
// Pass 2 makes the character's worst error the least any down-or-up rounding can give, whenever the
// refined vertices' best stays above kRefineShare of pass 1's worst (so the vertices left alone cannot
// decide it); the tests check that it does on every shared asset.
//
// Speed. Built frame by frame, G costs O(frames n^2) per vertex, the whole bake's largest term. But
// d_i(t) = D_i(t) x with x = (v, 1) and D_i = M_i - M_0 (3x4), so G_ij = x^T C_ij x with the 4x4 moment
// C_ij = sum_t D_i(t)^T D_j(t), which depends only on the joints (M_0, M_i, M_j): it is summed over the
// frames once per joint triple that some vertex uses, and each vertex's G then costs O(n^2), whatever
// the frame count (the moment form of the skinning-decomposition literature, e.g. Le and Deng, "Smooth
// Skinning Decomposition with Rigid Bones", 2012, section 4). The moments round differently from the
// frame-by-frame sums, so a vertex where two candidates come within that difference (a near tie the
// tie tolerance decides) is costed again frame by frame, exactly as before: the roundings are the
// reference ones (quantizeForMotionReference(), which the tests compare against on every shared asset).
// Pass 1's worst frame is only needed where it could reach kRefineShare of the character's worst; the
// error summed in squares bounds it (max_t |r(t)| <= sqrt(sum_t |r(t)|^2)), so the frames are only skinned
// for vertices whose bound gets there.
#include "pipeline/quantize_for_motion.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>

#include <emmintrin.h>

#include "pipeline/parallel.h"
#include "pipeline/pose.h"

namespace rigbake {
namespace {

constexpr double kRefineShare = 0.5;

struct RoundingSlot {
  int joint = 0;
  int units = 0;
};

// `slots` holds slots_per_vertex entries (sorted here). A vertex's joints are distinct, so the order
// sorted into is the only one there is, whatever the sort.
void writeCanonical(RoundingSlot* slots, int slots_per_vertex, int vertex, QuantizedInfluences* out) {
  std::sort(slots, slots + slots_per_vertex, [](const RoundingSlot& a, const RoundingSlot& b) {
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

// The distance at frame `at` between skinning with `units` and with the exact shares, in thousandths.
double frameError(const VertexMotion& motion, const std::vector<int>& units, size_t at) {
  const Eigen::Vector3d* moved = &motion.moved[at * units.size()];
  Eigen::Vector3d error = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < units.size(); ++i) error += (units[i] - motion.exact[i]) * moved[i];
  return error.norm() / kMilliScale;
}

// The largest frameError() over the frames, in the positions' units; stops early, returning a value
// above `give_up`, once a frame exceeds it. `*stopped_at` (when given) gets the frame it stopped at or
// the worst one.
double worstFrameError(const VertexMotion& motion, const std::vector<int>& units,
                       double give_up = std::numeric_limits<double>::infinity(), size_t* stopped_at = nullptr) {
  double worst = 0.0;
  const size_t frames = units.empty() ? 0 : motion.moved.size() / units.size();
  for (size_t at = 0; at < frames; ++at) {
    const double error = frameError(motion, units, at);
    if (stopped_at != nullptr && (error > worst || at == 0)) *stopped_at = at;
    worst = std::max(worst, error);
    if (worst > give_up) break;
  }
  return worst;
}

void writeUnits(const VertexMotion& motion, const std::vector<int>& units, int slots, int v,
                QuantizedInfluences* out) {
  std::vector<RoundingSlot> chosen(slots);
  for (size_t i = 0; i < units.size(); ++i) chosen[i] = RoundingSlot{motion.joints[i], units[i]};
  writeCanonical(chosen.data(), slots, v, out);
}

// Pass 2 for one vertex: the candidate with the smallest worst frame, if strictly better than pass 1's
// `pass1_worst` (whose rounding is already in `out`).
void refineVertex(const InfluenceSet& set, int v, const Eigen::Vector3d& position, const std::vector<SkinFrame>& frames,
                  double pass1_worst, QuantizedInfluences* out) {
  const VertexMotion motion = vertexMotion(set, v, position, frames);
  std::vector<int> best;
  double best_worst = pass1_worst;
  // The frame the last candidate was worst at, or gave up at, is tried first: a candidate worse
  // there than the best so far is worse over the frames too, so it is dropped without the scan that
  // would find the same (the choice is the scan's, to the bit). Measured on Quaternius Cyberpunk
  // (559 frames, 431 vertices refined): pass 2 365 M -> 152 M instructions (callgrind).
  size_t probe = 0;
  for (unsigned mask : candidateMasks(motion)) {
    std::vector<int> units = unitsOf(motion, mask);
    if (frameError(motion, units, probe) > best_worst) continue;
    const double w = worstFrameError(motion, units, best_worst, &probe);
    if (w < best_worst) {
      best_worst = w;
      best = std::move(units);
    }
  }
  if (!best.empty()) writeUnits(motion, best, set.slots_per_vertex, v, out);
}

// ---- The fast pass 1 ------------------------------------------------------------------------------

constexpr int kMomentJoints = 16;  // vertices with more distinct joints take the reference path

// A vertex's shares as vertexMotion() computes them (the same arithmetic, so the same bits), without
// the per-frame positions.
struct MotionShares {
  int n = 0;
  int missing = 0;
  std::array<int, kMomentJoints> joints{};
  std::array<double, kMomentJoints> exact{};
  std::array<int, kMomentJoints> floor_units{};
  bool tooMany = false;  // more than kMomentJoints distinct joints
  bool choice() const { return n > 1 && missing > 0 && missing < n; }
};

// e_i of the rounding `mask` gives slot i (bit i: rounded up), in thousandths: its units less the
// exact share.
double roundingError(const MotionShares& shares, unsigned mask, int i) {
  return (shares.floor_units[i] + static_cast<int>((mask >> i) & 1u)) - shares.exact[i];
}

MotionShares motionShares(const InfluenceSet& set, int v) {
  MotionShares shares;
  const int slots = set.slots_per_vertex;
  double sum = 0.0;
  for (int k = 0; k < slots; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * slots + k];
    if (w <= 0.0) continue;
    const int joint = set.joints[static_cast<size_t>(v) * slots + k];
    int at = 0;
    while (at < shares.n && shares.joints[at] != joint) ++at;
    if (at == shares.n) {
      if (shares.n == kMomentJoints) {
        shares.tooMany = true;
        return shares;
      }
      shares.joints[shares.n] = joint;
      shares.exact[shares.n] = w;
      ++shares.n;
    } else {
      shares.exact[at] += w;
    }
    sum += w;
  }
  int handed = 0;
  for (int i = 0; i < shares.n; ++i) {
    shares.exact[i] = shares.exact[i] / sum * kMilliScale;
    shares.floor_units[i] = static_cast<int>(std::floor(shares.exact[i]));
    handed += shares.floor_units[i];
  }
  shares.missing = kMilliScale - handed;
  return shares;
}

// candidateMasks() for MotionShares, in the same order, into `masks`.
void motionCandidates(const MotionShares& shares, std::vector<unsigned>* masks) {
  const int n = shares.n;
  std::array<int, kMomentJoints> order{};
  std::iota(order.begin(), order.begin() + n, 0);
  // Insertion sort: stable like std::stable_sort (so the same order) without its heap buffer.
  auto greater = [&](int a, int b) { return shares.exact[a] - shares.floor_units[a] > shares.exact[b] - shares.floor_units[b]; };
  for (int i = 1; i < n; ++i) {
    const int value = order[i];
    int j = i;
    for (; j > 0 && greater(value, order[j - 1]); --j) order[j] = order[j - 1];
    order[j] = value;
  }
  unsigned largest_remainder = 0;
  for (int i = 0; i < shares.missing; ++i) largest_remainder |= 1u << order[i];
  unsigned integral = 0;  // shares already on an integer cannot round up
  for (int i = 0; i < n; ++i)
    if (!(shares.exact[i] > shares.floor_units[i])) integral |= 1u << i;
  masks->clear();
  masks->push_back(largest_remainder);
  // Every n-bit mask with `missing` bits, ascending (Gosper's hack).
  const unsigned limit = 1u << n;
  for (unsigned mask = (1u << shares.missing) - 1; mask < limit;) {
    if (mask != largest_remainder && (mask & integral) == 0) masks->push_back(mask);
    const unsigned low = mask & (~mask + 1u);
    const unsigned ripple = mask + low;
    mask = (((ripple ^ mask) >> 2) / low) | ripple;
  }
}

// The moment of a joint triple (first joint, i, j), i <= j: the symmetric part of sum_t D_i^T D_j as
// its 10 upper entries, off-diagonal ones doubled, so that x^T C x = sum_{p <= q} c_pq x_p x_q.
struct TripleMoment {
  std::array<double, 10> c{};
  double scale = 0.0;  // i == j: sum_t |D_i(t)|_F^2, the size of the terms the form cancels
  bool zero = true;    // i == j: D_i(t) == 0 at every frame (joint i moves exactly as the first)
};

std::uint64_t tripleKey(int first, int i, int j) {
  if (i > j) std::swap(i, j);
  return (static_cast<std::uint64_t>(first) << 42) | (static_cast<std::uint64_t>(i) << 21) | static_cast<std::uint64_t>(j);
}

// The moments of the triples keys[begin, end), which share their first joint. Per frame each joint's
// difference from the first, D_k = M_k - M_first (3x4, by rows), is formed once for all the triples
// that use it, and each triple adds D_i^T D_j (4x4) row by row, two columns per SSE2 register; the
// symmetric part is taken at the end. The sums round differently from adding each entry's three
// products per frame, by the same order of magnitude (1e-16 of their terms), far inside the 1e-9 the
// comparisons allow for (momentMask()).
void tripleMoments(const std::vector<std::uint64_t>& keys, size_t begin, size_t end, const std::vector<SkinFrame>& frames,
                   std::vector<TripleMoment>* out) {
  const int first = static_cast<int>(keys[begin] >> 42);
  std::vector<int> joints;  // the i and j of the run, ascending
  for (size_t k = begin; k < end; ++k) {
    joints.push_back(static_cast<int>((keys[k] >> 21) & 0x1fffff));
    joints.push_back(static_cast<int>(keys[k] & 0x1fffff));
  }
  std::sort(joints.begin(), joints.end());
  joints.erase(std::unique(joints.begin(), joints.end()), joints.end());
  auto slotOf = [&](int joint) { return static_cast<size_t>(std::lower_bound(joints.begin(), joints.end(), joint) - joints.begin()); };
  std::vector<std::pair<size_t, size_t>> pairs;  // per triple: the slots of i and j
  for (size_t k = begin; k < end; ++k)
    pairs.emplace_back(slotOf(static_cast<int>((keys[k] >> 21) & 0x1fffff)), slotOf(static_cast<int>(keys[k] & 0x1fffff)));
  std::vector<double> rows(12 * joints.size());  // D_k by rows: rows[12 k + 4 r + c]
  std::vector<char> moves(joints.size(), 0);       // D_k != 0 at some frame
  // Per triple, sum_t D_i^T D_j by rows, two columns per register.
  struct alignas(16) Pair {
    double v[2];
  };
  std::vector<Pair> product(8 * (end - begin), Pair{{0.0, 0.0}});
  for (const SkinFrame& frame : frames) {
    const double* m0 = frame[first].data();
    for (size_t k = 0; k < joints.size(); ++k) {
      const double* mk = frame[joints[k]].data();
      double* d = &rows[12 * k];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) {
          d[4 * r + c] = mk[4 * c + r] - m0[4 * c + r];
          moves[k] |= d[4 * r + c] != 0.0;
        }
      }
    }
    for (size_t t = 0; t < pairs.size(); ++t) {
      const double* di = &rows[12 * pairs[t].first];
      const double* dj = &rows[12 * pairs[t].second];
      __m128d p[8];
      for (int k = 0; k < 8; ++k) p[k] = _mm_load_pd(product[8 * t + static_cast<size_t>(k)].v);
      for (int r = 0; r < 3; ++r) {
        const __m128d low = _mm_loadu_pd(dj + 4 * r), high = _mm_loadu_pd(dj + 4 * r + 2);
        for (int q = 0; q < 4; ++q) {
          const __m128d a = _mm_set1_pd(di[4 * r + q]);
          p[2 * q] = _mm_add_pd(p[2 * q], _mm_mul_pd(a, low));
          p[2 * q + 1] = _mm_add_pd(p[2 * q + 1], _mm_mul_pd(a, high));
        }
      }
      for (int k = 0; k < 8; ++k) _mm_store_pd(product[8 * t + static_cast<size_t>(k)].v, p[k]);
    }
  }
  for (size_t t = 0; t < pairs.size(); ++t) {
    double full[4][4];
    for (int q = 0; q < 4; ++q) {
      const Pair& low = product[8 * t + 2 * static_cast<size_t>(q)];
      const Pair& high = product[8 * t + 2 * static_cast<size_t>(q) + 1];
      full[q][0] = low.v[0];
      full[q][1] = low.v[1];
      full[q][2] = high.v[0];
      full[q][3] = high.v[1];
    }
    TripleMoment& moment = (*out)[begin + t];
    int at = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b) moment.c[at++] = a == b ? full[a][a] : full[a][b] + full[b][a];
    if (pairs[t].first == pairs[t].second) {
      moment.scale = full[0][0] + full[1][1] + full[2][2] + full[3][3];
      moment.zero = !moves[pairs[t].first];
    }
  }
}

double momentForm(const TripleMoment& moment, const Eigen::Vector3d& v) {
  const double x[4] = {v.x(), v.y(), v.z(), 1.0};
  double sum = 0.0;
  int at = 0;
  for (int p = 0; p < 4; ++p)
    for (int q = p; q < 4; ++q) sum += moment.c[at++] * x[p] * x[q];
  return sum;
}

// The moments of every triple the vertices with a choice use, sorted by key.
struct MomentTable {
  std::vector<std::uint64_t> keys;
  std::vector<TripleMoment> moments;
  const TripleMoment& at(int first, int i, int j) const {
    const std::uint64_t key = tripleKey(first, i, j);
    const size_t index = static_cast<size_t>(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin());
    assert(index < keys.size() && keys[index] == key);
    return moments[index];
  }
};

constexpr size_t kVertexGrain = 2048;

// The moments of every triple the vertices with a choice use, in every part (one table: parts share
// most of their joints' triples).
MomentTable momentTable(const std::vector<MotionPart>& parts, const std::vector<SkinFrame>& frames, int threads) {
  std::vector<std::vector<std::uint64_t>> chunk_keys;
  for (const MotionPart& part : parts) {
    const InfluenceSet& set = *part.set;
    const size_t vertices = static_cast<size_t>(set.vertexCount());
    std::vector<std::vector<std::uint64_t>> part_keys(parallelChunkCount(vertices, kVertexGrain));
    parallelFor(threads, vertices, kVertexGrain, [&](size_t chunk, size_t begin, size_t end) {
      std::vector<std::uint64_t>& keys = part_keys[chunk];
      for (size_t v = begin; v < end; ++v) {
        const MotionShares shares = motionShares(set, static_cast<int>(v));
        if (shares.tooMany || !shares.choice()) continue;
        for (int i = 1; i < shares.n; ++i)
          for (int j = i; j < shares.n; ++j) keys.push_back(tripleKey(shares.joints[0], shares.joints[i], shares.joints[j]));
      }
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    });
    for (std::vector<std::uint64_t>& keys : part_keys) chunk_keys.push_back(std::move(keys));
  }
  MomentTable table;
  for (std::vector<std::uint64_t>& keys : chunk_keys) {
    std::vector<std::uint64_t> merged;
    merged.reserve(table.keys.size() + keys.size());
    std::set_union(table.keys.begin(), table.keys.end(), keys.begin(), keys.end(), std::back_inserter(merged));
    table.keys.swap(merged);
    std::vector<std::uint64_t>().swap(keys);
  }
  table.moments.resize(table.keys.size());
  // Runs of one first joint, at most kTriplesPerRun long so that the threads share the work.
  constexpr size_t kTriplesPerRun = 256;
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t begin = 0; begin < table.keys.size();) {
    size_t end = begin + 1;
    while (end < table.keys.size() && end - begin < kTriplesPerRun && (table.keys[end] >> 42) == (table.keys[begin] >> 42)) ++end;
    runs.emplace_back(begin, end);
    begin = end;
  }
  parallelForEach(threads, runs.size(), [&](size_t r) { tripleMoments(table.keys, runs[r].first, runs[r].second, frames, &table.moments); });
  return table;
}

// The moments of a vertex's triples, found once for a run of vertices with the same joints (a mesh's
// neighbouring vertices usually share them): [i][j] for 1 <= i <= j < n.
struct TripleLookup {
  int n = 0;
  std::array<int, kMomentJoints> joints{};
  const TripleMoment* moment[kMomentJoints][kMomentJoints] = {};
  void find(const MotionShares& shares, const MomentTable& table) {
    if (n == shares.n && std::equal(joints.begin(), joints.begin() + n, shares.joints.begin())) return;
    n = shares.n;
    std::copy(shares.joints.begin(), shares.joints.begin() + n, joints.begin());
    for (int i = 1; i < n; ++i)
      for (int j = i; j < n; ++j) moment[i][j] = &table.at(joints[0], joints[i], joints[j]);
  }
};

// Pass 1 from the moments: the mask leastSquaresMask() would choose, or false when a comparison it
// makes comes too close to call with the moments' roundings (then the caller costs the vertex frame by
// frame; `masks` then holds the candidates). *cost gets the chosen candidate's error summed in squares
// (in thousandths squared) and *cost_error how far that figure may be off.
//
// A candidate is the rounding-down error f (f_i = floor_i - exact_i) plus its mask b, so its cost is
// e^T G e = f^T G f + 2 b . (G f) + b^T G b: with f^T G f and G f formed once per vertex, a candidate
// that rounds k shares up costs k^2 operations instead of n^2.
bool momentMask(const MotionShares& shares, const Eigen::Vector3d& position, const MomentTable& table,
                TripleLookup* lookup, std::vector<unsigned>* masks, unsigned* chosen, double* cost, double* cost_error) {
  const int n = shares.n;
  double gram[kMomentJoints][kMomentJoints];
  double magnitude[kMomentJoints];  // sqrt of G_ii plus what the form may have cancelled
  bool zero[kMomentJoints];         // d_i(t) == 0 at every frame: row and column i of G vanish
  const double x2 = position.squaredNorm() + 1.0;
  lookup->find(shares, table);
  for (int j = 0; j < n; ++j) gram[0][j] = gram[j][0] = 0.0;  // d_0 = 0
  magnitude[0] = 0.0;
  zero[0] = true;
  for (int i = 1; i < n; ++i) {
    for (int j = i; j < n; ++j) {
      const TripleMoment& moment = *lookup->moment[i][j];
      gram[i][j] = gram[j][i] = momentForm(moment, position);
      if (i == j) {
        magnitude[i] = std::sqrt(std::max(gram[i][i], 0.0) + 1e-6 * moment.scale * x2);
        zero[i] = moment.zero;
      }
    }
  }
  double total_magnitude = 0.0, size = 0.0;  // size: sum_ij |G_ij|, which bounds every cost's terms
  double round_down[kMomentJoints], pull[kMomentJoints];
  for (int i = 0; i < n; ++i) round_down[i] = shares.floor_units[i] - shares.exact[i];
  double base = 0.0;
  for (int i = 1; i < n; ++i) {
    total_magnitude += magnitude[i];
    pull[i] = 0.0;
    for (int j = 1; j < n; ++j) {
      pull[i] += gram[i][j] * round_down[j];
      size += std::abs(gram[i][j]);
    }
    base += round_down[i] * pull[i];
  }
  pull[0] = 0.0;
  auto costOf = [&](unsigned mask) {
    double linear = 0.0, quadratic = 0.0;
    for (unsigned rest = mask; rest != 0; rest &= rest - 1) {
      const int i = __builtin_ctz(rest);
      linear += pull[i];
      for (unsigned other = mask; other != 0; other &= other - 1) quadratic += gram[i][__builtin_ctz(other)];
    }
    return base + 2.0 * linear + quadratic;
  };
  motionCandidates(shares, masks);
  unsigned best = masks->front();
  double best_cost = costOf(best);
  const double tolerance = 1e-12 * std::max(1.0, best_cost);
  // Each |e_i| < 1, so every cost's terms sum to at most `size`: the reference's evaluation rounds by at
  // most (n + 1) units of roundoff of that, and this one (f^T G f, G f, the sums over the mask) by at
  // most (n + 1)^2 + 12 n + 12; 16 (n + 1)^2 units cover both.
  const double rounding = 16.0 * (n + 1) * (n + 1) * std::numeric_limits<double>::epsilon() * size;
  for (unsigned mask : *masks) {
    if (mask == best) continue;
    double differing = 0.0;
    bool moves = false;
    for (unsigned rest = mask ^ best; rest != 0; rest &= rest - 1) {
      const int i = __builtin_ctz(rest);
      differing += magnitude[i];
      moves |= !zero[i];
    }
    // Candidates that differ only where G's rows vanish have bit-identical costs in the reference
    // (the terms they change are products with zeros): never better.
    if (!moves) continue;
    const double c = costOf(mask);
    // The moments differ from the frame-by-frame sums by far less than 1e-9 of the terms they cancel
    // (typically 1e-14); only the rows of the joints the two candidates differ in change the difference.
    const double margin = c - (best_cost - tolerance);
    if (std::abs(margin) <= 1e-9 * differing * total_magnitude + rounding) return false;
    if (margin < 0.0) {
      best_cost = c;
      best = mask;
    }
  }
  *chosen = best;
  *cost = best_cost;
  *cost_error = 1e-9 * total_magnitude * total_magnitude + rounding;
  return true;
}

// worstFrameError() of the units a vertex's mask gives, skinning it frame by frame with the same
// arithmetic, so the same bits: transformPoint() and the weighted sum written out in scalars, in the
// order Eigen's `error += factor * transformPoint(m, p)` takes them (that expression kept a Vector3d
// temporary per joint and frame: Quaternius Cyberpunk's rounding stage took 101 ms at one thread with
// it, 65 ms without).
struct SettleVertex {
  int vertex = 0;
  int n = 0;
  std::array<int, kMomentJoints> joints{};
  std::array<double, kMomentJoints> factor{};
};

// e(t) = sum_i factor_i M_i(t) p at every frame, each component as
// ex += f * (((a0 x + a4 y) + a8 z) + a12): x and y in the two lanes of an SSE2 register (the matrix's
// column-major rows 0 and 1 are adjacent), z on its own, the same operations in the same order.
double motionWorstFrame(const SettleVertex& entry, const Eigen::Vector3d& position, const std::vector<SkinFrame>& frames) {
  const double x = position[0], y = position[1], z = position[2];
  const __m128d px = _mm_set1_pd(x), py = _mm_set1_pd(y), pz = _mm_set1_pd(z);
  double worst = 0.0;
  for (const SkinFrame& frame : frames) {
    __m128d exy = _mm_setzero_pd();
    double ez = 0.0;
    for (int i = 0; i < entry.n; ++i) {
      const double* a = frame[static_cast<size_t>(entry.joints[i])].data();  // column-major 4x4
      const double f = entry.factor[i];
      const __m128d moved_xy = _mm_add_pd(
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_loadu_pd(a), px), _mm_mul_pd(_mm_loadu_pd(a + 4), py)), _mm_mul_pd(_mm_loadu_pd(a + 8), pz)),
          _mm_loadu_pd(a + 12));
      exy = _mm_add_pd(exy, _mm_mul_pd(_mm_set1_pd(f), moved_xy));
      ez += f * (a[2] * x + a[6] * y + a[10] * z + a[14]);
    }
    double e[2];
    _mm_storeu_pd(e, exy);
    worst = std::max(worst, Eigen::Vector3d(e[0], e[1], ez).norm() / kMilliScale);
  }
  return worst;
}

// An upper bound on |M v| / (|v| + 1) over every frame's skin matrices: how far a skin matrix can carry
// a point, for bounding what rounding adds to a skinned position.
double skinReach(const std::vector<SkinFrame>& frames) {
  double reach = 1.0;
  for (const SkinFrame& frame : frames)
    for (const Eigen::Affine3d& m : frame) reach = std::max(reach, m.linear().norm() + m.translation().norm());
  return reach * (1.0 + 1e-9);
}

void writeMotionUnits(const MotionShares& shares, unsigned mask, int slots, int v, std::vector<RoundingSlot>* chosen,
                      QuantizedInfluences* out) {
  chosen->assign(static_cast<size_t>(slots), RoundingSlot{});
  for (int i = 0; i < shares.n; ++i)
    (*chosen)[i] = RoundingSlot{shares.joints[i], shares.floor_units[i] + static_cast<int>((mask >> i) & 1u)};
  writeCanonical(chosen->data(), slots, v, out);
}

// What a vertex costed frame by frame reuses from vertex to vertex.
struct FrameByFrameScratch {
  Eigen::MatrixXd gram;
  Eigen::VectorXd error, product;
  std::vector<Eigen::Vector3d> moved;  // frame-major, as VertexMotion::moved
  std::vector<RoundingSlot> chosen;
};

// leastSquaresMask() for the shares, with the candidates `masks` (motionCandidates()), skinning the
// vertex frame by frame as vertexMotion() does but without storing the skinned positions: each Gram
// entry adds the same products in the same order, and each candidate's cost is the same Eigen
// expression on the same matrix (the product into a kept vector instead of a temporary: the same
// kernel), so the same mask to the bit, without allocating per frame or per candidate. It is what the
// moments leave too close to call: candidates whose costs tie, e.g. a muscle that never responds and so
// moves its skin exactly as its carrier does.
unsigned frameByFrameMask(const MotionShares& shares, const Eigen::Vector3d& position, const std::vector<SkinFrame>& frames,
                          const std::vector<unsigned>& masks, FrameByFrameScratch* scratch) {
  const int n = shares.n;
  double gram[kMomentJoints][kMomentJoints] = {};
  scratch->moved.resize(frames.size() * static_cast<size_t>(n));
  for (size_t t = 0; t < frames.size(); ++t) {
    Eigen::Vector3d* moved = &scratch->moved[t * static_cast<size_t>(n)];
    for (int i = 0; i < n; ++i) moved[i] = transformPoint(frames[t][shares.joints[i]], position);
    for (int i = 1; i < n; ++i) {
      const Eigen::Vector3d di = moved[i] - moved[0];
      for (int j = i; j < n; ++j) gram[i][j] += di.dot(moved[j] - moved[0]);
    }
  }
  Eigen::MatrixXd& matrix = scratch->gram;
  matrix.setZero(n, n);
  for (int i = 1; i < n; ++i)
    for (int j = i; j < n; ++j) matrix(i, j) = matrix(j, i) = gram[i][j];
  Eigen::VectorXd& error = scratch->error;
  Eigen::VectorXd& product = scratch->product;
  error.resize(n);
  auto cost = [&](unsigned mask) {
    for (int i = 0; i < n; ++i) error[i] = shares.floor_units[i] + ((mask >> i) & 1u) - shares.exact[i];
    product.noalias() = matrix * error;
    return error.dot(product);
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

// motionWorstFrame() from the positions frameByFrameMask() kept (the same values, so the same bits).
double keptWorstFrame(const MotionShares& shares, unsigned mask, const FrameByFrameScratch& scratch) {
  double worst = 0.0;
  double factor[kMomentJoints];
  for (int i = 0; i < shares.n; ++i)
    factor[i] = roundingError(shares, mask, i);
  const size_t n = static_cast<size_t>(shares.n);
  for (size_t at = 0; at < scratch.moved.size(); at += n) {
    Eigen::Vector3d error = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < n; ++i) error += factor[i] * scratch.moved[at + i];
    worst = std::max(worst, error.norm() / kMilliScale);
  }
  return worst;
}

}  // namespace

QuantizedInfluences quantizeForMotionReference(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
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
    refineVertex(set, v, bind_positions[v], frames, worst[v], &out);
  }
  return out;
}

QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames) {
  return quantizeForMotion(set, bind_positions, frames, 1);
}

QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames, int threads) {
  return std::move(quantizeForMotion({MotionPart{&set, &bind_positions}}, frames, threads).front());
}

namespace {

// One part's rounding between the passes: pass 1 for every part first, so that pass 2 refines by the
// character's worst vertex, not each part's. Refined by each part's own worst, a body cut into other
// meshes rounded otherwise (the mannequin split by dominant joint: several vertices 0.001 apart from
// the whole's rounding).
struct PartRounding {
  const InfluenceSet& set;
  const std::vector<Eigen::Vector3d>& bind_positions;
  QuantizedInfluences out;
  // `worst` is exact where `known`; elsewhere `bound` bounds it from above.
  std::vector<double> worst, bound;
  std::vector<char> known;
  std::vector<unsigned> chosen;
  double worst_floor = 0.0;  // a lower bound on the part's worst
};

// Pass 1 of one part.
PartRounding roundPart(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                       const std::vector<SkinFrame>& frames, const MomentTable& table, int threads) {
  const size_t vertex_count = static_cast<size_t>(set.vertexCount());
  PartRounding part{set, bind_positions, quantizeInfluences(set, kMilliScale, threads), std::vector<double>(vertex_count, 0.0),
                    std::vector<double>(vertex_count, 0.0), std::vector<char>(vertex_count, 1),
                    std::vector<unsigned>(vertex_count, 0), 0.0};
  QuantizedInfluences& out = part.out;
  const int slots = set.slots_per_vertex;
  std::vector<double>& worst = part.worst;
  std::vector<double>& bound = part.bound;
  std::vector<char>& known = part.known;
  std::vector<unsigned>& chosen = part.chosen;
  // Per chunk, a lower bound on the part's worst: a vertex's worst frame is at least its root mean square.
  std::vector<double> chunk_floor(parallelChunkCount(vertex_count, kVertexGrain), 0.0);
  const double frame_count = static_cast<double>(frames.size());
  const double skin_reach = skinReach(frames);
  parallelFor(threads, vertex_count, kVertexGrain, [&](size_t chunk, size_t begin, size_t end) {
    std::vector<unsigned> masks;
    TripleLookup lookup;
    FrameByFrameScratch frame_by_frame;
    double lowest_worst = 0.0;
    for (size_t v = begin; v < end; ++v) {
      const int vertex = static_cast<int>(v);
      const MotionShares shares = motionShares(set, vertex);
      if (!shares.tooMany && !shares.choice()) continue;
      unsigned mask = 0;
      double cost = 0.0, cost_error = 0.0;
      if (!shares.tooMany && !momentMask(shares, bind_positions[v], table, &lookup, &masks, &mask, &cost, &cost_error)) {
        // momentMask() left `masks` holding the candidates.
        mask = frameByFrameMask(shares, bind_positions[v], frames, masks, &frame_by_frame);
        chosen[v] = mask;
        worst[v] = keptWorstFrame(shares, mask, frame_by_frame);
        writeMotionUnits(shares, mask, slots, vertex, &frame_by_frame.chosen, &out);
        lowest_worst = std::max(lowest_worst, worst[v]);
        continue;
      }
      if (shares.tooMany) {
        const VertexMotion motion = vertexMotion(set, vertex, bind_positions[v], frames);
        if (!hasChoice(motion)) continue;
        const std::vector<int> units = unitsOf(motion, leastSquaresMask(motion, candidateMasks(motion)));
        worst[v] = worstFrameError(motion, units);
        writeUnits(motion, units, slots, vertex, &out);
        lowest_worst = std::max(lowest_worst, worst[v]);
        continue;
      }
      chosen[v] = mask;
      writeMotionUnits(shares, mask, slots, vertex, &frame_by_frame.chosen, &out);
      // |r(t)| <= |sum_i e_i d_i(t)| + |sum_i e_i| |M_0(t) v|: the second term is rounding only.
      double sum_error = 0.0, largest = 0.0;
      for (int i = 0; i < shares.n; ++i) {
        const double e = roundingError(shares, mask, i);
        sum_error += e;
        largest = std::max(largest, std::abs(e));
      }
      // The positions' magnitude times the shares' rounding: sum_i e_i is 0 up to rounding, and the
      // reference adds e_i M_i v with roundings relative to |M_i v|.
      const double rounding = (std::abs(sum_error) + 1e-12 * largest) * skin_reach * (bind_positions[v].norm() + 1.0);
      const double squares = std::max(cost, 0.0);
      bound[v] = (std::sqrt(squares + cost_error) + rounding) * (1.0 + 1e-9) / kMilliScale;
      known[v] = 0;
      lowest_worst = std::max(lowest_worst, (std::sqrt(std::max(squares - cost_error, 0.0) / frame_count) * (1.0 - 1e-9) -
                                             rounding) / kMilliScale);
    }
    chunk_floor[chunk] = lowest_worst;
  });

  part.worst_floor = chunk_floor.empty() ? 0.0 : *std::max_element(chunk_floor.begin(), chunk_floor.end());
  return part;
}

// Gives every vertex of `part` whose bound reaches `threshold` its exact worst frame; returns the
// largest exact worst.
double settleWorst(PartRounding* part, const std::vector<SkinFrame>& frames, double threshold, int threads) {
  const size_t vertex_count = part->worst.size();
  std::vector<double>& worst = part->worst;
  std::vector<char>& known = part->known;
  // The vertices to settle, listed, then in a few chunks per thread: chunks of the part's vertices left
  // a part of a few hundred vertices on one thread (each writes only its own vertices' worst, so the
  // chunking does not change a bit).
  std::vector<SettleVertex> pending;
  for (size_t v = 0; v < vertex_count; ++v) {
    if (known[v] || part->bound[v] < threshold) continue;
    const MotionShares shares = motionShares(part->set, static_cast<int>(v));
    SettleVertex entry;
    entry.vertex = static_cast<int>(v);
    entry.n = shares.n;
    entry.joints = shares.joints;
    for (int i = 0; i < shares.n; ++i)
      entry.factor[i] = roundingError(shares, part->chosen[v], i);
    pending.push_back(entry);
    known[v] = 1;
  }
  const size_t chunks = 4 * static_cast<size_t>(resolveThreadCount(threads));
  const size_t grain = std::max<size_t>(16, (pending.size() + chunks - 1) / chunks);
  parallelFor(threads, pending.size(), grain, [&](size_t, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k)
      worst[static_cast<size_t>(pending[k].vertex)] =
          motionWorstFrame(pending[k], part->bind_positions[static_cast<size_t>(pending[k].vertex)], frames);
  });
  double largest = 0.0;
  for (size_t v = 0; v < vertex_count; ++v)
    if (known[v]) largest = std::max(largest, worst[v]);
  return largest;
}

// Pass 2 on the vertices of `part` that could decide the character's worst error `character_worst`
// (every vertex above kRefineShare of it has settled its exact worst frame).
void refinePart(PartRounding* part, const std::vector<SkinFrame>& frames, double character_worst, int threads) {
  std::vector<int> refine;
  for (size_t v = 0; v < part->worst.size(); ++v) {
    if (!part->known[v] || part->worst[v] <= kRefineShare * character_worst) continue;
    refine.push_back(static_cast<int>(v));
  }
  parallelForEach(threads, refine.size(), [&](size_t r) {
    const int v = refine[r];
    refineVertex(part->set, v, part->bind_positions[v], frames, part->worst[v], &part->out);
  });
}

}  // namespace

std::vector<QuantizedInfluences> quantizeForMotion(const std::vector<MotionPart>& parts, const std::vector<SkinFrame>& frames,
                                                   int threads) {
  std::vector<QuantizedInfluences> out;
  if (frames.empty()) {
    for (const MotionPart& part : parts) out.push_back(quantizeInfluences(*part.set, kMilliScale));
    return out;
  }
  const MomentTable table = momentTable(parts, frames, threads);
  std::vector<PartRounding> rounding;
  rounding.reserve(parts.size());
  double floor = 0.0;
  for (const MotionPart& part : parts) {
    rounding.push_back(roundPart(*part.set, *part.bind_positions, frames, table, threads));
    floor = std::max(floor, rounding.back().worst_floor);
  }
  // The character's worst: only vertices whose bound reaches the largest lower bound can hold it.
  double character_worst = 0.0;
  for (PartRounding& part : rounding) character_worst = std::max(character_worst, settleWorst(&part, frames, floor, threads));
  // Every vertex that could be above kRefineShare of it gets its exact worst frame, then pass 2.
  for (PartRounding& part : rounding) {
    settleWorst(&part, frames, kRefineShare * character_worst, threads);
    refinePart(&part, frames, character_worst, threads);
  }
  for (PartRounding& part : rounding) out.push_back(std::move(part.out));
  return out;
}

}  // namespace rigbake
