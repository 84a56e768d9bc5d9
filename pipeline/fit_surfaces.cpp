// The response fit's surfaces (pipeline/fit_surfaces.h).
#include "pipeline/fit_surfaces.h"

#include <algorithm>
#include <cassert>
#include <limits>

#include "pipeline/occupied_volume.h"
#include "pipeline/parallel.h"
#include "pipeline/skin_volume.h"

namespace rigbake {
namespace {

// A triangle any fitted muscle moves: one of its corners carries a fitted muscle's weight.
bool movesWithFit(const std::array<int, 3>& t, const std::vector<char>& fitted) {
  return fitted[t[0]] || fitted[t[1]] || fitted[t[2]];
}

SplitPatch splitPatch(const ClosedPatch& patch, const std::vector<char>& fitted) {
  SplitPatch out;
  if (patch.triangles.empty()) return out;
  out.first_vertex = patch.triangles[0][0];
  for (const auto& t : patch.triangles) (movesWithFit(t, fitted) ? out.moving : out.fixed).triangles.push_back(t);
  for (const std::vector<int>& hole : patch.holes) {
    const bool moves = std::any_of(hole.begin(), hole.end(), [&](int w) { return fitted[w] != 0; });
    (moves ? out.moving : out.fixed).holes.push_back(hole);
  }
  return out;
}

// The whole surface's triangles no fitted muscle moves (its fixed piece in splitPatch()), closed by
// caps over the loops where they meet the rest (and the surface's own holes among them): a closed
// piece, so its volume does not depend on where the body stands, and no response changes it.
ClosedPatch unreachedPiece(const VolumeSurface& surface, const std::vector<char>& fitted) {
  std::vector<int> triangles;
  for (size_t t = 0; t < surface.whole.triangles.size(); ++t)
    if (!movesWithFit(surface.whole.triangles[t], fitted)) triangles.push_back(static_cast<int>(t));
  return closePatch(surface, triangles);
}

// What findRim() needs of the whole surface's moving piece, the same for every region: each moving
// vertex's triangle count, whether it is on a hole, and whether its fan's far edges (b -> c for each
// triangle (v, b, c)) close: sum (c - b) = 0 whatever the positions, checked by sorting the fan's
// starts and ends. Formed once per part instead of once per region (at 100k vertices and 17 regions
// that was 3.8 million small vectors).
struct WholeFans {
  std::vector<int> triangle_count;
  std::vector<char> open;  // on a hole of the whole surface, or a fan that does not close
};

WholeFans wholeFans(const SplitPatch& whole, size_t moving_count) {
  WholeFans fans;
  fans.triangle_count.assign(moving_count, 0);
  fans.open.assign(moving_count, 0);
  for (const auto& t : whole.moving.triangles) {
    for (int w : t) ++fans.triangle_count[static_cast<size_t>(w)];
  }
  for (const std::vector<int>& hole : whole.moving.holes) {
    for (int w : hole) fans.open[static_cast<size_t>(w)] = 1;
  }
  // Each vertex's starts and ends, flat (CSR by vertex), sorted per vertex and compared.
  std::vector<size_t> first(moving_count + 1, 0);
  for (size_t c = 0; c < moving_count; ++c) first[c + 1] = first[c] + static_cast<size_t>(fans.triangle_count[c]);
  std::vector<int> starts(first.back()), ends(first.back());
  std::vector<size_t> next(first.begin(), first.end() - 1);
  for (const auto& t : whole.moving.triangles) {
    for (int k = 0; k < 3; ++k) {
      const size_t c = static_cast<size_t>(t[k]);
      starts[next[c]] = t[(k + 1) % 3];
      ends[next[c]++] = t[(k + 2) % 3];
    }
  }
  for (size_t c = 0; c < moving_count; ++c) {
    std::sort(starts.begin() + static_cast<std::ptrdiff_t>(first[c]), starts.begin() + static_cast<std::ptrdiff_t>(first[c + 1]));
    std::sort(ends.begin() + static_cast<std::ptrdiff_t>(first[c]), ends.begin() + static_cast<std::ptrdiff_t>(first[c + 1]));
    if (!std::equal(starts.begin() + static_cast<std::ptrdiff_t>(first[c]), starts.begin() + static_cast<std::ptrdiff_t>(first[c + 1]),
                    ends.begin() + static_cast<std::ptrdiff_t>(first[c])))
      fans.open[c] = 1;
  }
  return fans;
}

// Splits a piece's fitted vertices into inner ones and the rim (SplitPatch), after renumberMoving():
// `fans` are the whole surface's (wholeFans()), `moving_count` the part's moving vertices. A vertex is
// inner when it has as many triangles in the region as in the whole surface (the region's are among
// them), is on no hole of either, and its fan closes.
void findRim(const WholeFans& fans, size_t moving_count, SplitPatch* region) {
  std::vector<int> region_count(moving_count, 0);
  for (const auto& t : region->moving.triangles) {
    for (int w : t) ++region_count[static_cast<size_t>(w)];
  }
  std::vector<char> inner(moving_count, 1);
  for (const std::vector<int>& hole : region->moving.holes) {
    for (int w : hole) inner[static_cast<size_t>(w)] = 0;
  }
  for (int w : region->fitted) {
    const size_t c = static_cast<size_t>(w);
    if (fans.open[c] || fans.triangle_count[c] != region_count[c]) inner[c] = 0;
  }
  std::vector<char> on_rim(moving_count, 0);
  for (int w : region->fitted) {
    if (inner[static_cast<size_t>(w)]) {
      region->inner_fitted.push_back(w);
    } else {
      region->rim_fitted.push_back(w);
      on_rim[static_cast<size_t>(w)] = 1;
    }
  }
  for (const auto& t : region->moving.triangles) {
    if (on_rim[static_cast<size_t>(t[0])] || on_rim[static_cast<size_t>(t[1])] || on_rim[static_cast<size_t>(t[2])])
      region->rim.triangles.push_back(t);
  }
  region->rim.holes = region->moving.holes;
  region->rim_touched = patchVertices(region->rim, moving_count);
}

// Renumbers a moving piece's welded indices to moving-vertex indices (moving_count of them) and lists
// the ones it touches.
void renumberMoving(const std::vector<int>& moving_of_weld, size_t moving_count, SplitPatch* split) {
  for (auto& t : split->moving.triangles) {
    for (int& w : t) w = moving_of_weld[w];
  }
  for (std::vector<int>& hole : split->moving.holes) {
    for (int& w : hole) w = moving_of_weld[w];
  }
  split->touched = patchVertices(split->moving, moving_count);
  split->moving_holes.holes = split->moving.holes;
}

// Each lane's bind position (zero for an empty lane).
std::vector<Eigen::Vector3d> bindOfLane(const SkinningBatch& batch, const std::vector<Eigen::Vector3d>& bind_positions) {
  std::vector<Eigen::Vector3d> out(batch.vertex.size(), Eigen::Vector3d::Zero());
  for (size_t lane = 0; lane < batch.vertex.size(); ++lane) {
    if (batch.vertex[lane] >= 0) out[lane] = bind_positions[static_cast<size_t>(batch.vertex[lane])];
  }
  return out;
}

// The lane -> index map of a batch built over `vertices` (indices into a part's vertices).
std::vector<int> indexOfLane(const SkinningBatch& batch, const std::vector<int>& vertices, size_t part_vertex_count) {
  std::vector<int> index_of_vertex(part_vertex_count, -1);
  for (size_t i = 0; i < vertices.size(); ++i) index_of_vertex[static_cast<size_t>(vertices[i])] = static_cast<int>(i);
  std::vector<int> out(batch.vertex.size(), -1);
  for (size_t lane = 0; lane < batch.vertex.size(); ++lane) {
    if (batch.vertex[lane] >= 0) out[lane] = index_of_vertex[static_cast<size_t>(batch.vertex[lane])];
  }
  return out;
}

// Each welded vertex's fitted-muscle slots, flat: welded w has slots[first[w] .. first[w + 1]).
struct WeldSlots {
  std::vector<MuscleVertex> slots;
  std::vector<int> first;
  std::vector<char> fitted;  // per welded vertex: it has a slot
};

WeldSlots weldSlots(const VolumeSurface& surface, const MeshPart& mesh, const InfluenceSet& rig, int joint_count,
                    const std::vector<int>& kind, const std::vector<Eigen::Affine3d>& bind_inverse) {
  const int muscle_count = static_cast<int>(kind.size());
  WeldSlots out;
  out.first.assign(static_cast<size_t>(surface.weldedCount()) + 1, 0);
  out.fitted.assign(surface.weldedCount(), 0);
  for (int w = 0; w < surface.weldedCount(); ++w) {
    const int v = surface.vertex_of_weld[w];
    for (int k = 0; k < rig.slots_per_vertex; ++k) {
      const int m = rig.joints[v * rig.slots_per_vertex + k] - joint_count;
      const double weight = rig.weights[v * rig.slots_per_vertex + k];
      if (m < 0 || m >= muscle_count || kind[m] < 0 || weight <= 0.0) continue;
      out.slots.push_back({m, weight, bind_inverse[m] * mesh.positions[v]});
    }
    out.first[static_cast<size_t>(w) + 1] = static_cast<int>(out.slots.size());
    out.fitted[w] = out.first[w + 1] != out.first[w];
  }
  return out;
}

// The part's moving vertices (every vertex of a moving piece, in welded order) with their muscle slots;
// returns each welded vertex's moving index (-1 when it does not move) and renumbers the pieces to it.
std::vector<int> gatherMovingVertices(const VolumeSurface& surface, const WeldSlots& weld, FitPart* part) {
  std::vector<char> moving(surface.weldedCount(), 0);
  for (const SplitPatch& split : part->patches) {
    for (const auto& t : split.moving.triangles) {
      for (int w : t) moving[w] = 1;
    }
    for (const std::vector<int>& hole : split.moving.holes) {
      for (int w : hole) moving[w] = 1;
    }
  }
  std::vector<int> moving_of_weld(surface.weldedCount(), -1);
  part->first_share.push_back(0);
  for (int w = 0; w < surface.weldedCount(); ++w) {
    if (!moving[w]) continue;
    moving_of_weld[w] = static_cast<int>(part->moving_vertices.size());
    part->moving_vertices.push_back(surface.vertex_of_weld[w]);
    part->muscle_slots.insert(part->muscle_slots.end(), weld.slots.begin() + weld.first[w], weld.slots.begin() + weld.first[w + 1]);
    part->first_share.push_back(static_cast<int>(part->muscle_slots.size()));
  }
  for (SplitPatch& split : part->patches) renumberMoving(moving_of_weld, part->moving_vertices.size(), &split);
  for (SplitPatch& split : part->patches) {
    for (int c : split.touched) {
      if (part->hasSlots(c)) split.fitted.push_back(c);
    }
  }
  return moving_of_weld;
}

// Each region's moving triangles as indices into the whole surface's moving piece (the region's patch
// holds the surface triangles of its part triangles, in order: measuredSurfaces()), and every piece's
// rim. `part_index` is the part's place in the regions' triangle lists, `kept` the measured regions.
void findRegionTrianglesAndRims(const VolumeSurface& surface, const std::vector<char>& fitted, const std::vector<BodyRegion>& regions,
                                const std::vector<size_t>& kept, size_t part_index, FitPart* part) {
  const WholeFans fans = wholeFans(part->patches[0], part->moving_vertices.size());
  findRim(fans, part->moving_vertices.size(), &part->patches[0]);
  std::vector<int> whole_of_part(part->mesh->triangles.size(), -1);
  for (size_t t = 0; t < surface.part_triangle.size(); ++t) whole_of_part[surface.part_triangle[t]] = static_cast<int>(t);
  std::vector<int> moving_index(surface.whole.triangles.size(), -1);
  int next = 0;
  for (size_t t = 0; t < surface.whole.triangles.size(); ++t) {
    const auto& w = surface.whole.triangles[t];
    if (fitted[w[0]] || fitted[w[1]] || fitted[w[2]]) moving_index[t] = next++;
  }
  for (size_t k = 0; k < kept.size(); ++k) {
    SplitPatch& split = part->patches[k + 1];
    if (part_index < regions[kept[k]].triangles.size()) {
      for (int t : regions[kept[k]].triangles[part_index]) {
        if (whole_of_part[t] >= 0 && moving_index[whole_of_part[t]] >= 0) split.whole_triangles.push_back(moving_index[whole_of_part[t]]);
      }
    }
    assert(split.whole_triangles.size() == split.moving.triangles.size());
    findRim(fans, part->moving_vertices.size(), &split);
  }
}

// The part's two skinning batches (FitPart) and their lane maps.
void buildFitBatches(const VolumeSurface& surface, const MeasuredPart& weights, const Eigen::Vector3d& skin_centre,
                     DualQuaternionPivots* no_pivots, int threads, FitPart* part) {
  const size_t part_vertex_count = part->mesh->positions.size();
  std::array<SetWeights, kSkinSets> welded_sets, moving_sets;
  welded_sets[kWeldedInputSet].plus = &weights.input;
  welded_sets[kWeldedRigSet].plus = &weights.rig;
  moving_sets[0].plus = &weights.rig;
  part->welded_batch = buildSkinningBatch(part->mesh->positions, surface.vertex_of_weld, skin_centre, welded_sets,
                                          std::vector<char>(surface.vertex_of_weld.size(), 0), 0, no_pivots, threads);
  part->welded_of_lane = indexOfLane(part->welded_batch, surface.vertex_of_weld, part_vertex_count);
  part->welded_bind = bindOfLane(part->welded_batch, part->mesh->positions);
  part->moving_batch = buildSkinningBatch(part->mesh->positions, part->moving_vertices, skin_centre, moving_sets,
                                          std::vector<char>(part->moving_vertices.size(), 0), 0, no_pivots, threads);
  part->moving_of_lane = indexOfLane(part->moving_batch, part->moving_vertices, part_vertex_count);
  part->moving_bind = bindOfLane(part->moving_batch, part->mesh->positions);
  std::vector<char> on_rim(part->moving_vertices.size(), 0);
  for (const SplitPatch& split : part->patches) {
    for (int c : split.rim_touched) on_rim[static_cast<size_t>(c)] = 1;
  }
  part->rim_of_lane = part->moving_of_lane;
  for (int& c : part->rim_of_lane) {
    if (c >= 0 && !on_rim[static_cast<size_t>(c)]) c = -1;
  }
}

// The moving vertices some fitted muscle's skin holds, per fit part, with all their muscle slots.
std::vector<std::vector<SkinSlots>> skinSlots(const std::vector<FitPart>& fit_parts, const std::vector<std::vector<SkinVertex>>& muscle_skin,
                                              int joint_count) {
  std::vector<std::vector<SkinSlots>> skin_slots(fit_parts.size());
  std::vector<std::vector<char>> in_skin(fit_parts.size());
  for (size_t p = 0; p < fit_parts.size(); ++p) in_skin[p].assign(fit_parts[p].moving_vertices.size(), 0);
  for (const auto& skin : muscle_skin) {
    for (const SkinVertex& sv : skin) in_skin[sv.part][sv.vertex] = 1;
  }
  for (size_t p = 0; p < fit_parts.size(); ++p) {
    const InfluenceSet& weights = fit_parts[p].weights->rig;
    const int slots = weights.slots_per_vertex;
    for (size_t c = 0; c < in_skin[p].size(); ++c) {
      if (!in_skin[p][c]) continue;
      SkinSlots entry{static_cast<int>(c), {}};
      const int v = fit_parts[p].moving_vertices[c];
      for (int k = 0; k < slots; ++k) {
        const int joint = weights.joints[v * slots + k];
        const double weight = weights.weights[v * slots + k];
        if (joint >= joint_count && weight != 0.0) entry.muscles.emplace_back(joint - joint_count, weight);
      }
      skin_slots[p].push_back(std::move(entry));
    }
  }
  return skin_slots;
}

// What one worker of the pose-only pass reuses from pose to pose.
struct PoseOnlyScratch {
  std::vector<Eigen::Affine3d> frame;
  FloatSkinFrame float_frame;
  std::vector<double> volume;
  std::vector<Eigen::Vector3d> input;
  std::vector<std::vector<Eigen::Vector3d>> parts_welded;  // every part's, for the exposure
};

// The grid of the fit's exposure: columns across the bind body, a 128th of its largest extent apart.
// The exposure only sorts the skin into inside and outside of the folds, so it is coarser than the
// figures' grid (256): at 128 it adds 0.09 s to Cyberpunk's first bake.
OccupancyGrid fitOccupancyGrid(const FitSurfaces& s) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (const FitPart& part : s.parts) {
    for (size_t l = 0; l < part.welded_of_lane.size(); ++l) {
      if (part.welded_of_lane[l] < 0) continue;
      low = low.cwiseMin(part.welded_bind[l]);
      high = high.cwiseMax(part.welded_bind[l]);
    }
  }
  return occupancyGrid(low, high, 128.0);
}

}  // namespace

