// The response fit (pipeline/response_fit.h): the muscles' key amplitudes (pipeline/response_layout.h)
// solved by Levenberg-Marquardt with hinges and bounds (pipeline/hinge_least_squares.h) over the skin's
// volumes at the fitted poses (pipeline/fit_surfaces.h). Residuals: the whole body's volume change at
// every fitted pose; one-sided rows for each region that leaves its dead zone and for each muscle whose
// skin moves in further than its floor (a compressed muscle does not deflate, a stretched one does not
// hollow); optionally the smoothness term's rows and the roughness cap's hinges; and a prior towards the
// talk's amplitudes (1 when compressed, 0 otherwise: a stretched muscle does not thin unless volume asks
// for it). This file builds each pose's rows: the volumes and their Jacobian in the amplitudes.
#include "pipeline/response_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>
#include <set>
#include <string>

#include "pipeline/fit_surfaces.h"
#include "pipeline/hinge_least_squares.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/parallel.h"
#include "pipeline/response_layout.h"
#include "pipeline/surface_figures.h"
#include "pipeline/surface_graph.h"

namespace rigbake {
namespace {
// Per muscle, what the Jacobian's inner loop needs and the fit does not change: the skinned joint's
// bind transform and axes, its side, its carrier and its keys' shapes.
struct MuscleFrames {
  std::vector<Eigen::Affine3d> bind_inverse;
  std::vector<Eigen::Matrix3d> bind_axes;
  std::vector<double> side_sign;
  std::vector<std::array<KeyShape, kKeys>> shapes;
  std::vector<int> carrier_of;
};

MuscleFrames muscleFrames(const MuscleSet& muscles, const Skeleton& skeleton, const ResponseLayout& layout) {
  const size_t muscle_count = muscles.parts.size();
  MuscleFrames frames;
  frames.bind_inverse.resize(muscle_count);
  frames.bind_axes.resize(muscle_count);
  frames.side_sign.resize(muscle_count);
  frames.shapes.resize(muscle_count);
  frames.carrier_of.resize(muscle_count);
  for (size_t m = 0; m < muscle_count; ++m) {
    const MusclePart& part = muscles.parts[m];
    frames.bind_inverse[m] = muscleBindTransform(part, skeleton).inverse();
    frames.bind_axes[m] = frames.bind_inverse[m].inverse().linear();
    frames.side_sign[m] = part.side == "Right" ? -1.0 : 1.0;
    const int kind = layout.kind[m];
    for (int k = 0; k < kKeys; ++k) frames.shapes[m][k] = kind >= 0 ? keyShape(part, k, layout.stretched_at[kind]) : KeyShape{};
    frames.carrier_of[m] = muscleCarrierJoint(part);
  }
  return frames;
}

// One muscle's keys at one pose: its posed rest up and side axes and, per key, the coefficients of a
// vertex's motion along up, side and the scale's direction per unit amplitude (hat weight included).
struct MuscleKeyMotion {
  Eigen::Vector3d up_axis = Eigen::Vector3d::Zero(), side_axis = Eigen::Vector3d::Zero();
  double up[kKeys] = {}, side[kKeys] = {}, scale[kKeys] = {};
};

// Whether key k moves the muscle's skin at this pose: most keys' hat weights are zero at any one pose.
bool keyMoves(const MuscleKeyMotion& motion, int k) { return motion.up[k] != 0.0 || motion.side[k] != 0.0 || motion.scale[k] != 0.0; }

// One muscle's share of a Jacobian row being built: the sums of w g . u, w g . s and of their
// combination along the scale's direction over the row's vertices of the muscle.
struct MuscleSums {
  double up = 0.0, side = 0.0, scale = 0.0;
};

// What one worker of the fit's pose loop reuses from chunk to chunk and from iteration to iteration:
// per fit part, buffers the size of its moving vertices. Allocated per chunk they were mapped and
// zeroed by the kernel again for every four poses (at a million vertices, tens of megabytes each).
// `gradients` is all zero between uses: each use zeroes the entries it wrote.
struct PoseScratch {
  std::vector<std::vector<Eigen::Vector3d>> posed, moved, gradients, normals;
  std::vector<std::vector<Float4>> planar;
  std::vector<TriangleTerms> terms;
  std::vector<std::vector<MuscleSums>> body_shares;  // per part, per muscle slot
  std::vector<MuscleKeyMotion> key_motion;
  std::vector<MuscleSums> sums;
  std::vector<Eigen::Matrix4d> apart;  // a muscle's skinning matrix less its carrier's
  std::vector<std::vector<Eigen::Vector3d>> rig_move;  // per part, per moving vertex: d, the rig's move against the input
  std::vector<int> touched_muscles;
  std::vector<char> muscle_touched;
  std::vector<int> local_unknown;  // unknown -> its index in the pose's rough_unknowns, -1 when not moved
  std::vector<Eigen::Affine3d> frame;
  FloatSkinFrame float_frame;
};

PoseScratch poseScratch(const std::vector<FitPart>& fit_parts, size_t muscle_count) {
  PoseScratch scratch;
  const size_t part_count = fit_parts.size();
  scratch.posed.resize(part_count);
  scratch.moved.resize(part_count);
  scratch.gradients.resize(part_count);
  scratch.normals.resize(part_count);
  scratch.planar.resize(part_count);
  scratch.terms.resize(part_count);
  scratch.body_shares.resize(part_count);
  scratch.key_motion.resize(muscle_count);
  scratch.apart.resize(muscle_count);
  scratch.rig_move.resize(part_count);
  scratch.muscle_touched.assign(muscle_count, 0);
  for (size_t p = 0; p < part_count; ++p) scratch.gradients[p].assign(fit_parts[p].moving_vertices.size(), Eigen::Vector3d::Zero());
  return scratch;
}

// A few poses per chunk of the fit's pose loop, which keeps its posed vertices and gradients from pose
// to pose.
constexpr size_t kPosesPerChunk = 4;

// What stays fixed while the fit iterates.
struct FitProblem {
  const Skeleton& skeleton;
  const MuscleSet& muscles;  // read for each part's side, drivers' keys; its responses change between passes
  const ResponseLayout& layout;
  const ResponseFitOptions& options;
  const MuscleFrames& frames;
  const FitSurfaces& surfaces;
  const FixedPieces& fixed;
  double compressed_limit, hollow_limit, skin_band;  // metres
  double skin_weight;  // options.skin_weight x kReferenceBodyHeight / body height: per metre of this body
  double region_weight;  // the regions' rows: options.region_weight, or every_frame_region_weight
  // Per fit part, the one-ring of each moving vertex over the whole surface's moving piece; empty
  // when there is neither the smoothness term nor the roughness cap.
  const std::vector<std::vector<std::vector<int>>>& rings;
  // options.smoothness_weight x kReferenceBodyHeight / body height (per metre of this body) / sqrt(the
  // fitted vertices of every part); 0: no term
  double roughness_scale;
  // The roughness cap: its hinges' weight, scaled as roughness_scale is (0: no cap), the figures' floor
  // (scene units) and, per fitted pose, the input skinning's roughness rise (empty without the cap).
  double cap_scale;
  double roughness_floor;
  const std::vector<double>& input_rise;
};

// One pose's share of the model (joined in pose order, so any thread count gives the same system).
struct PoseRows {
  HingeLinearModel model;
  // The smoothness rows, as their normal equations over the unknowns the pose moves (`rough_unknowns`,
  // the keys whose hat weight is not zero there; the rows themselves are one per fitted vertex).
  std::vector<int> rough_unknowns;
  Eigen::MatrixXd rough_normal;
  Eigen::VectorXd rough_gradient;
  double rough_square = 0.0;
  double body_square = 0.0;
  double violation = 0.0;  // the violated hinges' squares, candidates or not
  double region_excess = 0.0;  // how far the lowest region is below its dead zone (a fraction of its bind volume)
};

// Builds one pose's rows at a time on one worker's scratch. A row's Jacobian is sum over its vertices v
// and their muscles m of factor * w * (g_v . motion), motion linear in the keys with per-muscle
// coefficients: so each vertex only adds g . u, g . s and their scale combination to its muscle's three
// sums, and the keys are expanded once per muscle when the row is taken.
class PoseRowBuilder {
 public:
  PoseRowBuilder(const FitProblem& problem, PoseScratch* scratch) : problem_(problem), s_(*scratch) {
    s_.sums.assign(problem.muscles.parts.size(), MuscleSums{});
  }
  void build(const runtime::MuscleRig<double>& rig, const Pose& pose, size_t pose_index, bool measure_only, PoseRows* out);
  // How far the pose's lowest region is below its dead zone (0 when every region is within it): the
  // regions alone, none of the other rows.
  double regionExcess(const runtime::MuscleRig<double>& rig, const Pose& pose, size_t pose_index);

