// How low 0.001 weights can take the deformation error at all. Issue 4 sets a goal of 0.1 mm at 10
// influences; these tests show on the shared assets' own weights and own clips (no muscles, nothing of
// rigbake's weighting) that some vertices cannot get there with any 0.001 rounding of their weights,
// that rigbake's worst vertex is as good as any rounding keeping each weight within 0.001 allows, and
// that it is close to the best rounding there is at all.
//
// The search is exhaustive: a rounding whose worst frame stays under E has a mean squared error under
// E^2, so every candidate lies inside the ellipsoid (q - x)^T G (q - x) < F E^2 (F frames, G the Gram
// matrix of the joints' displacements at the vertex), and Schnorr-Euchner enumeration visits every
// lattice point inside it.
#include <Eigen/Cholesky>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <iostream>
#include <limits>
#include <numeric>
#include <vector>

#include "formats/gltf_document.h"
#include "pipeline/influences.h"
#include "pipeline/pose.h"
#include "pipeline/quantize_for_motion.h"
#include "influence_fixtures.h"
#include "test_support.h"

namespace rigbake {
namespace {

constexpr double kGoalMetres = 0.1e-3;
constexpr double kMetresPerUnit = 1.0 / kMilliScale;
constexpr long kNodeLimit = 5000000;

// One vertex's own joints, exact shares in thousandths, and where each joint carries it per frame.
struct VertexMotion {
  std::vector<int> joints;
  std::vector<double> exact;
  std::vector<std::vector<Eigen::Vector3d>> moved;  // [frame][joint]
};

VertexMotion vertexMotion(const InfluenceSet& set, int v, const Eigen::Vector3d& position,
                          const std::vector<SkinFrame>& frames) {
  VertexMotion motion;
  double sum = 0.0;
  for (int k = 0; k < set.slots_per_vertex; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * set.slots_per_vertex + k];
    if (w <= 0.0) continue;
    motion.joints.push_back(set.joints[static_cast<size_t>(v) * set.slots_per_vertex + k]);
    motion.exact.push_back(w);
    sum += w;
  }
  for (double& share : motion.exact) share = share / sum * kMilliScale;
  for (const SkinFrame& frame : frames) {
    std::vector<Eigen::Vector3d> moved;
    for (int joint : motion.joints) moved.push_back(transformPoint(frame[joint], position));
    motion.moved.push_back(moved);
  }
  return motion;
}

double worstFrame(const VertexMotion& motion, const std::vector<int>& units) {
  double worst = 0.0;
  for (const auto& moved : motion.moved) {
    Eigen::Vector3d error = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < units.size(); ++i) error += (units[i] - motion.exact[i]) * moved[i];
    worst = std::max(worst, error.norm() * kMetresPerUnit);
  }
  return worst;
}

// The smallest worst-frame error over every 0.001 rounding (units >= 0 summing to 1000) whose worst
// frame is below `ceiling`, or `ceiling` when there is none. `exhaustive` is false when the search gave
// up (a degenerate or very wide ellipsoid): then the answer proves nothing.
struct Floor {
  double worst = 0.0;
  bool exhaustive = true;
};

Floor roundingFloor(const VertexMotion& motion, double ceiling) {
  const int n = static_cast<int>(motion.joints.size());
  const int reference = static_cast<int>(std::max_element(motion.exact.begin(), motion.exact.end()) -
                                         motion.exact.begin());
  std::vector<int> free;  // every joint but the reference, which takes what they leave of 1000
  for (int i = 0; i < n; ++i)
    if (i != reference) free.push_back(i);
  const int m = n - 1;
  Floor floor{ceiling, true};
  if (m == 0) {
    floor.worst = 0.0;
    return floor;
  }
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(m, m);
  for (const auto& moved : motion.moved) {
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b)
        gram(a, b) += (moved[free[a]] - moved[reference]).dot(moved[free[b]] - moved[reference]) *
                      kMetresPerUnit * kMetresPerUnit;
  }
  Eigen::LLT<Eigen::MatrixXd> cholesky(gram);
  if (cholesky.info() != Eigen::Success) return Floor{ceiling, false};
  const Eigen::MatrixXd r = cholesky.matrixU();
  const double radius = static_cast<double>(motion.moved.size()) * ceiling * ceiling;
  std::vector<int> units(n, 0);
  long nodes = 0;
  // Depth-first over free[m-1] .. free[0]; each level's cost term grows away from its centre, so
  // each side stops at the first value past the radius.
  auto visit = [&](auto&& self, int k, double partial) -> void {
    if (++nodes > kNodeLimit) {
      floor.exhaustive = false;
      return;
    }
    if (k < 0) {
      int used = 0;
      for (int a = 0; a < m; ++a) used += units[free[a]];
      if (used > kMilliScale) return;
      units[reference] = kMilliScale - used;
      floor.worst = std::min(floor.worst, worstFrame(motion, units));
      return;
    }
    double shift = 0.0;
    for (int j = k + 1; j < m; ++j) shift += r(k, j) * (units[free[j]] - motion.exact[free[j]]);
    const double center = motion.exact[free[k]] - shift / r(k, k);
    const int nearest = std::max(0, static_cast<int>(std::lround(center)));
    for (int direction : {+1, -1}) {
      for (int value = direction > 0 ? nearest : nearest - 1; value >= 0 && value <= kMilliScale; value += direction) {
        const double term = r(k, k) * (value - center);
        if (partial + term * term >= radius) break;
        units[free[k]] = value;
        self(self, k - 1, partial + term * term);
      }
    }
    units[free[k]] = 0;
  };
  visit(visit, m - 1, 0.0);
  return floor;
}