FitSurfaces buildFitSurfaces(const Character& character, const std::vector<BodyRegion>& regions,
                             const std::vector<MeasuredPart>& parts, const MuscleSet& muscles, const std::vector<int>& kind,
                             const std::vector<Eigen::Affine3d>& bind_inverse, int threads) {
  const int joint_count = character.skeleton.size();
  const int muscle_count = static_cast<int>(muscles.parts.size());
  FitSurfaces out;
  std::vector<int> mesh_parts;
  for (const MeasuredPart& part : parts) mesh_parts.push_back(part.mesh_part);
  std::vector<std::vector<std::vector<int>>> region_triangles;
  for (const BodyRegion& region : regions) region_triangles.push_back(region.triangles);
  out.measured = measuredSurfaces(character, mesh_parts, region_triangles, bodyWeldTolerance(muscles.body_height), threads);
  MeasuredSurfaces& measured = out.measured;
  std::vector<size_t> kept;
  for (size_t r = 0; r < regions.size(); ++r) {
    if (measured.region_measured[r]) kept.push_back(r);
  }
  out.region_count = static_cast<int>(kept.size());
  out.patch_count = 1 + kept.size();
  out.skin_centre = skinCentre(character, parts);
  out.muscle_skin.resize(muscle_count);
  for (size_t p = 0; p < parts.size(); ++p) {
    FitPart part;
    part.mesh = &character.meshes[parts[p].mesh_part];
    part.weights = &parts[p];
    VolumeSurface& surface = measured.surfaces[p];
    for (size_t r : kept) part.regions.push_back(std::move(measured.regions[p][r]));
    const InfluenceSet& rig = parts[p].rig;
    WeldSlots weld = weldSlots(surface, *part.mesh, rig, joint_count, kind, bind_inverse);
    part.patches.push_back(splitPatch(surface.whole, weld.fitted));
    part.unreached = unreachedPiece(surface, weld.fitted);
    out.bind_unreached += enclosedVolume(part.unreached, surface.bind);
    for (const ClosedPatch& region : part.regions) part.patches.push_back(splitPatch(region, weld.fitted));
    const std::vector<int> moving_of_weld = gatherMovingVertices(surface, weld, &part);
    std::vector<MuscleVertex>().swap(weld.slots);
    const std::vector<std::vector<MuscleSkinVertex>> skin = muscleSkin(rig, surface.vertex_of_weld, joint_count, muscle_count);
    for (int m = 0; m < muscle_count; ++m) {
      if (kind[m] < 0) continue;
      for (const MuscleSkinVertex& vertex : skin[static_cast<size_t>(m)]) {
        const int c = moving_of_weld[static_cast<size_t>(vertex.welded)];
        if (c >= 0) out.muscle_skin[static_cast<size_t>(m)].push_back({static_cast<int>(p), c, vertex.weight});
      }
    }
    findRegionTrianglesAndRims(surface, weld.fitted, regions, kept, p, &part);
    buildFitBatches(surface, parts[p], out.skin_centre, &out.no_pivots, threads, &part);
    out.parts.push_back(std::move(part));
  }
  out.skin_slots = skinSlots(out.parts, out.muscle_skin, joint_count);
  out.skin_total.assign(muscle_count, 0.0);
  for (int m = 0; m < muscle_count; ++m) {
    for (const SkinVertex& sv : out.muscle_skin[m]) out.skin_total[m] += sv.weight;
  }
  out.bind_body = measured.body_volume;
  for (size_t r : kept) out.bind_region.push_back(measured.region_volumes[r]);
  return out;
}

