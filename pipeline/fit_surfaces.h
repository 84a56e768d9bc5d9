// The surfaces the response fit (pipeline/response_fit.h) measures: each skinned part's closed surface
// and body regions, split into what the fit can move and what it cannot, the fitted muscles' skin, the
// single-precision skinning batches and the triangle sums the figures use (pipeline/deformation_quality.cpp),
// so the fit's volumes are the figures' to the bit. Internal to the fit; the keys and amplitudes are
// pipeline/response_layout.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <utility>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "pipeline/skin_volume.h"
#include "pipeline/skinning_batch.h"

namespace rigbake {

// A fitted muscle's slot at a vertex.
struct MuscleVertex {
  int muscle;
  double weight;      // the muscle's skin weight at the vertex
  Eigen::Vector3d q;  // the vertex in the skinned joint's bind frame
};

// A patch (the whole surface or a region) split by what the fit can move: the triangles and holes
// with a fitted muscle's vertex (`moving`, over the part's moving vertices) and the rest (`fixed`, over
// welded vertices). The fixed piece's volume depends on the pose alone, so it is summed once per pose;
// each iteration re-skins and re-sums only the moving piece, about the same point, and the moving
// piece is also all the volume gradient at the fitted vertices needs.
struct SplitPatch {
  int first_vertex = -1;     // welded; -1: the patch has no triangles (no volume, no gradient)
  ClosedPatch fixed;         // welded indices
  ClosedPatch moving;        // moving-vertex indices (FitPart::moving_vertices)
  std::vector<int> touched;  // the moving vertices of `moving`, ascending
  std::vector<int> fitted;   // the fitted vertices among them, ascending
  ClosedPatch moving_holes;  // moving.holes alone: summed apart from the triangles
  // A fitted vertex on no hole whose triangles close a fan around it has the volume gradient
  // (1/6) sum of their area vectors (the origin drops out of a closed fan's sum of b x c): the whole
  // surface's pass adds those up. For a region it is the whole surface's gradient when the fan is all
  // in the region: `inner_fitted`. The others' gradient is the rim's: the piece's triangles around
  // them, then every hole (addVolumeGradientAbout() keeps that order).
  std::vector<int> inner_fitted;
  ClosedPatch rim;
  std::vector<int> rim_fitted, rim_touched;
  // Regions only: their moving triangles are all in the whole surface's moving piece, whose pass keeps
  // each triangle's term; these are their indices there.
  std::vector<int> whole_triangles;
};

// The weight sets of the pose-only pass's skinning batch.
constexpr int kWeldedInputSet = 0, kWeldedRigSet = 1;

struct FitPart {
  const MeshPart* mesh = nullptr;
  const MeasuredPart* weights = nullptr;
  std::vector<ClosedPatch> regions;   // welded, for the input skinning's region changes
  std::vector<SplitPatch> patches;    // the whole surface, then each region
  ClosedPatch unreached;              // welded: the triangles with no fitted vertex, closed by caps
  std::vector<int> moving_vertices;   // part vertices of the moving pieces, by moving index
  // Every moving vertex's fitted-muscle slots, one vertex after another: moving index c has
  // muscle_slots[first_share[c] .. first_share[c + 1]) (one flat list: a vector per vertex was a
  // million allocations at 1M vertices).
  std::vector<MuscleVertex> muscle_slots;
  std::vector<int> first_share;  // moving index -> its first muscle slot; one past the last at the end
  const MuscleVertex* slotsBegin(int c) const { return muscle_slots.data() + first_share[static_cast<size_t>(c)]; }
  const MuscleVertex* slotsEnd(int c) const { return muscle_slots.data() + first_share[static_cast<size_t>(c) + 1]; }
  bool hasSlots(int c) const { return first_share[static_cast<size_t>(c)] != first_share[static_cast<size_t>(c) + 1]; }
  // Skinned in single precision (pipeline/skinning_batch.h), as the figures skin them: the pose-only
  // pass every welded vertex with the input's and the rig's weights, each iteration the moving
  // vertices with the rig's. A vertex's offset is the same bits in either batch (a set's offset does
  // not depend on the other sets or the lane), so the fixed and moving pieces agree where they meet.
  SkinningBatch welded_batch;
  std::vector<int> welded_of_lane;  // kSkinLanes per group: welded index, -1 for an empty lane
  SkinningBatch moving_batch;
  std::vector<int> moving_of_lane;  // kSkinLanes per group: moving index, -1 for an empty lane
  // The same with -1 also for the moving vertices no rim or cap touches: only those are needed in double
  // (the triangle pass reads single precision), so only those are converted.
  std::vector<int> rim_of_lane;
  // Each lane's bind position in double, in lane order (zero for an empty lane).
  std::vector<Eigen::Vector3d> welded_bind, moving_bind;
};

// A vertex of a fitted muscle's skin, as the figures take it (muscleSkin()).
struct SkinVertex {
  int part, vertex;  // fit part, moving index
  double weight;
};

// A moving vertex some fitted muscle's skin holds, with all its muscle slots (fitted or kept): the skin
// rows' rig-minus-input moves need those and nothing else.
struct SkinSlots {
  int vertex;                                   // moving index
  std::vector<std::pair<int, double>> muscles;  // muscle, weight
};

// A fixed piece at one pose: the point its volume is summed about and that sum.
struct FixedVolume {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double volume = 0.0;
};

// Everything the fit measures on the skin, formed once before its iterations.
struct FitSurfaces {
  std::vector<FitPart> parts;
  int region_count = 0;  // the regions the figures measure (patches 1 .. region_count of each part)
  size_t patch_count = 1;  // the whole surface, then each region
  double bind_body = 0.0;
  double bind_unreached = 0.0;  // the parts' unreached pieces, summed
  std::vector<double> bind_region;  // per measured region
  // Single precision about the same point as the figures skin about.
  Eigen::Vector3d skin_centre = Eigen::Vector3d::Zero();
  DualQuaternionPivots no_pivots;  // the fit skins by linear blending only
  std::vector<std::vector<SkinVertex>> muscle_skin;  // per muscle (fitted ones only)
  std::vector<double> skin_total;                    // per muscle: its skin's weight
  std::vector<std::vector<SkinSlots>> skin_slots;    // per fit part
  // The welded surfaces, for the pose-only pass alone (measureFixedPieces() frees them).
  MeasuredSurfaces measured;
};

// Surfaces, regions (those the figures measure), and which vertices each fitted muscle moves (those
// with `kind` >= 0; `bind_inverse` per muscle).
FitSurfaces buildFitSurfaces(const Character& character, const std::vector<BodyRegion>& regions,
                             const std::vector<MeasuredPart>& parts, const MuscleSet& muscles, const std::vector<int>& kind,
                             const std::vector<Eigen::Affine3d>& bind_inverse, int threads);

// The skinning matrices at a pose: the skeleton's joints, then each muscle's skinned joint (into
// `frame`, reusing its storage from pose to pose).
void skinningFrame(const Skeleton& skeleton, const Pose& pose, const RigEvaluation& evaluation,
                   const std::vector<Eigen::Affine3d>& bind_inverse, std::vector<Eigen::Affine3d>* frame);

// What the fit does not change, per pose: the input skinning's region changes (the dead zones), the
// change of the skin no fitted muscle moves (FitPart::unreached, as a share of the bind body), and the
// fixed pieces' volumes (their vertices carry no fitted muscle, so any response gives the same positions).
struct FixedPieces {
  std::vector<std::vector<double>> input_region_change;  // [pose][region]
  std::vector<double> unreached_change;                  // [pose]
  std::vector<double> input_body_change;                 // [pose]: the whole body's under the input skinning
  std::vector<std::vector<FixedVolume>> volume;          // [pose][part * patch_count + patch]
  // With ResponseFitOptions::occupied_volume: per pose, part and moving vertex, the share of its skin
  // that bounds the occupied space under the starting rig (pipeline/occupied_volume.h exposedShare());
  // empty otherwise.
  std::vector<std::vector<std::vector<float>>> exposure;
};

// One pass over the poses with `rig` (any response) for FixedPieces; then frees what the iterations do
// not need (the welded surfaces, their batch, the input's region patches and the fixed pieces: 16 MB
// of the fit at 100k vertices, which was the bake's peak).
FixedPieces measureFixedPieces(const Skeleton& skeleton, const std::vector<Pose>& poses, const runtime::MuscleRig<double>& rig,
                               const std::vector<Eigen::Affine3d>& bind_inverse, bool exposure, int threads, FitSurfaces* surfaces);

// Positions p + offset in double from a batch's single-precision offsets (set `set`), into
// (*posed)[index_of_lane[lane]]: the bind position (bind_of_lane, in lane order) keeps its digits and
// only the move is rounded.
// Inline: called for every group of every iteration's skinning.
inline void storeSkinned(const SkinnedGroup& group, size_t g, int set, const std::vector<int>& index_of_lane,
                         const std::vector<Eigen::Vector3d>& bind_of_lane, std::vector<Eigen::Vector3d>* posed) {
  Float4 offset[3];
  for (int r = 0; r < 3; ++r) _mm_store_ps(offset[r].v, group.offset[set][r]);
  for (size_t lane = 0; lane < kSkinLanes; ++lane) {
    const int index = index_of_lane[kSkinLanes * g + lane];
    if (index < 0) continue;
    (*posed)[static_cast<size_t>(index)] =
        bind_of_lane[kSkinLanes * g + lane] + Eigen::Vector3d(offset[0].v[lane], offset[1].v[lane], offset[2].v[lane]);
  }
}

// A moving vertex's posed position about the skin centre, x, y, z in lanes 0-2 and zero in lane 3:
// one aligned load per corner, and the cross product is two shuffles per operand instead of a gather
// of four triangles into lanes.
inline void storePlanar(const SkinnedGroup& group, size_t g, const std::vector<int>& index_of_lane, std::vector<Float4>* planar) {
  __m128 x = _mm_add_ps(group.x, group.offset[0][0]), y = _mm_add_ps(group.y, group.offset[0][1]);
  __m128 z = _mm_add_ps(group.z, group.offset[0][2]), w = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x, y, z, w);
  const __m128 lanes[kSkinLanes] = {x, y, z, w};
  for (size_t lane = 0; lane < kSkinLanes; ++lane) {
    const int index = index_of_lane[kSkinLanes * g + lane];
    if (index >= 0) _mm_store_ps((*planar)[static_cast<size_t>(index)].v, lanes[lane]);
  }
}