 private:
  void setKeyMotion(const RigEvaluation& evaluation);
  void addVertex(const FitPart& part, int w, const Eigen::Vector3d& g, double factor);
  void addBodyVertex(size_t p, int w);
  void addInnerVertex(size_t p, int w);
  Eigen::VectorXd takeRow(double weight);
  SparseRow laplacianRow(const FitPart& part, int v, const std::vector<int>& ring, const Eigen::Vector3d& n, double weight);
  Eigen::VectorXd volumeJacobian(size_t k, double weight);
  double measurePose(const RigEvaluation& evaluation, const Pose& pose, size_t pose_index, std::vector<double>* region_volume);
  double measureVolumes(std::vector<double>* region_volume);
  void addRegionHinges(const std::vector<double>& region_volume, bool measure_only, PoseRows* out);
  void addSkinFloorHinges(const RigEvaluation& evaluation, bool measure_only, PoseRows* out);
  void rigMove(size_t p);
  void addRoughness(bool measure_only, PoseRows* out);
  void addRoughnessCap(bool measure_only, PoseRows* out);

  const FitProblem& problem_;
  PoseScratch& s_;
  size_t pose_ = 0;
};

// Per muscle at this pose, a vertex's motion per unit of each key's amplitude is
// weight * phi_k * (up_k * u + side_k * s + scale_k * (q_y u + q_z s)), phi_k the key's hat weight, u
// and s the skinned joint's rest up and side axes as posed: so a row's Jacobian needs, per muscle
// vertex, only g . u and g . s for the row's gradient g at it.
void PoseRowBuilder::setKeyMotion(const RigEvaluation& evaluation) {
  const ResponseLayout& layout = problem_.layout;
  const MuscleFrames& frames = problem_.frames;
  for (size_t m = 0; m < problem_.muscles.parts.size(); ++m) {
    const int kind = layout.kind[m];
    if (kind < 0) continue;
    double phi[kKeys];
    keyWeights(problem_.muscles.parts[m], layout.ratio_keys[kind], layout.twist_keys[kind], evaluation.drivers[m], phi);
    const Eigen::Matrix3d axes = s_.frame[frames.carrier_of[m]].linear() * frames.bind_axes[m];
    MuscleKeyMotion& motion = s_.key_motion[m];
    motion.up_axis = axes.col(1);
    motion.side_axis = axes.col(2);
    for (int k = 0; k < kKeys; ++k) {
      const KeyShape& shape = frames.shapes[m][k];
      motion.up[k] = phi[k] * shape.up;
      motion.side[k] = phi[k] * shape.side * frames.side_sign[m];
      motion.scale[k] = phi[k] * shape.scale;
    }
  }
}

void PoseRowBuilder::addVertex(const FitPart& part, int w, const Eigen::Vector3d& g, double factor) {
  for (const MuscleVertex* mv = part.slotsBegin(w); mv != part.slotsEnd(w); ++mv) {
    const MuscleKeyMotion& motion = s_.key_motion[mv->muscle];
    const double along_up = factor * mv->weight * g.dot(motion.up_axis);
    const double along_side = factor * mv->weight * g.dot(motion.side_axis);
    MuscleSums& sum = s_.sums[mv->muscle];
    sum.up += along_up;
    sum.side += along_side;
    sum.scale += mv->q.y() * along_up + mv->q.z() * along_side;
  }
}

// The body row's shares are kept per muscle slot: a region's inner vertices have the same gradient, so
// their shares are only added up again (addInnerVertex()).
void PoseRowBuilder::addBodyVertex(size_t p, int w) {
  const FitPart& part = problem_.surfaces.parts[p];
  const Eigen::Vector3d& g = s_.normals[p][w];
  // With the occupied volume (FixedPieces::exposure) skin inside other skin earns the body row nothing;
  // the shares kept for the regions' rows stay the signed volume's.
  const double exposed =
      problem_.fixed.exposure.empty() ? 1.0 : static_cast<double>(problem_.fixed.exposure[pose_][p][static_cast<size_t>(w)]);
  MuscleSums* share = s_.body_shares[p].data() + part.first_share[w];
  for (const MuscleVertex* mv = part.slotsBegin(w); mv != part.slotsEnd(w); ++mv) {
    const MuscleKeyMotion& motion = s_.key_motion[mv->muscle];
    const double along_up = mv->weight * g.dot(motion.up_axis);
    const double along_side = mv->weight * g.dot(motion.side_axis);
    *share = {along_up, along_side, mv->q.y() * along_up + mv->q.z() * along_side};
    MuscleSums& sum = s_.sums[mv->muscle];
    sum.up += exposed * share->up;
    sum.side += exposed * share->side;
    sum.scale += exposed * share->scale;
    ++share;
  }
}

void PoseRowBuilder::addInnerVertex(size_t p, int w) {
  const FitPart& part = problem_.surfaces.parts[p];
  const MuscleSums* share = s_.body_shares[p].data() + part.first_share[w];
  for (const MuscleVertex* mv = part.slotsBegin(w); mv != part.slotsEnd(w); ++mv) {
    MuscleSums& sum = s_.sums[mv->muscle];
    sum.up += share->up;
    sum.side += share->side;
    sum.scale += share->scale;
    ++share;
  }
}

// The row the sums make, times `weight`; the sums are zeroed for the next row.
Eigen::VectorXd PoseRowBuilder::takeRow(double weight) {
  const ResponseLayout& layout = problem_.layout;
  Eigen::VectorXd jacobian = Eigen::VectorXd::Zero(layout.unknowns());
  for (size_t m = 0; m < problem_.muscles.parts.size(); ++m) {
    if (layout.kind[m] < 0) continue;
    MuscleSums& sum = s_.sums[m];
    const MuscleKeyMotion& motion = s_.key_motion[m];
    double* row_keys = jacobian.data() + layout.kind[m] * kKeys;
    for (int k = 0; k < kKeys; ++k) row_keys[k] += weight * (motion.up[k] * sum.up + motion.side[k] * sum.side + motion.scale[k] * sum.scale);
    sum = MuscleSums{};
  }
  return jacobian;
}

// weight * d((d_v - mean over its ring of d_u) . n)/d(amplitudes), d the rig's move against the input
// skinning: the smoothness term's and the roughness cap's row at fitted vertex v, as its entries over the
// keys that move at this pose (those of the few muscles that move v and its ring), unknowns ascending.
// Both sides' muscles share their kind's keys: such entries are summed in the order the muscles are met.
SparseRow PoseRowBuilder::laplacianRow(const FitPart& part, int v, const std::vector<int>& ring, const Eigen::Vector3d& n, double weight) {
  const ResponseLayout& layout = problem_.layout;
  const double share = 1.0 / static_cast<double>(ring.size());
  auto touch = [&](int c, double factor) {
    for (const MuscleVertex* mv = part.slotsBegin(c); mv != part.slotsEnd(c); ++mv) {
      if (!s_.muscle_touched[mv->muscle]) {
        s_.muscle_touched[mv->muscle] = 1;
        s_.touched_muscles.push_back(mv->muscle);
      }
    }
    addVertex(part, c, n, factor);
  };
  touch(v, 1.0);
  for (int u : ring) touch(u, -share);
  SparseRow row;
  for (int m : s_.touched_muscles) {
    s_.muscle_touched[m] = 0;
    MuscleSums& sum = s_.sums[m];
    const int kind = layout.kind[m];
    if (kind >= 0) {
      const MuscleKeyMotion& motion = s_.key_motion[m];
      for (int k = 0; k < kKeys; ++k) {
        if (!keyMoves(motion, k)) continue;
        row.entries.emplace_back(kind * kKeys + k, weight * (motion.up[k] * sum.up + motion.side[k] * sum.side + motion.scale[k] * sum.scale));
      }
    }
    sum = MuscleSums{};
  }
  s_.touched_muscles.clear();
  std::stable_sort(row.entries.begin(), row.entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  size_t kept = 0;
  for (size_t i = 0; i < row.entries.size(); ++i) {
    if (kept > 0 && row.entries[kept - 1].first == row.entries[i].first) row.entries[kept - 1].second += row.entries[i].second;
    else row.entries[kept++] = row.entries[i];
  }
  row.entries.resize(kept);
  return row;
}

// weight * d(volume of patch k)/d(amplitudes), summed over the parts.
Eigen::VectorXd PoseRowBuilder::volumeJacobian(size_t k, double weight) {
  const FitSurfaces& surfaces = problem_.surfaces;
  for (size_t p = 0; p < surfaces.parts.size(); ++p) {
    const FitPart& part = surfaces.parts[p];
    const SplitPatch& split = part.patches[k];
    if (split.first_vertex < 0) continue;
    // Inner vertices have the body's gradient; the rim's is summed from the triangles around it and
    // the holes, and the entries it touches are zeroed again for the next patch.
    for (int w : split.inner_fitted) addInnerVertex(p, w);
    std::vector<Eigen::Vector3d>& gradient = s_.gradients[p];
    addVolumeGradientAbout(split.rim, s_.posed[p], problem_.fixed.volume[pose_][p * surfaces.patch_count + k].origin, 1.0, &gradient);
    for (int w : split.rim_fitted) addVertex(part, w, gradient[w], 1.0);
    for (int w : split.rim_touched) gradient[w].setZero();
  }
  return takeRow(weight);
}

// Skins the moving vertices at the pose's frame and sums the body's volume (returned) and each
// region's (into region_volume). The body's gradient at the moving vertices is kept in `normals`: the
// body row's Jacobian, the inner vertices' of every region, then (normalized) the skin rows' normals.
double PoseRowBuilder::measureVolumes(std::vector<double>* region_volume) {
  const FitSurfaces& surfaces = problem_.surfaces;
  const std::vector<FixedVolume>& fixed_volume = problem_.fixed.volume[pose_];
  double body = 0.0;
  for (size_t p = 0; p < surfaces.parts.size(); ++p) {
    const FitPart& part = surfaces.parts[p];
    std::vector<Eigen::Vector3d>& posed = s_.posed[p];
    std::vector<Float4>& planar = s_.planar[p];
    posed.resize(part.moving_vertices.size());
    planar.resize(part.moving_vertices.size());
    skinSkinningBatch<1u>(part.moving_batch, s_.float_frame, 0, part.moving_batch.groups(), [&](size_t g, const SkinnedGroup& group) {
      storeSkinned(group, g, 0, part.rim_of_lane, part.moving_bind, &posed);
      storePlanar(group, g, part.moving_of_lane, &planar);
    });
    s_.normals[p].assign(part.moving_vertices.size(), Eigen::Vector3d::Zero());
    const SplitPatch& whole = part.patches[0];
    if (whole.first_vertex < 0) continue;  // no triangles: nor has any region
    const FixedVolume& whole_fixed = fixed_volume[p * surfaces.patch_count];
    const double whole_sum = sumTriangles(whole.moving.triangles, planar, planarPoint(whole_fixed.origin, surfaces.skin_centre),
                                          &s_.normals[p], &s_.terms[p]);
    body += whole_fixed.volume + whole_sum / 6.0 + enclosedVolumeAbout(whole.moving_holes, posed, whole_fixed.origin);
    if (!whole.rim_fitted.empty()) {
      std::vector<Eigen::Vector3d>& gradient = s_.gradients[p];
      addVolumeGradientAbout(whole.rim, posed, whole_fixed.origin, 1.0, &gradient);
      for (int w : whole.rim_fitted) s_.normals[p][w] = gradient[w];
      for (int w : whole.rim_touched) gradient[w].setZero();
    }
    // A region's moving triangles are the whole surface's: their terms, moved to the region's point.
    const TriangleTerms& terms = s_.terms[p];
    for (size_t k = 1; k < surfaces.patch_count; ++k) {
      const SplitPatch& split = part.patches[k];
      if (split.first_vertex < 0) continue;
      const FixedVolume& fixed = fixed_volume[p * surfaces.patch_count + k];
      const Eigen::Vector3d shift = fixed.origin - whole_fixed.origin;
      double sum = 0.0;
      __m128d area_xy = _mm_setzero_pd(), area_z = _mm_setzero_pd();
      for (int t : split.whole_triangles) {
        sum += static_cast<double>(terms.volume[static_cast<size_t>(t)]);
        const __m128 term_area = _mm_load_ps(terms.area[static_cast<size_t>(t)].v);
        area_xy = _mm_add_pd(area_xy, _mm_cvtps_pd(term_area));
        area_z = _mm_add_pd(area_z, _mm_cvtps_pd(_mm_movehl_ps(term_area, term_area)));
      }
      Eigen::Vector3d area;
      _mm_storeu_pd(area.data(), area_xy);
      _mm_store_sd(area.data() + 2, area_z);
      (*region_volume)[k - 1] += fixed.volume + (sum - shift.dot(area)) / 6.0 + enclosedVolumeAbout(split.moving_holes, posed, fixed.origin);
    }
  }
  return body;
}

// Each region's dead zone [lower, upper], two hinges, in the model while within region_band of an edge.
void PoseRowBuilder::addRegionHinges(const std::vector<double>& region_volume, bool measure_only, PoseRows* out) {
  const ResponseFitOptions& options = problem_.options;
  const FitSurfaces& surfaces = problem_.surfaces;
  HingeLinearModel& model = out->model;
  for (int r = 0; r < surfaces.region_count; ++r) {
    const double bind = surfaces.bind_region[r];
    if (bind == 0.0) continue;
    const double change = signedChange(region_volume[r], bind);
    const double input_change = problem_.fixed.input_region_change[pose_][r];
    const double lower = std::min(input_change, 0.0) - options.region_margin;
    const double upper = std::max(input_change, 0.0) + options.region_gain;
    const double weight = problem_.region_weight / std::abs(bind);
    const double below = problem_.region_weight * (change - lower), above = problem_.region_weight * (upper - change);
    out->violation += std::pow(std::min(below, 0.0), 2) + std::pow(std::min(above, 0.0), 2);
    out->region_excess = std::max(out->region_excess, lower - change);
    const bool near_lower = change - lower < options.region_band, near_upper = upper - change < options.region_band;
    if (!near_lower && !near_upper) continue;
    Eigen::VectorXd jacobian;
    if (!measure_only) jacobian = volumeJacobian(static_cast<size_t>(r) + 1, weight);
    if (near_lower) {
      model.slack.push_back(below);
      if (!measure_only) model.hinges.push_back(jacobian);
    }
    if (near_upper) {
      model.slack.push_back(above);
      if (!measure_only) model.hinges.push_back(-jacobian);
    }
  }
}

// Each fitted muscle's skin floor: a compressed muscle's skin may not move in against the input
// skinning by more than compressed_limit (its mean move along the normal, weighted by the muscle's skin
// weight, as the figures take it), a stretched one's by more than hollow_limit. The normal at a
// muscle's vertex is the direction of the body's volume gradient there (its one-ring is all in the
// moving piece). The rig moves a vertex away from the input skinning by sum_k w_k (M_k - M_carrier(k)) p
// over its muscle slots k: a muscle's weight is taken from its carrier's, so the joints' own slots
// cancel.
void PoseRowBuilder::addSkinFloorHinges(const RigEvaluation& evaluation, bool measure_only, PoseRows* out) {
  const ResponseFitOptions& options = problem_.options;
  const FitSurfaces& surfaces = problem_.surfaces;
  const ResponseLayout& layout = problem_.layout;
  const size_t muscle_count = problem_.muscles.parts.size();
  for (size_t p = 0; p < surfaces.parts.size(); ++p) {
    const FitPart& part = surfaces.parts[p];
    s_.moved[p].resize(part.moving_vertices.size());
    for (const SkinSlots& entry : surfaces.skin_slots[p]) {
      Eigen::Vector3d& n = s_.normals[p][entry.vertex];
      const double length = n.norm();
      if (length > 0.0) n /= length;
      const Eigen::Vector4d bind = part.mesh->positions[part.moving_vertices[entry.vertex]].homogeneous();
      Eigen::Vector3d move = Eigen::Vector3d::Zero();
      for (const auto& [muscle, weight] : entry.muscles) move += weight * (s_.apart[muscle] * bind).head<3>();
      s_.moved[p][entry.vertex] = move;
    }
  }
  HingeLinearModel& model = out->model;
  for (size_t m = 0; m < muscle_count; ++m) {
    // A corrective's skin may go either way: that is what it is for.
    const int kind = layout.kind[m];
    const double skin_total = surfaces.skin_total[m];
    if (kind < 0 || layout.corrective[kind] || skin_total <= 0.0) continue;
    const double ratio = evaluation.drivers[m].clamped_ratio;
    const bool compressed = ratio <= 1.0 - options.skin_min_compression, stretched = ratio > 1.0;
    if (!compressed && !stretched) continue;
    double mean = 0.0;
    for (const SkinVertex& sv : surfaces.muscle_skin[m]) mean += sv.weight * s_.moved[sv.part][sv.vertex].dot(s_.normals[sv.part][sv.vertex]);
    mean /= skin_total;
    const double floor = compressed ? -problem_.compressed_limit : -problem_.hollow_limit;
    const double slack = problem_.skin_weight * (mean - floor);
    out->violation += std::pow(std::min(slack, 0.0), 2);
    if (mean - floor >= problem_.skin_band) continue;
    model.slack.push_back(slack);
    if (measure_only) continue;
    for (const SkinVertex& sv : surfaces.muscle_skin[m])
      addVertex(surfaces.parts[sv.part], sv.vertex, s_.normals[sv.part][sv.vertex], sv.weight / skin_total);
    model.hinges.push_back(takeRow(problem_.skin_weight));
  }
}

// The rig's move against the input skinning at each of part p's moving vertices (into s_.rig_move[p]):
// sum over its fitted-muscle slots of w (M_muscle - M_carrier) p_bind.
void PoseRowBuilder::rigMove(size_t p) {
  const FitPart& part = problem_.surfaces.parts[p];
  std::vector<Eigen::Vector3d>& move = s_.rig_move[p];
  move.assign(part.moving_vertices.size(), Eigen::Vector3d::Zero());
  for (size_t c = 0; c < part.moving_vertices.size(); ++c) {
    if (!part.hasSlots(static_cast<int>(c))) continue;
    const Eigen::Vector4d bind = part.mesh->positions[part.moving_vertices[c]].homogeneous();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const MuscleVertex* mv = part.slotsBegin(static_cast<int>(c)); mv != part.slotsEnd(static_cast<int>(c)); ++mv)
      sum += mv->weight * (s_.apart[mv->muscle] * bind).head<3>();
    move[c] = sum;
  }
}

// The smoothness term: per fitted vertex v, r_v = scale * (d_v - mean over its ring of d_u) . n_v, d the
// rig's move against the input skinning, linear in the amplitudes; its rows go into the pose's normal
// equations (a few muscles per row, so each row's square is a small block).
void PoseRowBuilder::addRoughness(bool measure_only, PoseRows* out) {
  const FitSurfaces& surfaces = problem_.surfaces;
  const ResponseLayout& layout = problem_.layout;
  const size_t muscle_count = problem_.muscles.parts.size();
  const int unknowns = layout.unknowns();
  if (!measure_only) {
    s_.local_unknown.assign(static_cast<size_t>(unknowns), -1);
    for (size_t m = 0; m < muscle_count; ++m) {
      const int kind = layout.kind[m];
      if (kind < 0) continue;
      const MuscleKeyMotion& motion = s_.key_motion[m];
      for (int k = 0; k < kKeys; ++k) {
        const int u = kind * kKeys + k;
        if (!keyMoves(motion, k) || s_.local_unknown[u] >= 0) continue;
        s_.local_unknown[u] = static_cast<int>(out->rough_unknowns.size());
        out->rough_unknowns.push_back(u);
      }
    }
    const Eigen::Index active = static_cast<Eigen::Index>(out->rough_unknowns.size());
    out->rough_normal = Eigen::MatrixXd::Zero(active, active);
    out->rough_gradient = Eigen::VectorXd::Zero(active);
  }
  for (size_t p = 0; p < surfaces.parts.size(); ++p) {
    const FitPart& part = surfaces.parts[p];
    rigMove(p);
    const std::vector<Eigen::Vector3d>& move = s_.rig_move[p];
    const std::vector<std::vector<int>>& rings = problem_.rings[p];
    for (int v : part.patches[0].fitted) {
      const std::vector<int>& ring = rings[static_cast<size_t>(v)];
      if (ring.empty()) continue;
      Eigen::Vector3d n = s_.normals[p][v];
      const double length = n.norm();
      if (!(length > 0.0)) continue;
      n /= length;
      const double share = 1.0 / static_cast<double>(ring.size());
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int u : ring) mean += move[static_cast<size_t>(u)];
      const double scale = problem_.roughness_scale;
      const double residual = scale * (move[v] - share * mean).dot(n);
      out->rough_square += residual * residual;
      if (measure_only) continue;
      // Its entries are all among the pose's rough_unknowns (the keys that move).
      const SparseRow row = laplacianRow(part, v, ring, n, scale);
      for (const auto& [ua, va] : row.entries) {
        const int a = s_.local_unknown[static_cast<size_t>(ua)];
        out->rough_gradient[a] += va * residual;
        for (const auto& [ub, vb] : row.entries) out->rough_normal(a, s_.local_unknown[static_cast<size_t>(ub)]) += va * vb;
      }
    }
  }
}

// The roughness cap: per fitted vertex v, with a = (x_v - mean over its ring of x_u) . n_v for the input
// skinning's positions x and e the same of the rig's move d (linear in the amplitudes), the rig's
// |a + e| may exceed |a| by at most tau (ResponseFitOptions::roughness_cap): the hinges
// |a| + tau - (a + e) >= 0 and |a| + tau + (a + e) >= 0. The rig's posed positions are the moving
// vertices' single-precision ones (as the volumes take them) and a is read off them less d.
void PoseRowBuilder::addRoughnessCap(bool measure_only, PoseRows* out) {
  const FitSurfaces& surfaces = problem_.surfaces;
  const ResponseFitOptions& options = problem_.options;
  HingeLinearModel& model = out->model;
  const double input_rise = std::max(problem_.input_rise[pose_], 0.0);
  const double tau = options.roughness_cap * std::max(input_rise, problem_.roughness_floor) - input_rise;
  const double weight = problem_.cap_scale;
  for (size_t p = 0; p < surfaces.parts.size(); ++p) {
    const FitPart& part = surfaces.parts[p];
    rigMove(p);
    const std::vector<Eigen::Vector3d>& move = s_.rig_move[p];
    const std::vector<Float4>& planar = s_.planar[p];
    auto posed = [&](int c) {
      const float* at = planar[static_cast<size_t>(c)].v;
      return Eigen::Vector3d(at[0], at[1], at[2]);
    };
    const std::vector<std::vector<int>>& rings = problem_.rings[p];
    for (int v : part.patches[0].fitted) {
      const std::vector<int>& ring = rings[static_cast<size_t>(v)];
      const double length = s_.normals[p][v].norm();
      if (ring.empty() || !(length > 0.0)) continue;
      const Eigen::Vector3d n = s_.normals[p][v] / length;
      const double share = 1.0 / static_cast<double>(ring.size());
      Eigen::Vector3d ring_posed = Eigen::Vector3d::Zero(), ring_move = Eigen::Vector3d::Zero();
      for (int u : ring) {
        ring_posed += posed(u);
        ring_move += move[static_cast<size_t>(u)];
      }
      const double rig = (posed(v) - share * ring_posed).dot(n);
      const double e = (move[static_cast<size_t>(v)] - share * ring_move).dot(n);
      const double a = rig - e;
      const double bound = std::abs(a) + tau;
      const double above = weight * (bound - rig), below = weight * (bound + rig);
      out->violation += std::pow(std::min(above, 0.0), 2) + std::pow(std::min(below, 0.0), 2);
      const double band = options.roughness_cap_band * weight * tau;
      const bool near_above = above < band, near_below = below < band;
      if (!near_above && !near_below) continue;
      if (measure_only) continue;
      const SparseRow row = laplacianRow(part, v, ring, n, weight);  // d(weight e) / d(amplitudes)
      if (near_above) {
        SparseRow negated = row;
        for (auto& entry : negated.entries) entry.second = -entry.second;
        model.sparse_hinges.push_back(std::move(negated));
        model.sparse_slack.push_back(above);
      }
      if (near_below) {
        model.sparse_hinges.push_back(row);
        model.sparse_slack.push_back(below);
      }
    }
  }
}

// The pose's skinning frames at the current responses, then the body's volume (returned) and each
// region's (into region_volume).
double PoseRowBuilder::measurePose(const RigEvaluation& evaluation, const Pose& pose, size_t pose_index,
                                   std::vector<double>* region_volume) {
  pose_ = pose_index;
  skinningFrame(problem_.skeleton, pose, evaluation, problem_.frames.bind_inverse, &s_.frame);
  prepareFloatSkinFrame(s_.frame, problem_.surfaces.skin_centre, 0, problem_.surfaces.no_pivots, &s_.float_frame);
  region_volume->assign(static_cast<size_t>(problem_.surfaces.region_count), 0.0);
  return measureVolumes(region_volume);
}

double PoseRowBuilder::regionExcess(const runtime::MuscleRig<double>& rig, const Pose& pose, size_t pose_index) {
  std::vector<double> region_volume;
  measurePose(evaluateRig(rig, pose, false), pose, pose_index, &region_volume);
  PoseRows rows;
  addRegionHinges(region_volume, true, &rows);
  return rows.region_excess;
}

// The pose's rows: the whole body's change always (weights make volumes fractions of their bind
// volume), the regions' and the skin floors' hinges near or past their bounds. `measure_only` leaves
// the Jacobian rows out: the last pass's would be thrown away.
void PoseRowBuilder::build(const runtime::MuscleRig<double>& rig, const Pose& pose, size_t pose_index, bool measure_only,
                           PoseRows* out) {
  const FitSurfaces& surfaces = problem_.surfaces;
  const ResponseFitOptions& options = problem_.options;
  const RigEvaluation evaluation = evaluateRig(rig, pose, false);
  std::vector<double> region_volume;
  const double body = measurePose(evaluation, pose, pose_index, &region_volume);
  setKeyMotion(evaluation);
  const double body_change = signedChange(body, surfaces.bind_body);
  HingeLinearModel& model = out->model;
  out->body_square = body_change * body_change;
  const double body_weight = options.body_weight / std::max(std::abs(surfaces.bind_body), 1e-30);
  // The body's row asks the muscles for the volume of the skin they move: the loss of the skin no
  // fitted muscle moves, down to a share of the input skinning's loss, is its target
  // (ResponseFitOptions::spare_unreached_losses).
  const double body_target = options.spare_unreached_losses
                                 ? std::max(std::min(problem_.fixed.unreached_change[pose_index], 0.0),
                                            options.spared_input_share * std::min(problem_.fixed.input_body_change[pose_index], 0.0))
                                 : 0.0;
  model.rhs.push_back(-body_weight * std::abs(surfaces.bind_body) * (body_change - body_target));
  if (!measure_only) {
    for (size_t p = 0; p < surfaces.parts.size(); ++p) {
      s_.body_shares[p].resize(static_cast<size_t>(surfaces.parts[p].first_share.back()));
      for (int w : surfaces.parts[p].patches[0].fitted) addBodyVertex(p, w);
    }
    model.rows.push_back(takeRow(body_weight));
  }
  addRegionHinges(region_volume, measure_only, out);
  if (options.skin_weight > 0.0 || problem_.roughness_scale > 0.0 || problem_.cap_scale > 0.0) {
    // The skin floors, the smoothness term and the roughness cap read the rig's move against the input skinning,
    // through each muscle's skinning matrix less its carrier's.
    const int joint_count = problem_.skeleton.size();
    for (size_t m = 0; m < problem_.muscles.parts.size(); ++m)
      s_.apart[m] = s_.frame[joint_count + m].matrix() - s_.frame[problem_.frames.carrier_of[m]].matrix();
  }
  if (options.skin_weight > 0.0) addSkinFloorHinges(evaluation, measure_only, out);
  if (problem_.roughness_scale > 0.0) addRoughness(measure_only, out);
  if (problem_.cap_scale > 0.0) addRoughnessCap(measure_only, out);
}

// Every active pose's rows (`active`: indices into `poses`, ascending) at the muscles' current responses,
// joined in that order, on `threads` threads; the root mean square of the body's change into *rms.
HingeEvaluation evaluateFit(const FitProblem& problem, const std::vector<Pose>& poses, const std::vector<size_t>& active,
                            bool measure_only, int threads, std::vector<PoseScratch>* scratch, double* rms) {
  const runtime::MuscleRig<double> rig = buildMuscleRig(problem.muscles, problem.skeleton);
  std::vector<PoseRows> pose_rows(active.size());
  parallelForWorkers(threads, active.size(), kPosesPerChunk, [&](size_t worker, size_t, size_t chunk_begin, size_t chunk_end) {
    PoseRowBuilder builder(problem, &(*scratch)[worker]);
    for (size_t i = chunk_begin; i < chunk_end; ++i) builder.build(rig, poses[active[i]], active[i], measure_only, &pose_rows[i]);
  });
  HingeEvaluation evaluation;
  HingeLinearModel& model = evaluation.model;
  double body_squares = 0.0;
  const int unknowns = problem.layout.unknowns();
  Eigen::MatrixXd rough_normal = Eigen::MatrixXd::Zero(unknowns, unknowns);
  Eigen::VectorXd rough_gradient = Eigen::VectorXd::Zero(unknowns);
  for (PoseRows& pose : pose_rows) {
    evaluation.objective += pose.rough_square;
    for (size_t a = 0; a < pose.rough_unknowns.size(); ++a) {
      const Eigen::Index ia = static_cast<Eigen::Index>(a);
      rough_gradient[pose.rough_unknowns[a]] += pose.rough_gradient[ia];
      for (size_t b = 0; b < pose.rough_unknowns.size(); ++b)
        rough_normal(pose.rough_unknowns[a], pose.rough_unknowns[b]) += pose.rough_normal(ia, static_cast<Eigen::Index>(b));
    }
    body_squares += pose.body_square;
    evaluation.objective += pose.violation;
    for (double r : pose.model.rhs) evaluation.objective += r * r;
    model.rhs.insert(model.rhs.end(), pose.model.rhs.begin(), pose.model.rhs.end());
    model.slack.insert(model.slack.end(), pose.model.slack.begin(), pose.model.slack.end());
    for (Eigen::VectorXd& row : pose.model.rows) model.rows.push_back(std::move(row));
    for (Eigen::VectorXd& row : pose.model.hinges) model.hinges.push_back(std::move(row));
    model.sparse_slack.insert(model.sparse_slack.end(), pose.model.sparse_slack.begin(), pose.model.sparse_slack.end());
    for (SparseRow& row : pose.model.sparse_hinges) model.sparse_hinges.push_back(std::move(row));
  }
  // The smoothness rows' normal equations N, g as rows: N = V L V^T, rows sqrt(l) v^T with right-hand
  // sides -(v . g) / sqrt(l), whose squares are the rows' own (the objective has them already).
  if (!measure_only && problem.roughness_scale > 0.0) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(rough_normal);
    const double largest = eigen.eigenvalues().maxCoeff();
    for (int i = 0; i < unknowns; ++i) {
      const double l = eigen.eigenvalues()[i];
      if (!(l > 1e-12 * largest)) continue;
      const Eigen::VectorXd v = eigen.eigenvectors().col(i);
      model.rows.push_back(std::sqrt(l) * v);
      model.rhs.push_back(-v.dot(rough_gradient) / std::sqrt(l));
    }
  }
  *rms = std::sqrt(body_squares / static_cast<double>(active.size()));
  return evaluation;
}