void skinningFrame(const Skeleton& skeleton, const Pose& pose, const RigEvaluation& evaluation,
                   const std::vector<Eigen::Affine3d>& bind_inverse, std::vector<Eigen::Affine3d>* frame) {
  const int joint_count = skeleton.size();
  frame->resize(joint_count + bind_inverse.size());
  for (int j = 0; j < joint_count; ++j) (*frame)[j] = skinMatrix(pose, skeleton, j);
  for (size_t m = 0; m < bind_inverse.size(); ++m)
    (*frame)[joint_count + m] = matrixAt(evaluation.skinned, static_cast<int>(m)) * bind_inverse[m];
}

FixedPieces measureFixedPieces(const Skeleton& skeleton, const std::vector<Pose>& poses, const runtime::MuscleRig<double>& rig,
                               const std::vector<Eigen::Affine3d>& bind_inverse, bool exposure, int threads, FitSurfaces* surfaces) {
  const FitSurfaces& s = *surfaces;
  const int region_count = s.region_count;
  const size_t patch_count = s.patch_count;
  FixedPieces out;
  out.input_region_change.assign(poses.size(), std::vector<double>(region_count, 0.0));
  out.unreached_change.assign(poses.size(), 0.0);
  out.input_body_change.assign(poses.size(), 0.0);
  out.volume.assign(poses.size(), std::vector<FixedVolume>(s.parts.size() * patch_count));
  const OccupancyGrid grid = exposure ? fitOccupancyGrid(s) : OccupancyGrid{};
  if (grid.step > 0.0) out.exposure.resize(poses.size());
  std::vector<PoseOnlyScratch> scratches(parallelWorkerCount(threads, poses.size(), 1));
  parallelForWorkers(threads, poses.size(), 1, [&](size_t worker, size_t, size_t i, size_t) {
    PoseOnlyScratch& scratch = scratches[worker];
    skinningFrame(skeleton, poses[i], evaluateRig(rig, poses[i], false), bind_inverse, &scratch.frame);
    const FloatSkinFrame& float_frame = scratch.float_frame;
    prepareFloatSkinFrame(scratch.frame, s.skin_centre, 0, s.no_pivots, &scratch.float_frame);
    std::vector<double>& volume = scratch.volume;
    volume.assign(region_count, 0.0);
    scratch.parts_welded.resize(s.parts.size());
    std::vector<Eigen::Vector3d>& input = scratch.input;
    double unreached = 0.0, input_body = 0.0;
    for (size_t p = 0; p < s.parts.size(); ++p) {
      const FitPart& part = s.parts[p];
      std::vector<Eigen::Vector3d>& welded = scratch.parts_welded[p];
      const std::vector<int>& vertex_of_weld = s.measured.surfaces[p].vertex_of_weld;
      input.resize(vertex_of_weld.size());
      welded.resize(vertex_of_weld.size());
      skinSkinningBatch<(1u << kWeldedInputSet) | (1u << kWeldedRigSet)>(
          part.welded_batch, float_frame, 0, part.welded_batch.groups(), [&](size_t g, const SkinnedGroup& group) {
            storeSkinned(group, g, kWeldedInputSet, part.welded_of_lane, part.welded_bind, &input);
            storeSkinned(group, g, kWeldedRigSet, part.welded_of_lane, part.welded_bind, &welded);
          });
      for (int r = 0; r < region_count; ++r) volume[r] += enclosedVolume(part.regions[r], input);
      unreached += enclosedVolume(part.unreached, welded);
      input_body += enclosedVolume(s.measured.surfaces[p].whole, input);
      for (size_t k = 0; k < patch_count; ++k) {
        const SplitPatch& split = part.patches[k];
        if (split.first_vertex < 0) continue;
        FixedVolume& fixed = out.volume[i][p * patch_count + k];
        fixed.origin = welded[split.first_vertex];
        fixed.volume = enclosedVolumeAbout(split.fixed, welded, fixed.origin);
      }
    }
    for (int r = 0; r < region_count; ++r) out.input_region_change[i][r] = signedChange(volume[r], s.bind_region[r]);
    out.unreached_change[i] = (unreached - s.bind_unreached) / std::max(std::abs(s.bind_body), 1e-30);
    out.input_body_change[i] = signedChange(input_body, s.bind_body);
    if (out.exposure.empty()) return;
    // Every part at once: skin is inside skin of any part.
    std::vector<PosedPatch> posed;
    for (size_t p = 0; p < s.parts.size(); ++p) posed.push_back({&s.measured.surfaces[p].whole, &scratch.parts_welded[p]});
    const std::vector<std::vector<float>> share = exposedShare(posed, grid.axis, grid.step);
    out.exposure[i].resize(s.parts.size());
    for (size_t p = 0; p < s.parts.size(); ++p) {
      const std::vector<int>& moving = s.parts[p].moving_vertices;
      const std::vector<int>& weld_of_vertex = s.measured.surfaces[p].weld_of_vertex;
      std::vector<float>& e = out.exposure[i][p];
      e.resize(moving.size());
      for (size_t c = 0; c < moving.size(); ++c) e[c] = share[p][static_cast<size_t>(weld_of_vertex[static_cast<size_t>(moving[c])])];
    }
  });
  surfaces->measured = MeasuredSurfaces{};
  for (FitPart& part : surfaces->parts) {
    part.welded_batch = SkinningBatch{};
    std::vector<int>().swap(part.welded_of_lane);
    std::vector<Eigen::Vector3d>().swap(part.welded_bind);
    std::vector<ClosedPatch>().swap(part.regions);
    part.unreached = ClosedPatch{};
    for (SplitPatch& split : part.patches) split.fixed = ClosedPatch{};
  }
  return out;
}

