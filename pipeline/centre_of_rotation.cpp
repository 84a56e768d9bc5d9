#include "pipeline/centre_of_rotation.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>

#include "pipeline/parallel.h"

namespace rigbake {

double weightSimilarity(const SparseWeights& p, const SparseWeights& v) {
  // The common joints, in order; only they contribute (a product with a zero weight vanishes).
  double common_p[16], common_v[16];
  int count = 0;
  size_t a = 0, b = 0;
  while (a < p.entries.size() && b < v.entries.size() && count < 16) {
    if (p.entries[a].first < v.entries[b].first) {
      ++a;
    } else if (v.entries[b].first < p.entries[a].first) {
      ++b;
    } else {
      common_p[count] = p.entries[a++].second;
      common_v[count++] = v.entries[b++].second;
    }
  }
  double sum = 0.0;
  for (int j = 0; j < count; ++j) {
    for (int k = j + 1; k < count; ++k) {
      const double cross = common_p[j] * common_v[k] - common_p[k] * common_v[j];
      // Each unordered pair stands for the two ordered pairs (j, k) and (k, j) of the paper's sum.
      sum += 2.0 * common_p[j] * common_p[k] * common_v[j] * common_v[k] * std::exp(-cross * cross / (kCorSigma * kCorSigma));
    }
  }
  return sum;
}

namespace {

SparseWeights sparseOf(const InfluenceSet& set, int v) {
  std::map<int, double> merged;
  for (int k = 0; k < set.slots_per_vertex; ++k) {
    const double w = set.weights[static_cast<size_t>(v) * set.slots_per_vertex + k];
    if (w > 0.0) merged[set.joints[static_cast<size_t>(v) * set.slots_per_vertex + k]] += w;
  }
  SparseWeights out;
  out.entries.assign(merged.begin(), merged.end());
  return out;
}

// Triangles with the same weights to 1/64, summed: area, area * centroid, area * weights.
struct TriangleCluster {
  SparseWeights weights;  // area-weighted mean
  double area = 0.0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // sum of area * centroid
};

std::vector<TriangleCluster> triangleClusters(const MeshPart& mesh, const InfluenceSet& influences) {
  std::vector<SparseWeights> vertex_weights(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) vertex_weights[v] = sparseOf(influences, static_cast<int>(v));
  std::map<std::vector<std::pair<int, long>>, size_t> cluster_of_key;
  std::vector<TriangleCluster> clusters;
  std::vector<std::map<int, double>> weighted_sum;
  for (const auto& triangle : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.positions[triangle[0]];
    const Eigen::Vector3d& b = mesh.positions[triangle[1]];
    const Eigen::Vector3d& c = mesh.positions[triangle[2]];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!(area > 0.0)) continue;
    std::map<int, double> mean;
    for (int corner : triangle)
      for (const auto& [joint, w] : vertex_weights[corner].entries) mean[joint] += w / 3.0;
    std::vector<std::pair<int, long>> key;
    for (const auto& [joint, w] : mean) {
      const long step = std::lround(w * 64.0);
      if (step > 0) key.emplace_back(joint, step);
    }
    if (key.size() < 2) continue;  // one joint: similar to nothing (the similarity needs two)
    auto [it, added] = cluster_of_key.emplace(key, clusters.size());
    if (added) {
      clusters.emplace_back();
      weighted_sum.emplace_back();
    }
    TriangleCluster& cluster = clusters[it->second];
    cluster.area += area;
    cluster.moment += area * (a + b + c) / 3.0;
    for (const auto& [joint, w] : mean) weighted_sum[it->second][joint] += area * w;
  }
  for (size_t i = 0; i < clusters.size(); ++i)
    for (const auto& [joint, sum] : weighted_sum[i]) clusters[i].weights.entries.emplace_back(joint, sum / clusters[i].area);
  return clusters;
}

}  // namespace