// One triangle (a, b, c) of a piece summed about a point o: six times the volume of the tetrahedron
// (o, a, b, c), (a - o) . n, and its area vector n = (b - a) x (c - a), from which its term about
// another point o + d follows, minus d . n. The whole surface's pass keeps these, and each region's
// moving triangles, all among the whole surface's, are summed from them about the region's own point.
// Single precision, as the figures sum the same terms (pipeline/deformation_quality.cpp): the area
// vector in lanes 0-2 of `area` (lane 3 zero) and the term in `volume`.
struct TriangleTerms {
  std::vector<Float4> area;
  std::vector<float> volume;
};

// Six times the volume of `triangles` about `origin` (enclosedVolumeAbout()'s sum over triangles, each
// term formed in single precision as the figures form it and added in double), each triangle's terms,
// and a sixth of its area vector added to the gradient at its corners: the volume gradient at a vertex
// whose fan is closed (SplitPatch), in one pass with one cross product per triangle.
double sumTriangles(const std::vector<std::array<int, 3>>& triangles, const std::vector<Float4>& planar, __m128 origin,
                    std::vector<Eigen::Vector3d>* gradient, TriangleTerms* terms);

// A point about the skin centre in a register's lanes 0-2, as storePlanar() lays out positions.
__m128 planarPoint(const Eigen::Vector3d& point, const Eigen::Vector3d& centre);

// A volume's change against its bind volume (0 for an empty one).
inline double signedChange(double volume, double reference) { return reference != 0.0 ? volume / reference - 1.0 : 0.0; }

}  // namespace rigbake
