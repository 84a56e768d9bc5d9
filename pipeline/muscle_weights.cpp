// Muscle skin weights. Falloff around the origin-insertion segment: the smooth compact kernel
// (1 - x^2)^2, x = distance / radius (Wendland-like; C1 at the rim). Smoothing: the umbrella operator,
// Taubin, "A Signal Processing Approach to Fair Surface Design" (SIGGRAPH 1995), first pass only: on a
// weight field it only blurs, so no shrink compensation is needed.
#include "pipeline/muscle_weights.h"

#include "pipeline/muscle_joint.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace rigbake {
namespace {

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Vector3d ab = b - a;
  double length_squared = ab.squaredNorm();
  double t = length_squared > 0 ? std::clamp((p - a).dot(ab) / length_squared, 0.0, 1.0) : 0.0;
  return (p - (a + ab * t)).norm();
}

Eigen::Vector3d closestOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length_squared = ab.squaredNorm();
  const double t = length_squared > 0 ? std::clamp((p - a).dot(ab) / length_squared, 0.0, 1.0) : 0.0;
  return a + ab * t;
}

// Smoothstep from facing_start (no share) to facing_full (all of it) on the cosine between the
// vertex's direction from the muscle's axis and the muscle's up axis.
double sideFactor(double facing, const MuscleWeightOptions& options) {
  const double x = std::clamp((facing - options.facing_start) / (options.facing_full - options.facing_start), 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

double falloff(double distance, double radius) {
  if (radius <= 0 || distance >= radius) return 0.0;
  double x = distance / radius;
  return (1.0 - x * x) * (1.0 - x * x);
}

void smooth(std::vector<double>* field, const SurfaceGraph& surface, const MuscleWeightOptions& options) {
  std::vector<double> next(field->size());
  for (int pass = 0; pass < options.smoothing_iterations; ++pass) {
    for (int w = 0; w < surface.weldedCount(); ++w) {
      const std::vector<int>& ring = surface.neighbours[w];
      if (ring.empty()) {
        next[w] = (*field)[w];
        continue;
      }
      double mean = 0.0;
      for (int n : ring) mean += (*field)[n];
      mean /= static_cast<double>(ring.size());
      next[w] = (*field)[w] + options.smoothing_lambda * (mean - (*field)[w]);
    }
    field->swap(next);
  }
}

// Per welded vertex, min(1, gain * 4 x (1 - x)) with x the share of its weight on `joint` and the joints
// below it (its first part vertex's weights: split vertices carry the same).
std::vector<double> blendFactors(const Skeleton& skeleton, const MeshPart& part, const SurfaceGraph& surface, int joint,
                                 const MuscleWeightOptions& options) {
  std::vector<char> below(skeleton.size(), 0);
  for (int j = 0; j < skeleton.size(); ++j) {
    for (int a = j; a >= 0 && !below[j]; a = skeleton.parents[a]) below[j] = a == joint;
  }
  std::vector<double> blend(surface.weldedCount(), 0.0);
  const int slots = part.influences_per_vertex;
  for (int v = static_cast<int>(part.positions.size()) - 1; v >= 0; --v) {
    double on_side = 0.0, total = 0.0;
    for (int k = 0; k < slots; ++k) {
      const double weight = part.weights[v * slots + k];
      total += weight;
      if (below[part.joints[v * slots + k]]) on_side += weight;
    }
    const double x = total > 0.0 ? on_side / total : 0.0;
    blend[surface.weld_of_vertex[v]] = std::min(1.0, options.corrective_blend_gain * 4.0 * x * (1.0 - x));
  }
  return blend;
}

}  // namespace

double muscleWeightRadius(const MusclePart& part, double body_height) {
  if (part.weight_radius > 0) return part.weight_radius;
  return 0.02 * body_height + 0.15 * (part.insertion.world - part.origin.world).norm();
}

std::vector<double> muscleWeightRadii(const Character& character, const MuscleSet& muscles, double body_height) {
  std::vector<double> radii;
  for (const MusclePart& muscle : muscles.parts) {
    const double base = muscleWeightRadius(muscle, body_height);
    if (muscle.weight_radius > 0) {
      radii.push_back(base);
      continue;
    }
    // Only skin the muscle could take weight from counts: vertices weighted to a joint it spans.
    std::vector<char> spans(character.skeleton.size(), 0);
    for (int joint : spannedJoints(character.skeleton, muscle)) spans[joint] = 1;
    double nearest = std::numeric_limits<double>::infinity();
    for (const MeshPart& part : character.meshes) {
      if (!part.skinned) continue;
      const int slots = part.influences_per_vertex;
      for (size_t v = 0; v < part.positions.size(); ++v) {
        bool reachable = false;
        for (int k = 0; k < slots && !reachable; ++k)
          reachable = part.weights[v * slots + k] > 0 && spans[part.joints[v * slots + k]];
        if (reachable) nearest = std::min(nearest, distanceToSegment(part.positions[v], muscle.origin.world, muscle.insertion.world));
      }
    }
    radii.push_back(std::isfinite(nearest) ? std::max(base, nearest + 0.5 * base) : base);
  }
  return radii;
}

std::vector<int> spannedJoints(const Skeleton& skeleton, const MusclePart& part) {
  std::vector<int> up_from_origin, up_from_insertion;
  for (int j = part.origin.joint; j >= 0; j = skeleton.parents[j]) up_from_origin.push_back(j);
  for (int j = part.insertion.joint; j >= 0; j = skeleton.parents[j]) up_from_insertion.push_back(j);
  // Drop the common ancestors above the lowest common one.
  while (up_from_origin.size() >= 2 && up_from_insertion.size() >= 2 &&
         up_from_origin[up_from_origin.size() - 2] == up_from_insertion[up_from_insertion.size() - 2]) {
    up_from_origin.pop_back();
    up_from_insertion.pop_back();
  }
  std::vector<int> path = up_from_origin;
  if (!up_from_insertion.empty() && !up_from_origin.empty() && up_from_insertion.back() == up_from_origin.back())
    up_from_insertion.pop_back();
  path.insert(path.end(), up_from_insertion.begin(), up_from_insertion.end());
  std::sort(path.begin(), path.end());
  path.erase(std::unique(path.begin(), path.end()), path.end());
  return path;
}

MuscleShares muscleShares(const Skeleton& skeleton, const MeshPart& part, const SurfaceGraph& surface, const MuscleSet& muscles,
                          const std::vector<double>& radii, const MuscleWeightOptions& options) {
  assert(radii.size() == muscles.parts.size());
  std::vector<Eigen::Vector3d> welded_position(surface.weldedCount());
  for (int v = static_cast<int>(part.positions.size()) - 1; v >= 0; --v) welded_position[surface.weld_of_vertex[v]] = part.positions[v];
  MuscleShares share(muscles.parts.size());
  for (size_t m = 0; m < muscles.parts.size(); ++m) {
    const MusclePart& muscle = muscles.parts[m];
    share[m].assign(surface.weldedCount(), 0.0);
    // A muscle drives the skin on its own side of the limb (its belly's side, the rest up axis): a bulge
    // that moved the whole circumference would only shift the limb, pushing its far side in. A
    // corrective drives the blended skin around its span, all of it.
    const bool corrective = muscle.kind == PartKind::kCorrective;
    const std::vector<double> blend = corrective ? blendFactors(skeleton, part, surface, muscle.insertion.joint, options)
                                                 : std::vector<double>();
    const Eigen::Vector3d up = muscleRestFrame(muscle, skeleton).up;
    for (int w = 0; w < surface.weldedCount(); ++w) {
      const Eigen::Vector3d& p = welded_position[w];
      const Eigen::Vector3d closest = closestOnSegment(p, muscle.origin.world, muscle.insertion.world);
      const Eigen::Vector3d away = p - closest;
      const double facing = away.norm() > 0.0 ? away.normalized().dot(up) : 1.0;
      share[m][w] = options.peak_share * falloff(away.norm(), radii[m]) * (corrective ? 1.0 : sideFactor(facing, options));
    }
    smooth(&share[m], surface, options);
    // After the smoothing, so that a corrective moves no skin its carrier holds alone (skin that plain
    // skinning does not stretch); the blend factor is as smooth as the input's weights are.
    if (corrective) {
      for (int w = 0; w < surface.weldedCount(); ++w) share[m][w] *= blend[w];
    }
  }
  return share;
}

void chooseCarrierJoints(const Character& character, const std::vector<SurfaceGraph>& surfaces,
                         const std::vector<MuscleShares>& shares, MuscleSet* muscles) {
  const Skeleton& skeleton = character.skeleton;
  for (size_t m = 0; m < muscles->parts.size(); ++m) {
    MusclePart& muscle = muscles->parts[m];
    if (muscle.carrier >= 0) continue;
    std::vector<double> mass(skeleton.size(), 0.0);
    std::vector<char> spans(skeleton.size(), 0);
    for (int joint : spannedJoints(skeleton, muscle)) spans[joint] = 1;
    size_t p = 0;
    for (const MeshPart& part : character.meshes) {
      if (!part.skinned || part.positions.empty()) continue;
      const std::vector<double>& share = shares[p][m];
      const std::vector<int>& weld = surfaces[p].weld_of_vertex;
      ++p;
      const int slots = part.influences_per_vertex;
      for (size_t v = 0; v < part.positions.size(); ++v) {
        const double s = share[weld[v]];
        if (s <= 0.0) continue;
        for (int k = 0; k < slots; ++k) {
          const int joint = part.joints[v * slots + k];
          if (spans[joint]) mass[joint] += s * part.weights[v * slots + k];
        }
      }
    }
    int best = muscle.origin.joint;
    double best_mass = 0.0;
    for (int j = 0; j < skeleton.size(); ++j) {
      if (mass[j] > best_mass) {
        best_mass = mass[j];
        best = j;
      }
    }
    muscle.carrier = best;
  }
}

InfluenceSet addMuscleInfluences(const InfluenceSet& base, const SurfaceGraph& surface, const MuscleShares& shares,
                                 const MuscleSet& muscles, const std::vector<int>& muscle_joints,
                                 const MuscleWeightOptions& options) {
  assert(muscle_joints.size() == muscles.parts.size() && shares.size() == muscles.parts.size());
  const int vertex_count = base.vertexCount();
  const int muscle_count = static_cast<int>(muscles.parts.size());

  std::vector<std::vector<std::pair<int, double>>> rows(vertex_count);
  int widest = 0;
  for (int v = 0; v < vertex_count; ++v) {
    const int weld = surface.weld_of_vertex[v];
    // The strongest muscles here, as many as the influence budget leaves room for (ties: file order).
    int existing = 0;
    for (int k = 0; k < base.slots_per_vertex; ++k) existing += base.weights[v * base.slots_per_vertex + k] > 0.0;
    std::vector<int> order;
    for (int m = 0; m < muscle_count; ++m) {
      if (shares[m][weld] > 0.0) order.push_back(m);
    }
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return shares[a][weld] > shares[b][weld]; });
    const size_t room = static_cast<size_t>(std::max(0, options.max_influences - existing));
    std::vector<double> share_here(muscle_count, 0.0);
    for (size_t i = 0; i < order.size() && i < room; ++i) share_here[order[i]] = shares[order[i]][weld];
    std::vector<double> taken(muscle_count, 0.0);
    std::vector<std::pair<int, double>>& row = rows[v];
    for (int k = 0; k < base.slots_per_vertex; ++k) {
      const int joint = base.joints[v * base.slots_per_vertex + k];
      const double weight = base.weights[v * base.slots_per_vertex + k];
      if (weight <= 0.0) continue;
      // The muscles riding this joint share at most max_total_share of its weight here.
      double total = 0.0;
      for (int m = 0; m < muscle_count; ++m) {
        if (muscles.parts[m].carrier == joint) total += share_here[m];
      }
      const double limit = total > options.max_total_share ? options.max_total_share / total : 1.0;
      double given = 0.0;
      for (int m = 0; m < muscle_count; ++m) {
        if (muscles.parts[m].carrier != joint || share_here[m] <= 0.0) continue;
        const double amount = weight * share_here[m] * limit;
        taken[m] += amount;
        given += amount;
      }
      if (weight - given > 0.0) row.emplace_back(joint, weight - given);
    }
    for (int m = 0; m < muscle_count; ++m) {
      if (taken[m] > 0.0) row.emplace_back(muscle_joints[m], taken[m]);
    }
    widest = std::max(widest, static_cast<int>(row.size()));
  }
  InfluenceSet result;
  result.slots_per_vertex = std::max(widest, base.slots_per_vertex);
  result.joints.assign(static_cast<size_t>(vertex_count) * result.slots_per_vertex, 0);
  result.weights.assign(result.joints.size(), 0.0);
  for (int v = 0; v < vertex_count; ++v) {
    for (size_t k = 0; k < rows[v].size(); ++k) {
      result.joints[v * result.slots_per_vertex + k] = rows[v][k].first;
      result.weights[v * result.slots_per_vertex + k] = rows[v][k].second;
    }
  }
  return result;
}

}  // namespace rigbake