double sumTriangles(const std::vector<std::array<int, 3>>& triangles, const std::vector<Float4>& planar, __m128 origin,
                    std::vector<Eigen::Vector3d>* gradient, TriangleTerms* terms) {
  // About 100 instructions per triangle in double with Eigen's 3-vectors; here the corners are one
  // register each.
  std::vector<Eigen::Vector3d>& g = *gradient;
  terms->area.resize(triangles.size());
  terms->volume.resize(triangles.size());
  const __m128 sixth = _mm_set1_ps(1.0f / 6.0f);
  double volume = 0.0;
  for (size_t i = 0; i < triangles.size(); ++i) {
    const std::array<int, 3>& t = triangles[i];
    const __m128 a = _mm_load_ps(planar[static_cast<size_t>(t[0])].v);
    const __m128 u = _mm_sub_ps(_mm_load_ps(planar[static_cast<size_t>(t[1])].v), a);
    const __m128 v = _mm_sub_ps(_mm_load_ps(planar[static_cast<size_t>(t[2])].v), a);
    // u x v = u.yzx * v.zxy - u.zxy * v.yzx; lane 3 stays zero.
    const __m128 area =
        _mm_sub_ps(_mm_mul_ps(_mm_shuffle_ps(u, u, _MM_SHUFFLE(3, 0, 2, 1)), _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 1, 0, 2))),
                   _mm_mul_ps(_mm_shuffle_ps(u, u, _MM_SHUFFLE(3, 1, 0, 2)), _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 0, 2, 1))));
    const __m128 product = _mm_mul_ps(_mm_sub_ps(a, origin), area);
    const __m128 pair = _mm_add_ps(product, _mm_movehl_ps(product, product));  // x + z, y + 0
    const __m128 term = _mm_add_ss(pair, _mm_shuffle_ps(pair, pair, _MM_SHUFFLE(1, 1, 1, 1)));
    _mm_store_ps(terms->area[i].v, area);
    _mm_store_ss(&terms->volume[i], term);
    volume += static_cast<double>(_mm_cvtss_f32(term));
    const __m128 share = _mm_mul_ps(area, sixth);
    const __m128d share_xy = _mm_cvtps_pd(share), share_z = _mm_cvtps_pd(_mm_movehl_ps(share, share));
    for (int k = 0; k < 3; ++k) {
      double* corner = g[static_cast<size_t>(t[k])].data();
      _mm_storeu_pd(corner, _mm_add_pd(_mm_loadu_pd(corner), share_xy));
      _mm_store_sd(corner + 2, _mm_add_sd(_mm_load_sd(corner + 2), share_z));
    }
  }
  return volume;
}

__m128 planarPoint(const Eigen::Vector3d& point, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d d = point - centre;
  return _mm_set_ps(0.0f, static_cast<float>(d.z()), static_cast<float>(d.y()), static_cast<float>(d.x()));
}

}  // namespace rigbake