// The least worst-frame error over the roundings that take each share down or up, by trying them all.
double bestDownOrUp(const VertexMotion& motion) {
  const int n = static_cast<int>(motion.joints.size());
  double best = std::numeric_limits<double>::infinity();
  std::vector<int> units(n);
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    int sum = 0;
    bool possible = true;
    for (int i = 0; i < n; ++i) {
      units[i] = static_cast<int>(std::floor(motion.exact[i])) + static_cast<int>((mask >> i) & 1u);
      possible = possible && !(((mask >> i) & 1u) && motion.exact[i] == std::floor(motion.exact[i]));
      sum += units[i];
    }
    if (possible && sum == kMilliScale) best = std::min(best, worstFrame(motion, units));
  }
  return best;
}

}  // namespace

TEST_CASE("0.001 weights cannot keep every vertex within 0.1 mm: the floor on the assets' own weights") {
  std::cout << "asset | frames | rigbake max mm | proven floor mm (vertex) | rigbake there mm\n";
  for (const std::string& name : test::sharedAssetNames()) {
    const std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    const Character character = loadCharacter(path).character;
    const std::vector<SkinFrame> frames = test::ownClipFrames(character);
    if (frames.empty()) continue;  // no motion, no error: the goal holds trivially (error 0)
    double rigbake_max = 0.0;
    bool proven = false;
    double proven_floor = 0.0, rigbake_there = 0.0;
    int proven_vertex = -1;
    for (const MeshPart& mesh : character.meshes) {
      if (!mesh.skinned) continue;
      const InfluenceSet exact = pruneInfluences(influencesFromMesh(mesh), 10);
      const InfluenceSet rounded = dequantizeInfluences(quantizeForMotion(exact, mesh.positions, frames));
      std::vector<std::pair<double, int>> worst_first;
      for (int v = 0; v < exact.vertexCount(); ++v) {
        const VertexMotion motion = vertexMotion(exact, v, mesh.positions[v], frames);
        std::vector<int> units;
        for (int joint : motion.joints) {
          int u = 0;
          for (int k = 0; k < rounded.slots_per_vertex; ++k) {
            const size_t at = static_cast<size_t>(v) * rounded.slots_per_vertex + k;
            if (rounded.joints[at] == joint && rounded.weights[at] > 0.0)
              u = static_cast<int>(std::lround(rounded.weights[at] * kMilliScale));
          }
          units.push_back(u);
        }
        // The rounding keeps each vertex on its own joints (every unit accounted for above).
        REQUIRE(std::accumulate(units.begin(), units.end(), 0) == kMilliScale);
        const double worst = worstFrame(motion, units);
        rigbake_max = std::max(rigbake_max, worst);
        if (worst > kGoalMetres) worst_first.emplace_back(worst, v);
      }
      std::sort(worst_first.rbegin(), worst_first.rend());
      // No rounding that keeps every weight within 0.001 does better than rigbake's on this part: the
      // part's worst is the largest per-vertex best, and a vertex rigbake keeps under the largest best
      // found so far cannot raise it.
      double optimum = 0.0;
      for (const auto& [worst, v] : worst_first) {
        if (worst <= optimum) break;
        optimum = std::max(optimum, bestDownOrUp(vertexMotion(exact, v, mesh.positions[v], frames)));
      }
      if (!worst_first.empty()) CHECK(worst_first.front().first == Approx(optimum).epsilon(1e-12));
      // The worst vertices first: the first one no rounding brings under 0.1 mm settles the question.
      for (size_t i = 0; i < worst_first.size() && i < 40 && !proven; ++i) {
        const int v = worst_first[i].second;
        const VertexMotion motion = vertexMotion(exact, v, mesh.positions[v], frames);
        const Floor under_goal = roundingFloor(motion, kGoalMetres);
        if (!under_goal.exhaustive || under_goal.worst < kGoalMetres) continue;
        // Proven: nothing under 0.1 mm. The true best, searched up to rigbake's own error there.
        const Floor best = roundingFloor(motion, worst_first[i].first * (1.0 + 1e-9));
        REQUIRE(best.exhaustive);
        proven = true;
        proven_vertex = v;
        proven_floor = best.worst;
        rigbake_there = worst_first[i].first;
      }
    }
    std::cout << name << " | " << frames.size() << " | " << rigbake_max * 1000.0 << " | "
              << (proven ? std::to_string(proven_floor * 1000.0) + " (" + std::to_string(proven_vertex) + ")" : "-")
              << " | " << rigbake_there * 1000.0 << "\n";
    // Every shared asset with clips (CesiumMan, Cyberpunk, RobotExpressive) has such a vertex.
    INFO(name << ": vertex " << proven_vertex);
    REQUIRE(proven);
    CHECK(proven_floor >= kGoalMetres);
    // rigbake's rounding there, which keeps each weight within 0.001, is within 5% of the best 0.001
    // rounding that exists at all.
    CHECK(rigbake_there <= 1.05 * proven_floor);
  }
}

}  // namespace rigbake