// At each of `checked`'s poses, how far its lowest region is below its dead zone at the muscles' current
// responses (0 when every region is within it).
std::vector<double> regionExcess(const FitProblem& problem, const std::vector<Pose>& poses, const std::vector<size_t>& checked,
                                 int threads, std::vector<PoseScratch>* scratch) {
  const runtime::MuscleRig<double> rig = buildMuscleRig(problem.muscles, problem.skeleton);
  std::vector<double> excess(checked.size(), 0.0);
  parallelForWorkers(threads, checked.size(), kPosesPerChunk, [&](size_t worker, size_t, size_t chunk_begin, size_t chunk_end) {
    PoseRowBuilder builder(problem, &(*scratch)[worker]);
    for (size_t i = chunk_begin; i < chunk_end; ++i) excess[i] = builder.regionExcess(rig, poses[checked[i]], checked[i]);
  });
  return excess;
}

}  // namespace

std::vector<double> driverFeatures(const runtime::MuscleRig<double>& rig, const MuscleSet& muscles,
                                   const std::vector<char>& fit, const Pose& pose) {
  const std::vector<runtime::MuscleDrivers<double>> drivers = evaluateRig(rig, pose, false).drivers;
  std::vector<double> features;
  for (size_t m = 0; m < muscles.parts.size(); ++m) {
    if (!fit[m]) continue;
    features.push_back(drivers[m].clamped_ratio - 1.0);
    features.push_back(sideTwist(muscles.parts[m], drivers[m]));
  }
  return features;
}

