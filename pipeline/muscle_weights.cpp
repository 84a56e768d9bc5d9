// Muscle skin weights. Falloff around the origin-insertion segment: the smooth compact kernel
// (1 - x^2)^2, x = distance / radius (Wendland-like; C1 at the rim). Smoothing: the umbrella operator,
// Taubin, "A Signal Processing Approach to Fair Surface Design" (SIGGRAPH 1995), first pass only: on a
// weight field it only blurs, so no shrink compensation is needed.
#include "pipeline/muscle_weights.h"

#include "pipeline/muscle_joint.h"
#include "pipeline/parallel.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace rigbake {
namespace {

// Where `p` projects on the line through segment ab: 0 at a, 1 at b, beyond them outside [0, 1].
double alongSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length_squared = ab.squaredNorm();
  return length_squared > 0 ? (p - a).dot(ab) / length_squared : 0.5;
}

// The point of segment ab at `along` (alongSegment()), clamped to the segment.
Eigen::Vector3d pointOnSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double along) {
  return a + (b - a) * std::clamp(along, 0.0, 1.0);
}

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (p - pointOnSegment(a, b, alongSegment(p, a, b))).norm();
}

// Smoothstep from facing_start (no share) to facing_full (all of it) on the cosine between the
// vertex's direction from the muscle's axis and the muscle's up axis.
double sideFactor(double facing, const MuscleWeightOptions& options) {
  const double x = std::clamp((facing - options.facing_start) / (options.facing_full - options.facing_start), 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// A muscle's belly bulges; over its tendons, at its ends, the skin moves with the bones they attach to,
// which the muscle's skinned joint (riding one carrier joint) does not follow. So the share is all of
// it over the belly and fades by a smoothstep over the last `tendon_fraction` of the origin-insertion
// segment at each end, none beyond either end (where the falloff's round end caps reach without it).
// `along`: the vertex's position projected on the segment, 0 at the origin, 1 at the insertion.
double tendonFactor(double along, double tendon_fraction) {
  if (tendon_fraction <= 0.0) return 1.0;
  auto rise = [&](double x) {
    x = std::clamp(x / tendon_fraction, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
  };
  return rise(along) * rise(1.0 - along);
}

// How far from all of a vertex's weight its strongest joint may be and still hold it alone: the 0.001
// rounding of stored weights.
constexpr double kRigidWeightTolerance = 1e-3;

double falloff(double distance, double radius) {
  if (radius <= 0 || distance >= radius) return 0.0;
  double x = distance / radius;
  return (1.0 - x * x) * (1.0 - x * x);
}

// One muscle's share field over the welded vertices, kept from muscle to muscle by a worker. `field`
// and `next` are zero outside `active`, the vertices whose share may be above 0.
struct ShareScratch {
  std::vector<double> field, next;
  std::vector<int> active, grown;
  std::vector<int> stamp;  // the pass a vertex last joined `grown` in
  int pass = 0;
};

// Umbrella passes next = f + lambda (mean of the one-ring - f). A vertex whose one-ring and itself are
// all 0 stays exactly 0, so each pass updates only the vertices within one ring of the field's support;
// the others would be recomputed to the same 0.
void smooth(const SurfaceGraph& surface, const MuscleWeightOptions& options, ShareScratch* scratch) {
  std::vector<double>& field = scratch->field;
  std::vector<double>& next = scratch->next;
  for (int pass = 0; pass < options.smoothing_iterations; ++pass) {
    // The support grows by one ring per pass: next is written on all of it, so what it held two passes
    // ago (a subset) is overwritten.
    ++scratch->pass;
    scratch->grown.clear();
    auto grow = [&](int w) {
      if (scratch->stamp[w] == scratch->pass) return;
      scratch->stamp[w] = scratch->pass;
      scratch->grown.push_back(w);
    };
    for (int w : scratch->active) {
      grow(w);
      for (std::uint32_t k = surface.first_neighbour[w]; k < surface.first_neighbour[w + 1]; ++k) grow(surface.neighbours[k]);
    }
    for (int w : scratch->grown) {
      const std::uint32_t begin = surface.first_neighbour[w], end = surface.first_neighbour[w + 1];
      if (begin == end) {
        next[w] = field[w];
        continue;
      }
      double mean = 0.0;
      for (std::uint32_t k = begin; k < end; ++k) mean += field[surface.neighbours[k]];
      mean /= static_cast<double>(end - begin);
      next[w] = field[w] + options.smoothing_lambda * (mean - field[w]);
    }
    field.swap(next);
    scratch->active.swap(scratch->grown);
  }
}

// Per welded vertex, min(1, gain * 4 x (1 - x)) with x the share of its weight on `joint` and the joints
// below it (its first part vertex's weights: split vertices carry the same).
std::vector<double> blendFactors(const std::vector<int>& parents, const MeshPart& part, const SurfaceGraph& surface,
                                 int joint, const MuscleWeightOptions& options) {
  std::vector<char> below(parents.size(), 0);
  for (size_t j = 0; j < parents.size(); ++j) {
    for (int a = static_cast<int>(j); a >= 0 && !below[j]; a = parents[a]) below[j] = a == joint;
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

std::vector<double> muscleWeightRadii(const Character& character, const MuscleSet& muscles, double body_height,
                                      int threads) {
  std::vector<double> radii(muscles.parts.size());
  parallelForEach(threads, muscles.parts.size(), [&](size_t m) {
    const MusclePart& muscle = muscles.parts[m];
    const double base = muscleWeightRadius(muscle, body_height);
    if (muscle.weight_radius > 0) {
      radii[m] = base;
      return;
    }
    // Only skin the muscle could take weight from counts: vertices weighted to a joint it spans.
    std::vector<char> spans(character.skeleton.size(), 0);
    for (int joint : spannedJoints(spannedHierarchy(muscles, character.skeleton), muscle)) spans[joint] = 1;
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
    radii[m] = std::isfinite(nearest) ? std::max(base, nearest + 0.5 * base) : base;
  });
  return radii;
}

std::vector<char> rigidPieces(const MeshPart& part, const SurfaceGraph& surface) {
  const int welded_count = surface.weldedCount();
  const int slots = part.influences_per_vertex;
  // The one joint holding each welded vertex alone, -1 where none does (-2: not seen yet).
  std::vector<int> sole(welded_count, -2);
  for (size_t v = 0; v < part.positions.size(); ++v) {
    double total = 0.0, largest = 0.0;
    int joint = -1;
    for (int k = 0; k < slots; ++k) {
      const double weight = part.weights[v * slots + k];
      total += weight;
      if (weight > largest) {
        largest = weight;
        joint = part.joints[v * slots + k];
      }
    }
    const int holder = total > 0.0 && largest >= (1.0 - kRigidWeightTolerance) * total ? joint : -1;
    // Split copies of a welded vertex (UV seams) must agree on their holder.
    int& welded = sole[surface.weld_of_vertex[v]];
    welded = welded == -2 || welded == holder ? holder : -1;
  }
  // Pieces: connected components of the welded graph, each flooded once.
  std::vector<char> rigid(welded_count, 0);
  std::vector<char> seen(welded_count, 0);
  std::vector<int> stack, members;
  for (int start = 0; start < welded_count; ++start) {
    if (seen[start]) continue;
    members.clear();
    stack.assign(1, start);
    seen[start] = 1;
    bool is_rigid = sole[start] >= 0;
    while (!stack.empty()) {
      const int w = stack.back();
      stack.pop_back();
      members.push_back(w);
      is_rigid = is_rigid && sole[w] == sole[start];
      for (std::uint32_t k = surface.first_neighbour[w]; k < surface.first_neighbour[w + 1]; ++k) {
        const int u = surface.neighbours[k];
        if (!seen[u]) {
          seen[u] = 1;
          stack.push_back(u);
        }
      }
    }
    if (is_rigid)
      for (int w : members) rigid[w] = 1;
  }
  return rigid;
}

std::vector<int> spannedJoints(const std::vector<int>& parents, const MusclePart& part) {
  std::vector<int> up_from_origin, up_from_insertion;
  for (int j = part.origin.joint; j >= 0; j = parents[j]) up_from_origin.push_back(j);
  for (int j = part.insertion.joint; j >= 0; j = parents[j]) up_from_insertion.push_back(j);
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
                          const std::vector<double>& radii, const MuscleWeightOptions& options, int threads) {
  assert(radii.size() == muscles.parts.size());
  const int welded_count = surface.weldedCount();
  std::vector<Eigen::Vector3d> welded_position(welded_count);
  for (int v = static_cast<int>(part.positions.size()) - 1; v >= 0; --v) welded_position[surface.weld_of_vertex[v]] = part.positions[v];
  const size_t muscle_count = muscles.parts.size();
  std::vector<char> rigid =
      options.rigid_pieces_stay_rigid ? rigidPieces(part, surface) : std::vector<char>(static_cast<size_t>(welded_count), 0);
  // Each muscle's shares above 0, welded vertices ascending.
  std::vector<std::vector<std::pair<int, double>>> per_muscle(muscle_count);
  std::vector<ShareScratch> scratch(std::max<size_t>(1, parallelWorkerCount(threads, muscle_count, 1)));
  parallelForWorkers(threads, muscle_count, 1, [&](size_t worker, size_t, size_t m, size_t) {
    ShareScratch& work = scratch[worker];
    if (work.field.size() != static_cast<size_t>(welded_count)) {
      work.field.assign(welded_count, 0.0);
      work.next.assign(welded_count, 0.0);
      work.stamp.assign(welded_count, 0);
    }
    const MusclePart& muscle = muscles.parts[m];
    // A muscle drives the skin on its own side of the limb (its belly's side, the rest up axis): a bulge
    // that moved the whole circumference would only shift the limb, pushing its far side in. A
    // corrective drives the blended skin around its span, all of it.
    const bool corrective = muscle.kind == PartKind::kCorrective;
    const std::vector<double> blend =
        corrective ? blendFactors(spannedHierarchy(muscles, skeleton), part, surface, muscle.insertion.joint, options)
                   : std::vector<double>();
    const Eigen::Vector3d up = muscleRestFrame(muscle, skeleton).up;
    // Vertices outside the segment's box widened by the radius are farther than the radius from it:
    // falloff 0. (Widened a little more, so that a distance rounded down to the radius still counts.)
    const double reach = radii[m] * (1.0 + 1e-9) + 1e-12;
    const Eigen::Vector3d low = muscle.origin.world.cwiseMin(muscle.insertion.world).array() - reach;
    const Eigen::Vector3d high = muscle.origin.world.cwiseMax(muscle.insertion.world).array() + reach;
    work.active.clear();
    for (int w = 0; w < welded_count; ++w) {
      if (rigid[w]) continue;
      const Eigen::Vector3d& p = welded_position[w];
      if ((p.array() < low.array()).any() || (p.array() > high.array()).any()) continue;
      // One projection on the segment for the distance across it and the place along it.
      const double along = alongSegment(p, muscle.origin.world, muscle.insertion.world);
      const Eigen::Vector3d away = p - pointOnSegment(muscle.origin.world, muscle.insertion.world, along);
      const double facing = away.norm() > 0.0 ? away.normalized().dot(up) : 1.0;
      const double tendon = tendonFactor(along, options.tendon_fraction);
      const double share = options.peak_share * falloff(away.norm(), radii[m]) * (corrective ? 1.0 : sideFactor(facing, options) * tendon);
      if (share == 0.0) continue;
      work.field[w] = share;
      work.active.push_back(w);
    }
    smooth(surface, options, &work);
    std::sort(work.active.begin(), work.active.end());
    // After the smoothing, a corrective's share is scaled by its blend factor, so that it moves no skin
    // its carrier holds alone (skin that plain skinning does not stretch); the blend factor is as smooth
    // as the input's weights are.
    for (int w : work.active) {
      const double value = work.field[w] * (corrective ? blend[w] : 1.0);
      if (value > 0.0) per_muscle[m].emplace_back(w, value);
      work.field[w] = work.next[w] = 0.0;
    }
  });
  MuscleShares shares;
  shares.first.assign(static_cast<size_t>(welded_count) + 1, 0);
  for (const auto& list : per_muscle)
    for (const auto& [w, value] : list) ++shares.first[static_cast<size_t>(w) + 1];
  for (int w = 0; w < welded_count; ++w) shares.first[w + 1] += shares.first[w];
  shares.muscle.resize(shares.first.back());
  shares.share.resize(shares.first.back());
  std::vector<std::uint32_t> fill(shares.first.begin(), shares.first.end() - 1);
  for (size_t m = 0; m < muscle_count; ++m) {
    for (const auto& [w, value] : per_muscle[m]) {
      shares.muscle[fill[w]] = static_cast<int>(m);
      shares.share[fill[w]++] = value;
    }
  }
  shares.rigid = std::move(rigid);
  return shares;
}

void chooseCarrierJoints(const Character& character, const BodySurface& body, const MuscleShares& shares,
                         MuscleSet* muscles) {
  const Skeleton& skeleton = character.skeleton;
  const size_t muscle_count = muscles->parts.size();
  const size_t joint_count = static_cast<size_t>(skeleton.size());
  // mass[m][j]: the weight of joint j under muscle m's share field, summed vertex by vertex (part after
  // part) and slot by slot, over the joints the muscle spans (the order of each sum is the order a
  // muscle-by-muscle loop would take). Each welded vertex weighs once, at its first copy: UV seams and the
  // borders of a character built from several meshes copy vertices, and a split into more meshes copies
  // more, which must not tip a near tie (measured on CesiumMan: its right latissimus carried by the torso
  // where the left one rides the upper arm, and 0.34 of a vertex's weight moved by a split).
  std::vector<double> mass(muscle_count * joint_count, 0.0);
  std::vector<char> spans(muscle_count * joint_count, 0);
  const std::vector<int>& parents = spannedHierarchy(*muscles, skeleton);
  for (size_t m = 0; m < muscle_count; ++m)
    for (int joint : spannedJoints(parents, muscles->parts[m])) spans[m * joint_count + static_cast<size_t>(joint)] = 1;
  const MeshPart& skin = body.skin(character);
  const std::vector<int>& weld = body.graph.weld_of_vertex;
  const int slots = skin.influences_per_vertex;
  std::vector<char> counted(static_cast<size_t>(body.graph.weldedCount()), 0);
  for (size_t v = 0; v < skin.positions.size(); ++v) {
    const int w = weld[v];
    if (counted[w]) continue;
    counted[w] = 1;
    for (std::uint32_t i = shares.first[w]; i < shares.first[w + 1]; ++i) {
      const size_t m = static_cast<size_t>(shares.muscle[i]);
      const double s = shares.share[i];
      if (s <= 0.0 || muscles->parts[m].carrier >= 0) continue;
      for (int k = 0; k < slots; ++k) {
        const size_t joint = static_cast<size_t>(skin.joints[v * slots + k]);
        if (spans[m * joint_count + joint]) mass[m * joint_count + joint] += s * skin.weights[v * slots + k];
      }
    }
  }
  for (size_t m = 0; m < muscle_count; ++m) {
    MusclePart& muscle = muscles->parts[m];
    if (muscle.carrier >= 0) continue;
    int best = muscle.origin.joint;
    double best_mass = 0.0;
    for (size_t j = 0; j < joint_count; ++j) {
      if (mass[m * joint_count + j] > best_mass) {
        best_mass = mass[m * joint_count + j];
        best = static_cast<int>(j);
      }
    }
    muscle.carrier = best;
  }
}

InfluenceSet addMuscleInfluences(const InfluenceSet& base, const SurfaceGraph& surface, const MuscleShares& shares,
                                 const MuscleSet& muscles, const std::vector<int>& muscle_joints,
                                 const MuscleWeightOptions& options, int threads) {
  assert(muscle_joints.size() == muscles.parts.size());
  const int vertex_count = base.vertexCount();
  const int muscle_count = static_cast<int>(muscles.parts.size());

  // Each vertex's row of (joint, weight), one after another; per vertex only its muscles are touched
  // (the sums skip the others' zero shares, which add nothing). Chunks of vertices in parallel, each
  // with its own rows: every vertex's row is the same at any thread count.
  constexpr size_t kVerticesPerChunk = 8192;
  struct ChunkRows {
    std::vector<std::pair<int, double>> rows;
    std::vector<std::uint32_t> first_of_row;  // per vertex of the chunk, and one past the last
    int widest = 0;
  };
  std::vector<ChunkRows> chunks(parallelChunkCount(static_cast<size_t>(vertex_count), kVerticesPerChunk));
  parallelFor(threads, static_cast<size_t>(vertex_count), kVerticesPerChunk, [&](size_t chunk, size_t begin, size_t end) {
    ChunkRows& out = chunks[chunk];
    std::vector<std::pair<int, double>>& rows = out.rows;
    out.first_of_row.assign(end - begin + 1, 0);
    std::vector<double> share_here(static_cast<size_t>(muscle_count), 0.0), taken(static_cast<size_t>(muscle_count), 0.0);
    std::vector<int> order;
    for (int v = static_cast<int>(begin); v < static_cast<int>(end); ++v) {
      const int weld = surface.weld_of_vertex[v];
      const std::uint32_t shares_begin = shares.first[weld], shares_end = shares.first[weld + 1];
      // The strongest muscles here, as many as the influence budget leaves room for (ties: file order).
      int existing = 0;
      for (int k = 0; k < base.slots_per_vertex; ++k) existing += base.weights[v * base.slots_per_vertex + k] > 0.0;
      order.clear();
      for (std::uint32_t i = shares_begin; i < shares_end; ++i) {
        if (shares.share[i] > 0.0) order.push_back(static_cast<int>(i));
      }
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return shares.share[a] > shares.share[b]; });
      const size_t room = static_cast<size_t>(std::max(0, options.max_influences - existing));
      for (size_t i = 0; i < order.size() && i < room; ++i) share_here[shares.muscle[order[i]]] = shares.share[order[i]];
      const size_t row_begin = rows.size();
      for (int k = 0; k < base.slots_per_vertex; ++k) {
        const int joint = base.joints[v * base.slots_per_vertex + k];
        const double weight = base.weights[v * base.slots_per_vertex + k];
        if (weight <= 0.0) continue;
        // The muscles riding this joint share at most max_total_share of its weight here.
        double total = 0.0;
        for (std::uint32_t i = shares_begin; i < shares_end; ++i) {
          const int m = shares.muscle[i];
          if (muscles.parts[m].carrier == joint) total += share_here[m];
        }
        const double limit = total > options.max_total_share ? options.max_total_share / total : 1.0;
        double given = 0.0;
        for (std::uint32_t i = shares_begin; i < shares_end; ++i) {
          const int m = shares.muscle[i];
          if (muscles.parts[m].carrier != joint || share_here[m] <= 0.0) continue;
          const double amount = weight * share_here[m] * limit;
          taken[m] += amount;
          given += amount;
        }
        if (weight - given > 0.0) rows.emplace_back(joint, weight - given);
      }
      for (std::uint32_t i = shares_begin; i < shares_end; ++i) {
        const int m = shares.muscle[i];
        if (taken[m] > 0.0) rows.emplace_back(muscle_joints[m], taken[m]);
        share_here[m] = taken[m] = 0.0;
      }
      out.widest = std::max(out.widest, static_cast<int>(rows.size() - row_begin));
      out.first_of_row[static_cast<size_t>(v) - begin + 1] = static_cast<std::uint32_t>(rows.size());
    }
  });
  InfluenceSet result;
  result.slots_per_vertex = base.slots_per_vertex;
  for (const ChunkRows& chunk : chunks) result.slots_per_vertex = std::max(result.slots_per_vertex, chunk.widest);
  result.joints.assign(static_cast<size_t>(vertex_count) * result.slots_per_vertex, 0);
  result.weights.assign(result.joints.size(), 0.0);
  parallelFor(threads, static_cast<size_t>(vertex_count), kVerticesPerChunk, [&](size_t chunk, size_t begin, size_t end) {
    const ChunkRows& rows = chunks[chunk];
    for (size_t v = begin; v < end; ++v) {
      for (std::uint32_t i = rows.first_of_row[v - begin]; i < rows.first_of_row[v - begin + 1]; ++i) {
        const size_t k = i - rows.first_of_row[v - begin];
        result.joints[v * result.slots_per_vertex + k] = rows.rows[i].first;
        result.weights[v * result.slots_per_vertex + k] = rows.rows[i].second;
      }
    }
  });
  return result;
}

}  // namespace rigbake