RotationCentres optimizedRotationCentres(const MeshPart& mesh, const InfluenceSet& influences, int threads) {
  const size_t count = mesh.positions.size();
  RotationCentres out;
  out.centre.assign(count, Eigen::Vector3d::Zero());
  out.has_centre.assign(count, 0);
  const std::vector<TriangleCluster> clusters = triangleClusters(mesh, influences);
  // Clusters by joint pair: a vertex can only resemble a cluster that has two of its joints.
  std::map<std::pair<int, int>, std::vector<int>> clusters_of_pair;
  for (size_t i = 0; i < clusters.size(); ++i) {
    const auto& entries = clusters[i].weights.entries;
    for (size_t j = 0; j < entries.size(); ++j)
      for (size_t k = j + 1; k < entries.size(); ++k) clusters_of_pair[{entries[j].first, entries[k].first}].push_back(static_cast<int>(i));
  }
  // A centre depends on the vertex's weights alone, and skinned meshes repeat rows (a ring of a limb,
  // both sides of a UV seam): each distinct row is summed once, as its first vertex would be, and every
  // vertex with it gets the same bits. (These sums are most of the 100k-vertex sample's first bake; its
  // smooth procedural weights repeat few rows, so there this saves about a tenth.)
  std::map<std::vector<std::pair<int, double>>, size_t> row_index;
  std::vector<SparseWeights> rows;
  std::vector<size_t> row_of_vertex(count);
  for (size_t v = 0; v < count; ++v) {
    SparseWeights weights = sparseOf(influences, static_cast<int>(v));
    auto [it, added] = row_index.emplace(weights.entries, rows.size());
    if (added) rows.push_back(std::move(weights));
    row_of_vertex[v] = it->second;
  }
  std::vector<Eigen::Vector3d> row_centre(rows.size(), Eigen::Vector3d::Zero());
  std::vector<char> row_has_centre(rows.size(), 0);
  constexpr size_t kRowsPerChunk = 256;
  parallelFor(threads, rows.size(), kRowsPerChunk, [&](size_t, size_t begin, size_t end) {
    std::vector<size_t> stamp(clusters.size(), static_cast<size_t>(-1));
    for (size_t r = begin; r < end; ++r) {
      const SparseWeights& weights = rows[r];
      double total = 0.0;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      const auto& entries = weights.entries;
      for (size_t j = 0; j < entries.size(); ++j) {
        for (size_t k = j + 1; k < entries.size(); ++k) {
          auto found = clusters_of_pair.find({entries[j].first, entries[k].first});
          if (found == clusters_of_pair.end()) continue;
          for (int i : found->second) {
            if (stamp[i] == r) continue;
            stamp[i] = r;
            const double s = weightSimilarity(weights, clusters[i].weights);
            total += s * clusters[i].area;
            sum += s * clusters[i].moment;
          }
        }
      }
      if (total > 1e-300) {
        row_centre[r] = sum / total;
        row_has_centre[r] = 1;
      }
    }
  });
  for (size_t v = 0; v < count; ++v) {
    out.centre[v] = row_centre[row_of_vertex[v]];
    out.has_centre[v] = row_has_centre[row_of_vertex[v]];
  }
  return out;
}

std::vector<Eigen::Vector3d> skinCentreOfRotation(const std::vector<Eigen::Vector3d>& bind_positions,
                                                  const InfluenceSet& influences, const RotationCentres& centres,
                                                  const std::vector<Eigen::Affine3d>& frame,
                                                  const DualQuaternionFrame& rotations) {
  const int slots = influences.slots_per_vertex;
  std::vector<Eigen::Vector3d> posed(bind_positions.size());
  for (size_t v = 0; v < bind_positions.size(); ++v) {
    const Eigen::Vector3d& p = bind_positions[v];
    const size_t row = static_cast<size_t>(v) * slots;
    if (!centres.has_centre[v]) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = 0; k < slots; ++k)
        if (influences.weights[row + k] > 0.0) sum += influences.weights[row + k] * (frame[influences.joints[row + k]] * p);
      posed[v] = sum;
      continue;
    }
    const Eigen::Vector3d& centre = centres.centre[v];
    Eigen::Vector4d blend = Eigen::Vector4d::Zero();
    Eigen::Vector3d moved_centre = Eigen::Vector3d::Zero();
    Eigen::Vector4d first = Eigen::Vector4d::Zero();
    bool have_first = false;
    for (int k = 0; k < slots; ++k) {
      const double w = influences.weights[row + k];
      if (w <= 0.0) continue;
      const int joint = influences.joints[row + k];
      Eigen::Vector4d q = rotations.real[joint].coeffs();
      if (!have_first) {
        first = q;
        have_first = true;
      } else if (q.dot(first) < 0.0) {
        q = -q;
      }
      blend += w * q;
      moved_centre += w * (frame[joint] * centre);
    }
    const Eigen::Matrix3d rotation = Eigen::Quaterniond(blend.normalized()).toRotationMatrix();
    posed[v] = rotation * p + (moved_centre - rotation * centre);
  }
  return posed;
}

}  // namespace rigbake
