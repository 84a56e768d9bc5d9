// The response fit (pipeline/response_fit.h). The talk's response has a shape: at full compression the
// preset's bulge vector and the volume-preserving across-fibre scale 1 / sqrt(compression); at full
// stretch the thinning 1 / sqrt(stretch). The fit keeps those shapes and solves, per muscle kind (a part
// name: left and right share it, mirrored), four amplitudes: of the compression key, of the stretch key,
// and of a twist key a quarter turn each way (the compression shape, driven by twist). Amplitude 1 is
// the talk's response; linear set-driven keys in between, rest = no response. Residuals: the whole
// body's volume change at every fitted pose, each region's change where it leaves its dead zone, and a
// prior towards the talk's amplitudes (1 when compressed, 0 otherwise: a stretched muscle does not
// thin unless volume asks for it). Bounds are kept by an active set: a violated amplitude is held at
// its bound and the rest solved again.
#include "pipeline/response_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>

#include "pipeline/muscle_joint.h"
#include "pipeline/parallel.h"
#include "pipeline/skinning.h"
#include "pipeline/skin_volume.h"

namespace rigbake {
namespace {

constexpr double kQuarterTurn = 3.14159265358979323846 / 2.0;
constexpr int kKeys = 4;  // compressed, stretched, twisted +, twisted -
enum Key { kCompressed = 0, kStretched = 1, kTwistPositive = 2, kTwistNegative = 3 };

// A key's response at amplitude 1: offsets along up and side (metres) and scale - 1.
struct KeyShape {
  double up = 0.0, side = 0.0, scale = 0.0;
};

KeyShape keyShape(const MusclePart& part, int key) {
  const double bulge_scale = part.compression < 1.0 ? 1.0 / std::sqrt(part.compression) - 1.0 : 0.0;
  switch (key) {
    case kCompressed: return {part.bulge.x(), part.bulge.y(), bulge_scale};
    case kStretched: return {0.0, 0.0, 1.0 / std::sqrt(part.stretch) - 1.0};
    default: return {part.bulge.x(), 0.0, bulge_scale};
  }
}

// Key weights of one part at its drivers (the linear set-driven keys' hat functions).
void keyWeights(const MusclePart& part, const runtime::MuscleDrivers<double>& drivers, double weights[kKeys]) {
  const double r = drivers.clamped_ratio;
  weights[kCompressed] = r < 1.0 && part.compression < 1.0 ? (1.0 - r) / (1.0 - part.compression) : 0.0;
  weights[kStretched] = r > 1.0 && part.stretch > 1.0 ? (r - 1.0) / (part.stretch - 1.0) : 0.0;
  // The right side's twist runs the other way: its keys are the left's, mirrored.
  const double twist = std::clamp((part.side == "Right" ? -drivers.twist : drivers.twist) / kQuarterTurn, -1.0, 1.0);
  weights[kTwistPositive] = std::max(twist, 0.0);
  weights[kTwistNegative] = std::max(-twist, 0.0);
}

struct MuscleVertex {
  int muscle;
  double weight;        // the muscle's skin weight at the vertex
  Eigen::Vector3d q;    // the vertex in the skinned joint's bind frame
};

// A patch's triangles and holes with a fitted muscle's vertex, in the patch's order: each of those
// vertices gets the whole patch's gradient from them to the bit (addVolumeGradientAbout(), about the
// patch's first vertex as addVolumeGradient() sums).
struct GradientPiece {
  bool empty = true;  // the patch has no triangles: no gradient
  ClosedPatch piece;  // welded indices
  int origin = -1;    // the patch's first vertex
  std::vector<int> touched;  // the welded vertices of the piece, ascending
};

GradientPiece gradientPiece(const ClosedPatch& patch, const std::vector<char>& fitted) {
  GradientPiece out;
  if (patch.triangles.empty()) return out;
  out.empty = false;
  out.origin = patch.triangles[0][0];
  std::vector<int> touched;
  for (const auto& t : patch.triangles) {
    if (!fitted[t[0]] && !fitted[t[1]] && !fitted[t[2]]) continue;
    out.piece.triangles.push_back(t);
    touched.insert(touched.end(), t.begin(), t.end());
  }
  for (const std::vector<int>& hole : patch.holes) {
    if (std::none_of(hole.begin(), hole.end(), [&](int w) { return fitted[w] != 0; })) continue;
    out.piece.holes.push_back(hole);
    touched.insert(touched.end(), hole.begin(), hole.end());
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  out.touched = std::move(touched);
  return out;
}

struct FitPart {
  const MeshPart* mesh = nullptr;
  const MeasuredPart* weights = nullptr;
  VolumeSurface surface;
  std::vector<ClosedPatch> regions;
  std::vector<std::vector<MuscleVertex>> muscle_vertices;  // per welded vertex
  std::vector<int> muscle_welded;  // the welded vertices with muscle vertices, ascending
  // The gradient is only read at muscle_welded: per patch (the whole, then each region), the
  // triangles and holes around those vertices, in order, and the vertices they touch.
  std::vector<GradientPiece> gradient_pieces;
};

double signedChange(double volume, double reference) { return reference != 0.0 ? volume / reference - 1.0 : 0.0; }

}  // namespace

bool hasPresetResponse(const MusclePart& part) {
  const MuscleResponse preset = defaultMuscleResponse(part.compression, part.stretch, part.bulge);
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
                                     const std::vector<MeasuredPart>& parts, const std::vector<Pose>& poses,
                                     const std::vector<char>& fit, MuscleSet* muscles, const ResponseFitOptions& options,
                                     int threads) {
  const Skeleton& skeleton = character.skeleton;
  const int joint_count = skeleton.size();
  const int muscle_count = static_cast<int>(muscles->parts.size());
  assert(static_cast<int>(fit.size()) == muscle_count);
  ResponseFitReport report;
  report.poses = static_cast<int>(poses.size());

  // Kinds: one per fitted part name, in part order.
  std::map<std::string, int> kind_of_name;
  std::vector<int> kind(muscle_count, -1);
  for (int m = 0; m < muscle_count; ++m) {
    if (!fit[m]) continue;
    kind[m] = kind_of_name.emplace(muscles->parts[m].name, static_cast<int>(kind_of_name.size())).first->second;
    ++report.fitted_parts;
  }
  const int kinds = static_cast<int>(kind_of_name.size());
  const int unknowns = kinds * kKeys;
  report.parameters = unknowns;
  if (unknowns == 0 || poses.empty()) return report;

  // The talk's amplitudes are the prior and the start.
  Eigen::VectorXd prior = Eigen::VectorXd::Zero(unknowns);
  for (int k = 0; k < kinds; ++k) prior[k * kKeys + kCompressed] = 1.0;
  Eigen::VectorXd theta = prior;

  auto applyTheta = [&](const Eigen::VectorXd& amplitudes) {
    for (int m = 0; m < muscle_count; ++m) {
      if (kind[m] < 0) continue;
      MusclePart& part = muscles->parts[m];
      const double* a = amplitudes.data() + kind[m] * kKeys;
      auto key = [&](double at, int which) {
        const KeyShape shape = keyShape(part, which);
        return ResponseKey{at, a[which] * shape.up, a[which] * shape.side, 1.0 + a[which] * shape.scale};
      };
      MuscleResponse response;
      response.fitted = true;
      if (part.compression < 1.0) response.ratio.push_back(key(part.compression, kCompressed));
      response.ratio.push_back({1.0, 0.0, 0.0, 1.0});
      if (part.stretch > 1.0) response.ratio.push_back(key(part.stretch, kStretched));
      // The right side's keys are the left's mirrored: its positive twist is the left's negative one.
      const bool right = part.side == "Right";
      response.twist = {key(-kQuarterTurn, right ? kTwistPositive : kTwistNegative), {0.0, 0.0, 0.0, 1.0},
                        key(kQuarterTurn, right ? kTwistNegative : kTwistPositive)};
      part.response = response;
    }
  };

  // Surfaces, regions (those the figures measure), and which vertices each fitted muscle moves.
  std::vector<int> mesh_parts;
  for (const MeasuredPart& part : parts) mesh_parts.push_back(part.mesh_part);
  std::vector<std::vector<std::vector<int>>> region_triangles;
  for (const BodyRegion& region : regions) region_triangles.push_back(region.triangles);
  MeasuredSurfaces measured = measuredSurfaces(character, mesh_parts, region_triangles, 1e-6 * std::max(muscles->body_height, 1e-3));
  std::vector<size_t> kept;
  for (size_t r = 0; r < regions.size(); ++r) {
    if (measured.region_measured[r]) kept.push_back(r);
  }
  const int region_count = static_cast<int>(kept.size());
  std::vector<FitPart> fit_parts;
  std::vector<Eigen::Affine3d> bind_inverse(muscle_count);
  for (int m = 0; m < muscle_count; ++m) bind_inverse[m] = muscleBindTransform(muscles->parts[m], skeleton).inverse();
  // Per muscle, what the Jacobian's inner loop needs and the fit does not change: the skinned joint's
  // bind axes, its side and its keys' shapes.
  std::vector<Eigen::Matrix3d> bind_axes(muscle_count);
  std::vector<double> side_sign(muscle_count);
  std::vector<std::array<KeyShape, kKeys>> shapes(muscle_count);
  for (int m = 0; m < muscle_count; ++m) {
    bind_axes[m] = bind_inverse[m].inverse().linear();
    side_sign[m] = muscles->parts[m].side == "Right" ? -1.0 : 1.0;
    for (int k = 0; k < kKeys; ++k) shapes[m][k] = keyShape(muscles->parts[m], k);
  }
  for (size_t p = 0; p < parts.size(); ++p) {
    FitPart part;
    part.mesh = &character.meshes[parts[p].mesh_part];
    part.weights = &parts[p];
    part.surface = std::move(measured.surfaces[p]);
    for (size_t r : kept) part.regions.push_back(std::move(measured.regions[p][r]));
    part.muscle_vertices.resize(part.surface.weldedCount());
    const InfluenceSet& rig = parts[p].rig;
    for (int w = 0; w < part.surface.weldedCount(); ++w) {
      const int v = part.surface.vertex_of_weld[w];
      for (int k = 0; k < rig.slots_per_vertex; ++k) {
        const int m = rig.joints[v * rig.slots_per_vertex + k] - joint_count;
        const double weight = rig.weights[v * rig.slots_per_vertex + k];
        if (m < 0 || m >= muscle_count || kind[m] < 0 || weight <= 0.0) continue;
        part.muscle_vertices[w].push_back({m, weight, bind_inverse[m] * part.mesh->positions[v]});
      }
      if (!part.muscle_vertices[w].empty()) part.muscle_welded.push_back(w);
    }
    std::vector<char> fitted(part.surface.weldedCount(), 0);
    for (int w : part.muscle_welded) fitted[w] = 1;
    part.gradient_pieces.push_back(gradientPiece(part.surface.whole, fitted));
    for (const ClosedPatch& region : part.regions) part.gradient_pieces.push_back(gradientPiece(region, fitted));
    fit_parts.push_back(std::move(part));
  }
  const double bind_body = measured.body_volume;
  std::vector<double> bind_region;
  for (size_t r : kept) bind_region.push_back(measured.region_volumes[r]);
  // Input-skinning region changes per pose: the dead zones do not depend on the fit.
  std::vector<std::vector<double>> input_region_change(poses.size(), std::vector<double>(region_count, 0.0));
  parallelForEach(threads, poses.size(), [&](size_t i) {
    std::vector<Eigen::Affine3d> frame(joint_count);
    for (int j = 0; j < joint_count; ++j) frame[j] = skinMatrix(poses[i], skeleton, j);
    std::vector<double> volume(region_count, 0.0);
    std::vector<Eigen::Vector3d> welded;
    for (const FitPart& part : fit_parts) {
      skinLinearBlend(part.mesh->positions, part.weights->input, frame, part.surface.vertex_of_weld, &welded);
      for (int r = 0; r < region_count; ++r) volume[r] += enclosedVolume(part.regions[r], welded);
    }
    for (int r = 0; r < region_count; ++r) input_region_change[i][r] = signedChange(volume[r], bind_region[r]);
  });

  // How far the poses drive each key (its largest hat weight): the prior bounds the response the poses
  // actually see, so a key the clips barely reach cannot grow without limit, and a key they never
  // reach keeps its prior value.
  std::vector<double> reach(unknowns, 0.0);
  {
    const runtime::MuscleRig<double> rig = buildMuscleRig(*muscles, skeleton);
    for (const Pose& pose : poses) {
      const RigEvaluation evaluation = evaluateRig(rig, pose, false);
      for (int m = 0; m < muscle_count; ++m) {
        if (kind[m] < 0) continue;
        double weights[kKeys];
        keyWeights(muscles->parts[m], evaluation.drivers[m], weights);
        for (int k = 0; k < kKeys; ++k) reach[kind[m] * kKeys + k] = std::max(reach[kind[m] * kKeys + k], weights[k]);
      }
    }
  }
  // Levenberg-Marquardt: a step that does not lower the objective is taken back and the damping raised.
  Eigen::VectorXd best_theta = theta;
  double best_objective = std::numeric_limits<double>::infinity();
  double best_rms = 0.0;
  Eigen::MatrixXd best_a;
  Eigen::VectorXd best_b;
  double damping = 1e-3;
  for (int iteration = 0; iteration <= options.iterations; ++iteration) {
    applyTheta(theta);
    const runtime::MuscleRig<double> rig = buildMuscleRig(*muscles, skeleton);
    // Each pose's rows are built on its own and joined in pose order, so any thread count gives the
    // same system. The last pass only measures: its Jacobian rows would be thrown away.
    const bool measure_only = iteration == options.iterations;
    struct PoseRows {
      std::vector<Eigen::VectorXd> rows;
      std::vector<double> rhs;
      double body_square = 0.0;
    };
    std::vector<PoseRows> pose_rows(poses.size());
    // A few poses per chunk, which keeps its posed vertices and gradients from pose to pose.
    constexpr size_t kPosesPerChunk = 4;
    parallelFor(threads, poses.size(), kPosesPerChunk, [&](size_t, size_t chunk_begin, size_t chunk_end) {
    std::vector<std::vector<Eigen::Vector3d>> posed(fit_parts.size());
    std::vector<std::vector<Eigen::Vector3d>> gradients(fit_parts.size());
    for (size_t p = 0; p < fit_parts.size(); ++p) gradients[p].assign(fit_parts[p].surface.weldedCount(), Eigen::Vector3d::Zero());
    for (size_t i = chunk_begin; i < chunk_end; ++i) {
      const Pose& pose = poses[i];
      const RigEvaluation evaluation = evaluateRig(rig, pose, false);
      std::vector<Eigen::Affine3d> frame(joint_count + muscle_count);
      for (int j = 0; j < joint_count; ++j) frame[j] = skinMatrix(pose, skeleton, j);
      for (int m = 0; m < muscle_count; ++m) frame[joint_count + m] = matrixAt(evaluation.skinned, m) * bind_inverse[m];
      std::vector<std::array<double, kKeys>> key_weight(muscle_count);
      for (int m = 0; m < muscle_count; ++m) keyWeights(muscles->parts[m], evaluation.drivers[m], key_weight[m].data());
      // d p / d (offset up) and d p / d (scale): the skinned joint's rest axes as posed.
      std::vector<Eigen::Matrix3d> axes(muscle_count);
      for (int m = 0; m < muscle_count; ++m) axes[m] = frame[muscleCarrierJoint(muscles->parts[m])].linear() * bind_axes[m];

      double body = 0.0;
      std::vector<double> region_volume(region_count, 0.0);
      for (size_t p = 0; p < fit_parts.size(); ++p) {
        const FitPart& part = fit_parts[p];
        skinLinearBlend(part.mesh->positions, part.weights->rig, frame, part.surface.vertex_of_weld, &posed[p]);
        body += enclosedVolume(part.surface.whole, posed[p]);
        for (int r = 0; r < region_count; ++r) region_volume[r] += enclosedVolume(part.regions[r], posed[p]);
      }
      const double body_change = signedChange(body, bind_body);
      PoseRows& out = pose_rows[i];
      out.body_square = body_change * body_change;
      // Rows: the body always; a region when it leaves its dead zone (then towards the nearer edge).
      struct Row {
        int region;  // -1: the whole body
        double weight, residual;
      };
      std::vector<Row> active = {{-1, options.body_weight / std::max(std::abs(bind_body), 1e-30), body_change}};
      for (int r = 0; r < region_count; ++r) {
        if (bind_region[r] == 0.0) continue;
        const double change = signedChange(region_volume[r], bind_region[r]);
        const double lower = std::min(input_region_change[i][r], 0.0) - options.region_margin;
        const double upper = std::max(input_region_change[i][r], 0.0) + options.region_gain;
        if (change >= lower && change <= upper) continue;
        const double target = change < lower ? lower : upper;
        active.push_back({r, options.region_weight / std::abs(bind_region[r]), change - target});
      }
      for (const Row& row : active) {
        out.rhs.push_back(-row.weight * std::abs(row.region < 0 ? bind_body : bind_region[row.region]) * row.residual);
        if (measure_only) continue;
        Eigen::VectorXd jacobian = Eigen::VectorXd::Zero(unknowns);
        for (size_t p = 0; p < fit_parts.size(); ++p) {
          const FitPart& part = fit_parts[p];
          // The gradient of the row's patch at the fitted muscles' vertices, from the triangles around
          // them only; the entries it touches are zeroed again for the next row.
          std::vector<Eigen::Vector3d>& gradient = gradients[p];
          const GradientPiece& piece = part.gradient_pieces[static_cast<size_t>(row.region + 1)];
          if (!piece.empty) addVolumeGradientAbout(piece.piece, posed[p], posed[p][piece.origin], 1.0, &gradient);
          for (int w : part.muscle_welded) {
            if (gradient[w].isZero()) continue;
            for (const MuscleVertex& mv : part.muscle_vertices[w]) {
              const Eigen::Matrix3d& muscle_axes = axes[mv.muscle];
              const double along_up = mv.weight * gradient[w].dot(muscle_axes.col(1));
              const double along_side = mv.weight * side_sign[mv.muscle] * gradient[w].dot(muscle_axes.col(2));
              const double along_scale =
                  mv.weight * gradient[w].dot(muscle_axes.col(1) * mv.q.y() + muscle_axes.col(2) * mv.q.z());
              const int base = kind[mv.muscle] * kKeys;
              for (int k = 0; k < kKeys; ++k) {
                const double phi = key_weight[mv.muscle][k];
                if (phi == 0.0) continue;
                const KeyShape& shape = shapes[mv.muscle][k];
                jacobian[base + k] += phi * (shape.up * along_up + shape.side * along_side + shape.scale * along_scale);
              }
            }
          }
          for (int w : piece.touched) gradient[w].setZero();
        }
        out.rows.push_back(row.weight * jacobian);
      }
    }
    });
    std::vector<Eigen::VectorXd> rows;
    std::vector<double> rhs;
    double body_squares = 0.0;
    for (PoseRows& pose : pose_rows) {
      body_squares += pose.body_square;
      rhs.insert(rhs.end(), pose.rhs.begin(), pose.rhs.end());
      for (Eigen::VectorXd& row : pose.rows) rows.push_back(std::move(row));
    }
    const double rms = std::sqrt(body_squares / static_cast<double>(poses.size()));
    if (iteration == 0) report.body_rms_before = rms;
    double objective = 0.0;
    for (double r : rhs) objective += r * r;
    for (int u = 0; u < unknowns; ++u) {
      const double prior_residual = options.prior_weight * (theta[u] - prior[u]) * std::max(reach[u], 1e-3);
      objective += prior_residual * prior_residual;
    }
    // The objective counts the regions that left their dead zone at this pose set; its rows exist only
    // while measuring (the last pass builds none), so the comparison uses the same rows each time.
    const bool better = objective < best_objective;
    if (better) {
      best_objective = objective;
      best_theta = theta;
      best_rms = rms;
      damping = std::max(damping / 3.0, 1e-6);
    } else {
      theta = best_theta;
      damping *= 10.0;
    }
    if (iteration == options.iterations) break;

    // Solve for the step with the prior, keeping the bounds.
    const int n = static_cast<int>(rows.size());
    Eigen::MatrixXd a(n + unknowns, unknowns);
    Eigen::VectorXd b(n + unknowns);
    for (int r = 0; r < n; ++r) {
      a.row(r) = rows[r].transpose();
      b[r] = rhs[r];
    }
    for (int u = 0; u < unknowns; ++u) {
      const double unit = 1.0 / std::max(reach[u], 1e-3);
      a.row(n + u).setZero();
      a(n + u, u) = options.prior_weight / unit;
      b[n + u] = options.prior_weight * (prior[u] - theta[u]) / unit;
    }
    if (better) {
      best_a = a;
      best_b = b;
    } else {
      a = best_a;
      b = best_b;
    }
    {
      // Damping rows (Marquardt): sqrt(lambda * diag(A^T A)) * step = 0, so the damping scales with
      // how strongly each amplitude moves the volumes.
      const Eigen::Index rows_before = a.rows();
      const Eigen::VectorXd diagonal = a.colwise().squaredNorm().transpose();
      a.conservativeResize(rows_before + unknowns, Eigen::NoChange);
      b.conservativeResize(rows_before + unknowns);
      a.bottomRows(unknowns).setZero();
      for (int u = 0; u < unknowns; ++u) a(rows_before + u, u) = std::sqrt(damping * std::max(diagonal[u], 1e-12));
      b.tail(unknowns).setZero();
    }
    auto lowerBound = [&](int u) {
      const int key = u % kKeys;
      return key == kCompressed || key == kStretched ? 0.0 : -options.min_twist_amplitude;
    };
    auto upperBound = [&](int u) {
      const int key = u % kKeys;
      return key == kStretched ? options.max_stretch_amplitude : (key == kCompressed ? options.max_amplitude : options.max_twist_amplitude);
    };
    // fixed[u]: 0 free, -1 held at its lower bound, +1 at its upper bound.
    std::vector<int> fixed(unknowns, 0);
    auto heldAt = [&](int u) { return fixed[u] < 0 ? lowerBound(u) : upperBound(u); };
    Eigen::VectorXd step = Eigen::VectorXd::Zero(unknowns);
    for (int pass = 0; pass <= unknowns; ++pass) {
      std::vector<int> free;
      Eigen::VectorXd b_free = b;
      for (int u = 0; u < unknowns; ++u) {
        if (fixed[u] != 0) b_free -= a.col(u) * (heldAt(u) - theta[u]);
        else free.push_back(u);
      }
      Eigen::VectorXd x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(free.size()));
      if (!free.empty()) {
        Eigen::MatrixXd a_free(a.rows(), static_cast<Eigen::Index>(free.size()));
        for (size_t c = 0; c < free.size(); ++c) a_free.col(static_cast<Eigen::Index>(c)) = a.col(free[c]);
        x = a_free.colPivHouseholderQr().solve(b_free);
      }
      for (int u = 0; u < unknowns; ++u) step[u] = fixed[u] != 0 ? heldAt(u) - theta[u] : 0.0;
      for (size_t c = 0; c < free.size(); ++c) step[free[c]] = x[static_cast<Eigen::Index>(c)];
      bool changed = false;
      for (int u : free) {
        if (theta[u] + step[u] < lowerBound(u) - 1e-12) {
          fixed[u] = -1;
          changed = true;
        } else if (theta[u] + step[u] > upperBound(u) + 1e-12) {
          fixed[u] = 1;
          changed = true;
        }
      }
      if (!changed) break;
    }
    theta += step;
  }
  report.body_rms_after = best_rms;
  applyTheta(best_theta);
  return report;
}

}  // namespace rigbake