bool hasPresetResponse(const MusclePart& part) {
  const MuscleResponse preset = defaultResponse(part);
  auto same = [](const std::vector<ResponseKey>& a, const std::vector<ResponseKey>& b) {
    if (a.size() != b.size()) return false;
    for (size_t k = 0; k < a.size(); ++k) {
      if (a[k].at != b[k].at || a[k].up != b[k].up || a[k].side != b[k].side || a[k].scale != b[k].scale) return false;
    }
    return true;
  };
  return !part.response.fitted && same(part.response.ratio, preset.ratio) && same(part.response.twist, preset.twist);
}


ResponseFitReport fitMuscleResponses(const Character& character, const std::vector<BodyRegion>& regions,
                                     const std::vector<MeasuredPart>& parts, const std::vector<Pose>& fit_poses,
                                     const std::vector<Pose>& check_poses, const std::vector<char>& fit, MuscleSet* muscles,
                                     const ResponseFitOptions& options, int threads) {
  const Skeleton& skeleton = character.skeleton;
  const size_t muscle_count = muscles->parts.size();
  assert(fit.size() == muscle_count);
  ResponseFitReport report;
  report.poses = static_cast<int>(fit_poses.size());
  std::set<std::string> kind_names;
  for (size_t m = 0; m < muscle_count; ++m) {
    if (!fit[m]) continue;
    kind_names.insert(muscles->parts[m].name);
    ++report.fitted_parts;
  }
  report.parameters = static_cast<int>(kind_names.size()) * kKeys;
  if (report.parameters == 0 || fit_poses.empty()) return report;

  // The drivers at every fitted pose do not depend on the response: the keys are placed where they take
  // the muscles before anything is fitted.
  std::vector<std::vector<runtime::MuscleDrivers<double>>> pose_drivers(fit_poses.size());
  {
    const runtime::MuscleRig<double> rig = buildMuscleRig(*muscles, skeleton);
    for (size_t i = 0; i < fit_poses.size(); ++i) pose_drivers[i] = evaluateRig(rig, fit_poses[i], false).drivers;
  }
  // The fitted poses, then the checked ones: the fixed pieces are measured at all of them at once.
  std::vector<Pose> poses = fit_poses;
  if (options.every_frame_regions && options.region_check_rounds > 0 && options.region_check_poses > 0 && !options.occupied_volume)
    poses.insert(poses.end(), check_poses.begin(), check_poses.end());
  const ResponseLayout layout = layoutResponses(*muscles, fit, pose_drivers);
  assert(layout.unknowns() == report.parameters);
  const Eigen::VectorXd talk = talkAmplitudes(layout, *muscles);
  const MuscleFrames frames = muscleFrames(*muscles, skeleton, layout);
  FitSurfaces surfaces = buildFitSurfaces(character, regions, parts, *muscles, layout.kind, frames.bind_inverse, threads);

  const char* const kStage = "fitting the muscles' response";
  const bool checking = poses.size() > fit_poses.size();
  const int solve_passes = options.iterations + 1;
  const int passes = 1 + solve_passes + (checking ? options.region_check_rounds * (1 + solve_passes) : 0);
  reportProgress(options.progress, kStage, 0, passes);
  applyAmplitudes(layout, talk, muscles);
  const FixedPieces fixed = measureFixedPieces(skeleton, poses, buildMuscleRig(*muscles, skeleton), frames.bind_inverse,
                                                options.occupied_volume, threads, &surfaces);

  // The prior: the talk's amplitudes, each scaled by how far the poses drive its key. Each pose's rows
  // stand for options.pose_weight poses of the clips: the prior is weighed against that many, so a fit
  // over every third frame balances its terms as one over every frame would.
  HingePrior prior;
  prior.target = talk;
  auto priorWeight = [&](size_t active_poses) {
    const double pose_weight = options.pose_weight * static_cast<double>(fit_poses.size()) / static_cast<double>(active_poses);
    return options.prior_weight / std::sqrt(std::max(pose_weight, 1e-6));
  };
  prior.weight = priorWeight(fit_poses.size());
  const std::vector<double> reach = keyReach(layout, *muscles, pose_drivers);
  prior.scale.resize(layout.unknowns());
  for (int u = 0; u < layout.unknowns(); ++u) prior.scale[u] = std::max(reach[u], 1e-3);

  // The skin and smoothness rows weigh lengths against the volume rows' ratios: taken per body height
  // (so much per metre of a 1.8 m body), a character's fit does not depend on its scene's unit. Per
  // metre, a body in centimetres weighed them 10,000 times more and kept almost none of the volume.
  const double per_height = kReferenceBodyHeight / muscles->body_height;
  // The smoothness term's and the roughness cap's one-rings, over the whole surface's moving piece: only
  // when there is either.
  std::vector<std::vector<std::vector<int>>> rings;
  double roughness_scale = 0.0, cap_scale = 0.0;
  if (options.smoothness_weight > 0.0 || options.roughness_cap > 0.0) {
    size_t fitted_vertices = 0;
    for (const FitPart& part : surfaces.parts) {
      const bool any = part.patches[0].first_vertex >= 0;
      rings.push_back(oneRings(any ? part.patches[0].moving.triangles : std::vector<std::array<int, 3>>{}, part.moving_vertices.size()));
      if (any) fitted_vertices += part.patches[0].fitted.size();
    }
    const double per_vertex = fitted_vertices > 0 ? per_height / std::sqrt(static_cast<double>(fitted_vertices)) : 0.0;
    roughness_scale = options.smoothness_weight * per_vertex;
    if (options.roughness_cap > 0.0) cap_scale = options.roughness_cap_weight * per_vertex;
  }
  // The cap's bound at each fitted pose: the input skinning's roughness rise there, as the figure takes it.
  std::vector<double> input_rise;
  if (cap_scale > 0.0) {
    std::vector<SkinFrame> input_frames(poses.size());
    for (size_t i = 0; i < poses.size(); ++i)
      for (int j = 0; j < skeleton.size(); ++j) input_frames[i].push_back(skinMatrix(poses[i], skeleton, j));
    input_rise = inputRoughnessRise(character, parts, skeleton.size(), muscles->body_height, threads, input_frames);
  }
  const FitProblem problem{skeleton, *muscles, layout, options, frames, surfaces, fixed,
                           options.compressed_in_share * muscles->body_height, options.stretch_hollow_share * muscles->body_height,
                           options.skin_band_share * muscles->body_height, options.skin_weight * per_height,
                           options.every_frame_regions ? options.every_frame_region_weight : options.region_weight, rings, roughness_scale,
                           cap_scale, kRoughnessFloorPerHeight * muscles->body_height, input_rise};
  std::vector<PoseScratch> scratch(parallelWorkerCount(threads, poses.size(), kPosesPerChunk));
  for (PoseScratch& worker : scratch) worker = poseScratch(surfaces.parts, muscle_count);
  std::vector<double> rms(static_cast<size_t>(options.iterations) + 1, 0.0);
  std::vector<size_t> active(fit_poses.size());
  std::iota(active.begin(), active.end(), size_t{0});
  int passes_done = 1;
  auto evaluate = [&](const Eigen::VectorXd& amplitudes, int evaluation, bool measure_only) {
    reportProgress(options.progress, kStage, passes_done + evaluation, passes);
    applyAmplitudes(layout, amplitudes, muscles);
    return evaluateFit(problem, poses, active, measure_only, threads, &scratch, &rms[static_cast<size_t>(evaluation)]);
  };
  HingeSolveOptions solve;
  solve.iterations = options.iterations;
  solve.initial_damping = options.initial_damping;
  // Measured on the mannequin, VRM 1.0, CesiumMan and Cyberpunk: the hinges' active set settles after 1
  // to 7 re-solves; three of the four fits reach the cap once, and that step is taken as it stands.
  solve.hinge_passes = 8;
  const HingeBounds bounds = amplitudeBounds(layout, talk, options);
  HingeSolveResult result = solveHingeLeastSquares(talk, prior, bounds, evaluate, solve);
  report.body_rms_before = rms[0];
  report.body_rms_after = result.best_evaluation >= 0 ? rms[static_cast<size_t>(result.best_evaluation)] : 0.0;
  // The checked poses: where a region falls below its dead zone by more than region_check_tolerance at
  // one the fit did not see, the worst of them join the fit and it goes on from where it was.
  for (int round = 0; checking && round < options.region_check_rounds; ++round) {
    passes_done += solve_passes;
    reportProgress(options.progress, kStage, passes_done, passes);
    ++passes_done;
    applyAmplitudes(layout, result.theta, muscles);
    std::vector<size_t> unseen;
    for (size_t i = fit_poses.size(), a = 0; i < poses.size(); ++i) {
      while (a < active.size() && active[a] < i) ++a;
      if (a == active.size() || active[a] != i) unseen.push_back(i);
    }
    const std::vector<double> excess = regionExcess(problem, poses, unseen, threads, &scratch);
    std::vector<size_t> order;
    for (size_t k = 0; k < unseen.size(); ++k)
      if (excess[k] > options.region_check_tolerance) order.push_back(k);
    if (order.empty()) break;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return excess[a] > excess[b]; });
    order.resize(std::min(order.size(), static_cast<size_t>(options.region_check_poses)));
    for (size_t k : order) active.push_back(unseen[k]);
    std::sort(active.begin(), active.end());
    report.added_poses += static_cast<int>(order.size());
    prior.weight = priorWeight(active.size());
    const HingeSolveResult next = solveHingeLeastSquares(result.theta, prior, bounds, evaluate, solve);
    if (next.best_evaluation >= 0) report.body_rms_after = rms[static_cast<size_t>(next.best_evaluation)];
    result = next;
  }
  if (checking) reportProgress(options.progress, kStage, passes, passes);
  applyAmplitudes(layout, result.theta, muscles);
  return report;
}

}  // namespace rigbake
