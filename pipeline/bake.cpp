#include "pipeline/bake.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <functional>

#include "core/error.h"
#include "pipeline/surface_graph.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/influence_refit.h"
#include "pipeline/joint_regions.h"
#include "pipeline/parallel.h"
#include "pipeline/pose.h"
#include "pipeline/quantize_for_motion.h"
#include "pipeline/seam_opening.h"
#include "pipeline/seam_rounding.h"
#include "pipeline/skin_volume.h"
#include "pipeline/surface_figures.h"

namespace rigbake {

std::string muscleJointName(const MusclePart& part, MuscleJointRole role) {
  switch (role) {
    case MuscleJointRole::kBase: return part.fullName() + "_muscleBase";
    case MuscleJointRole::kTip: return part.fullName() + "_muscleTip";
    case MuscleJointRole::kDriver: return part.fullName() + "_muscleDriver";
    case MuscleJointRole::kSkinned: return part.fullName() + "_muscleSkinned";
  }
  return part.fullName();
}

namespace {

constexpr std::array<MuscleJointRole, 4> kRoles = {MuscleJointRole::kBase, MuscleJointRole::kTip, MuscleJointRole::kDriver,
                                                  MuscleJointRole::kSkinned};

// Base and driver ride the origin attach joint, the tip the insertion joint (the talk's attachments);
// the skinned joint rides its carrier, the joint whose skin weight it takes.
int parentOf(const MusclePart& part, MuscleJointRole role) {
  switch (role) {
    case MuscleJointRole::kTip: return part.insertion.joint;
    case MuscleJointRole::kSkinned: return muscleCarrierJoint(part);
    default: return part.origin.joint;
  }
}

// World transform of muscle m's joint in one evaluation of the rig (helpers: base, tip, driver).
Eigen::Affine3d roleWorld(const RigEvaluation& evaluation, int m, MuscleJointRole role) {
  if (role == MuscleJointRole::kSkinned) return matrixAt(evaluation.skinned, m);
  return matrixAt(evaluation.helpers, 3 * static_cast<size_t>(m) + static_cast<size_t>(role));
}

Trs localTrs(const Eigen::Affine3d& world, const Pose& pose, int parent) {
  return decomposeTrs(pose.world[parent].inverse() * world);
}

// A muscle jiggle follows the muscle's skinned joint as the muscle model moves it, so its frames are
// the evaluated muscle at every frame time the fixed-step simulation asks for.
JiggleTrack simulateMuscleJiggle(const JiggleSetup& setup, const MuscleSet& muscles, const Skeleton& skeleton,
                                 const Clip& clip, const std::vector<double>& times, const std::vector<HitImpulse>& hits) {
  const MusclePart& part = muscles.parts[setup.muscle];
  const std::vector<double> frame_times = jiggleFrameTimes(times);
  std::vector<JiggleFrame> frames;
  frames.reserve(frame_times.size());
  for (double time : frame_times) {
    const Pose pose = sampleClip(skeleton, clip, time);
    JiggleFrame frame;
    frame.parent = pose.world[parentOf(part, MuscleJointRole::kSkinned)];
    frame.root = pose.world[setup.root >= 0 ? setup.root : part.origin.joint];
    frame.pivot = evaluateMuscle(part, skeleton, pose).skinned;
    frames.push_back(frame);
  }
  return simulateJiggleFrames(setup, times, frame_times, frames, hits, clip.name);
}

// Every jiggle of one clip, in setup order; a muscle jiggle's track also replaces its skinned joint's
// samples (and skin matrices) so the file and the deformation figures see the jiggled joint.
std::vector<JiggleTrack> bakeJiggles(const Skeleton& skeleton, const MuscleSet& muscles, const Clip& clip,
                                     const std::vector<Pose>& poses, const BakeOptions& options,
                                     const BakeResult& result, BakedClip* baked, std::vector<SkinFrame>* frames) {
  std::vector<JiggleTrack> skeleton_tracks = simulateJiggle(skeleton, clip, baked->times, options.jiggles, options.hits);
  std::vector<JiggleTrack> tracks;
  size_t next_skeleton_track = 0;
  for (const JiggleSetup& setup : options.jiggles) {
    if (setup.host == JiggleHost::kSkeletonJoint) {
      tracks.push_back(std::move(skeleton_tracks[next_skeleton_track++]));
      continue;
    }
    JiggleTrack track = simulateMuscleJiggle(setup, muscles, skeleton, clip, baked->times, options.hits);
    const int joint = result.skinned_joint_of_muscle[setup.muscle];
    const MusclePart& part = muscles.parts[setup.muscle];
    for (size_t t = 0; t < baked->times.size(); ++t) {
      if (!baked->local.empty()) baked->local[t][joint] = track.local[t];
      const Eigen::Affine3d world = poses[t].world[parentOf(part, MuscleJointRole::kSkinned)] * track.local[t].matrix();
      (*frames)[t][skeleton.size() + setup.muscle] = world * result.joints[joint].bind_world.inverse();
    }
    tracks.push_back(std::move(track));
  }
  return tracks;
}

// Per skinned mesh part (index into Character::meshes), its rounded weights with skeleton indices.
using Approximations = std::vector<std::pair<int, const InfluenceSet*>>;

// How far `approximations` move the skin from the parts' full-precision weights at every sampled frame
// of every clip, and where each clip's largest move is, from the pass's single-precision figures
// (screened[f][p], every clip's frames in order). Each clip's largest move is recomputed in double
// (skinningDeformationError()) on every frame whose screened figure could reach it, so the largest
// move, its vertex and its time are the double figures; the root mean squares are the pass's.
DeformationFigures deformationFigures(const Character& character, const BakeResult& result,
                                      const Approximations& approximations,
                                      const std::vector<std::vector<ScreenedError>>& screened,
                                      const std::vector<std::vector<SkinFrame>>& clip_frames, int threads) {
  // The (frame, part) pairs whose largest move could be their clip's.
  std::vector<std::pair<size_t, size_t>> exact;  // (frame, part), frames counted over every clip
  const size_t part_count = approximations.size();
  size_t first = 0;
  for (size_t c = 0; c < result.clips.size(); ++c) {
    const size_t frames = clip_frames[c].size();
    // The clip's largest screened move (over its frames, the largest of the parts'), and its frame's
    // largest bound: the clip's exact largest move is at least their difference.
    double largest = -1.0, largest_bound = 0.0;
    for (size_t t = 0; t < frames; ++t) {
      double frame_largest = 0.0, frame_bound = 0.0;
      for (size_t a = 0; a < part_count; ++a) {
        const ScreenedError& figure = screened[first + t][a];
        frame_largest = std::max(frame_largest, figure.error.max_displacement);
        frame_bound = std::max(frame_bound, figure.bound);
      }
      if (frame_largest > largest) {
        largest = frame_largest;
        largest_bound = frame_bound;
      }
    }
    // Only the parts whose own screened figure could reach it are recomputed: on Quaternius Cyberpunk
    // (10 parts) the others were most of this pass.
    for (size_t t = 0; t < frames; ++t) {
      for (size_t a = 0; a < part_count; ++a) {
        const ScreenedError& figure = screened[first + t][a];
        if (figure.error.max_displacement + figure.bound >= largest - largest_bound) exact.emplace_back(first + t, a);
      }
    }
    first += frames;
  }
  std::vector<size_t> clip_of_frame, frame_in_clip;
  for (size_t c = 0; c < clip_frames.size(); ++c) {
    for (size_t t = 0; t < clip_frames[c].size(); ++t) {
      clip_of_frame.push_back(c);
      frame_in_clip.push_back(t);
    }
  }
  std::vector<DeformationError> exact_figures(exact.size());
  parallelForEach(threads, exact.size(), [&](size_t i) {
    const auto [f, a] = exact[i];
    const MeshPart& mesh = character.meshes[approximations[a].first];
    exact_figures[i] = skinningDeformationError(mesh.positions, result.parts[a].full, *approximations[a].second,
                                                clip_frames[clip_of_frame[f]][frame_in_clip[f]]);
  });

  DeformationFigures errors;
  size_t next_exact = 0;
  first = 0;
  for (size_t c = 0; c < result.clips.size(); ++c) {
    DeformationError clip_error;
    ErrorPeak peak;
    for (size_t t = 0; t < clip_frames[c].size(); ++t) {
      for (size_t a = 0; a < part_count; ++a) {
        const bool measured = next_exact < exact.size() && exact[next_exact] == std::make_pair(first + t, a);
        const DeformationError& frame = measured ? exact_figures[next_exact++] : screened[first + t][a].error;
        if (frame.max_vertex >= 0 && frame.max_displacement > clip_error.max_displacement)
          peak = ErrorPeak{approximations[a].first, frame.max_vertex, result.clips[c].times[t]};
        clip_error = combineDeformationErrors(clip_error, frame);
      }
    }
    first += clip_frames[c].size();
    if (peak.vertex >= 0 && clip_error.max_displacement > errors.overall.max_displacement)
      errors.peak_clip = static_cast<int>(c);
    errors.overall = combineDeformationErrors(errors.overall, clip_error);
    errors.per_clip.push_back(clip_error);
    errors.peaks.push_back(peak);
  }
  return errors;
}

// The muscles' skin weights (bakeCharacter()'s first stage): full-precision weights with the muscles
// per skinned part, and which vertices of the parts share a place (for the rounding).
struct MuscleWeights {
  std::vector<MeasuredPart> measured;  // per skinned part: input and rig weights, full precision
  std::vector<int> muscle_joints;      // muscle m's skinned joint: skeleton joint (size + m)
  std::vector<int> weld_of_vertex, first_vertex;
};

// The rounded weights (bakeCharacter()'s rounding stage). Dequantized, skeleton indices: the weights an
// engine skins with (the milli ones, or with GltfWeights::kUnorm16 the fine ones) take the place of the
// full weights in the measured parts, which the volumes are measured with; the full weights move into
// the result.
struct RoundedWeights {
  Approximations milli, fine;
  std::vector<InfluenceSet> milli_beside;          // unorm16 only: the milli weights beside the fine
  std::vector<QuantizedInfluences> fine_local;     // unorm16 only: skin-local, for WEIGHTS_n
};

// Where each muscle takes weight, and from which joint: its carrier, chosen from those shares (into
// result->muscles). The weights do not depend on the response.
MuscleWeights weighMuscles(const Character& character, const MuscleSet& muscles, const BakeOptions& options, BakeResult* result);

// The response fit (into result->muscles and result->fit), over poses chosen from every clip's frames
// where they spread the drivers most.
void fitResponses(const Character& character, const BakeOptions& options, const std::vector<MeasuredPart>& measured,
                  BakeResult* result);

// The kept weights refitted to the full ones' motion (pipeline/influence_refit.h). A place that several
// parts' vertices share (a border between meshes) is fitted at its first vertex's position, so the same
// weights there stay the same and round alike (shareSeamRoundings()).
void refitAtPlaces(const Character& character, const std::vector<MeasuredPart>& measured, const MuscleWeights& weights,
                   const std::vector<SkinFrame>& frames, int threads, std::vector<InfluenceSet>* pruned) {
  const std::vector<std::pair<int, int>> first_at = firstVertexAtEachPlace(weights.weld_of_vertex, weights.first_vertex);
  for (size_t a = 0; a < measured.size(); ++a) {
    const size_t count = character.meshes[measured[a].mesh_part].positions.size();
    std::vector<Eigen::Vector3d> at(count);
    for (size_t v = 0; v < count; ++v) {
      const auto& [part, vertex] = first_at[static_cast<size_t>(weights.weld_of_vertex[static_cast<size_t>(weights.first_vertex[a]) + v])];
      at[v] = character.meshes[measured[static_cast<size_t>(part)].mesh_part].positions[static_cast<size_t>(vertex)];
    }
    refitKeptWeights(measured[a].rig, at, frames, &(*pruned)[a], threads);
  }
}

// Joints: bind and rest transforms of every muscle's base, tip, driver and skinned joint.
void bakeMuscleJoints(const Skeleton& skeleton, const runtime::MuscleRig<double>& rig, BakeResult* result);

// Clips: every baked joint's local TRS (only written as channels when the motion is sampled), every
// muscle's length ratio and jiggles (into result->clips), and the skin matrices of every sampled frame
// (returned, per clip: for the rounding of the weights and for the deformation error). The inverse
// bind matrices are formed once (the same products as skinMatrix() forms per frame).
std::vector<std::vector<SkinFrame>> sampleBakedClips(const Character& character, const runtime::MuscleRig<double>& rig,
                                                     const BakeOptions& options, BakeResult* result);

// Every part pruned, then rounded together against every frame (they share the moments of their
// joints' motion), into result->parts with skin-local indices (the file's joint list, then the
// muscles' skinned joints). `lap` gives the seconds since it was last called, for `timing`.
void roundWeights(const Character& character, const BakeOptions& options, const MuscleWeights& weights,
                  std::vector<std::vector<SkinFrame>>* clip_frames, std::vector<MeasuredPart>* measured,
                  const std::function<double()>& lap, BakeTimings* timing, RoundedWeights* rounded, BakeResult* result);

// One pass over every frame for the deformation error of the pruned, quantized weights against the
// full-precision ones and, measured with the weights written as an engine skins them, the volumes
// (result->quality, result->error, result->gltf_error).
void measureBakeFigures(const Character& character, const BakeOptions& options, double body_height,
                        const std::vector<MeasuredPart>& measured,
                        const RoundedWeights& rounded, const std::vector<std::vector<SkinFrame>>& clip_frames,
                        const std::function<double()>& lap, BakeTimings* timing, BakeResult* result);

// The written attributes and packed buffers last: built before the figures, they were 7 MB of the
// bake's peak at 100k vertices, which the figures' skinning batches set.
void packWeights(const BakeOptions& options, RoundedWeights* rounded, BakeResult* result);

}  // namespace

BakeResult bakeCharacter(const Character& character, const MuscleSet& muscles, const BakeOptions& options,
                         BakeTimings* timings) {
  BakeTimings ignored;
  BakeTimings& timing = timings ? *timings : ignored;
  auto stopwatch = std::chrono::steady_clock::now();
  auto lap = [&stopwatch]() {
    auto now = std::chrono::steady_clock::now();
    double seconds = std::chrono::duration<double>(now - stopwatch).count();
    stopwatch = now;
    return seconds;
  };
  const Skeleton& skeleton = character.skeleton;
  if (!isPackedInfluenceCount(options.influences))
    failOption("influences", "must be 4, 7 or 10 (got " + std::to_string(options.influences) + ")");
  if (options.fps < 0) failOption("fps", "must be positive, or 0 for the clips' own key times");
  // The same ranges the command line and the build manifest take: a library caller (app/, bench/) gets
  // the refusal they would, not a fit over no poses or a term that pulls the wrong way.
  if (options.fit.max_poses < 1 || options.fit.max_poses > 100000)
    failOption("fit_poses", "must be from 1 to 100000 (got " + std::to_string(options.fit.max_poses) + ")");
  if (!(options.fit.smoothness_weight >= 0.0 && options.fit.smoothness_weight <= 1e6))
    failOption("fit_smoothness", "must be from 0 to 1000000 per metre of a 1.8 m body");
  if (!(options.fit.roughness_cap == 0.0 || (options.fit.roughness_cap >= 1.0 && options.fit.roughness_cap <= 100.0)))
    failOption("fit_roughness_cap", "must be 0 (no cap) or from 1 to 100 times plain skinning's roughness rise");
  // The occupied fit's exposure is per vertex and fitted pose: at every frame it would not fit in memory.
  if (options.fit.every_frame_regions && options.fit.occupied_volume)
    failOption("fit_regions", "every-frame cannot be combined with the occupied-volume fit");
  for (const MusclePart& part : muscles.parts) {
    std::string problem = musclePartProblem(part, skeleton);
    if (!problem.empty()) fail(errc::MUSCLES_MISMATCH, muscles.character, part.fullName() + ": " + problem);
  }
  for (const JiggleSetup& setup : options.jiggles) {
    std::string problem = jiggleSetupProblem(setup, skeleton);
    if (setup.host == JiggleHost::kMuscle && (setup.muscle < 0 || setup.muscle >= static_cast<int>(muscles.parts.size())))
      problem = "names no muscle of this muscle set";
    if (!problem.empty()) fail(errc::JIGGLE_UNRESOLVED, setup.name, problem);
  }
  checkHits(options.hits, options.jiggles);
  BakeResult result;
  result.influences = options.influences;
  result.motion = options.motion;
  result.helper_joints = options.helper_joints;
  result.jiggles = options.jiggles;
  const double body_height = muscles.body_height;

  MuscleWeights weights = weighMuscles(character, muscles, options, &result);
  timing.weights += lap();
  result.gltf_weights = options.gltf_weights;
  RoundedWeights rounded;
  std::vector<std::vector<SkinFrame>> clip_frames;
  // Samples every clip with the muscles' response as it stands (their joints and the frames the
  // rounding and the figures read).
  auto sampleClips = [&]() {
    const runtime::MuscleRig<double> rig = buildMuscleRig(result.muscles, skeleton);
    reportProgress(options.progress, "sampling every clip");
    result.joints.clear();
    result.skinned_joint_of_muscle.clear();
    result.clips.clear();
    bakeMuscleJoints(skeleton, rig, &result);
    clip_frames = sampleBakedClips(character, rig, options, &result);
    timing.evaluate += lap();
  };
  if (options.fit.every_frame_regions) {
    // The weights are cut and rounded first, following the preset's response, and the fit keeps the
    // regions on them (docs/deformation-quality.md, "Every region at every frame"); then the clips are
    // sampled again with the fitted response.
    sampleClips();
    roundWeights(character, options, weights, &clip_frames, &weights.measured, lap, &timing, &rounded, &result);
    timing.weights += lap();
    fitResponses(character, options, weights.measured, &result);
    timing.fit = lap();
    sampleClips();
  } else {
    fitResponses(character, options, weights.measured, &result);
    timing.fit = lap();
    sampleClips();
    roundWeights(character, options, weights, &clip_frames, &weights.measured, lap, &timing, &rounded, &result);
    timing.weights += lap();
  }
  measureBakeFigures(character, options, body_height, weights.measured, rounded, clip_frames, lap, &timing, &result);
  reportProgress(options.progress, "packing the weights");
  packWeights(options, &rounded, &result);
  timing.pack += lap();
  return result;
}

namespace {

MuscleWeights weighMuscles(const Character& character, const MuscleSet& muscles, const BakeOptions& options, BakeResult* result) {
  const Skeleton& skeleton = character.skeleton;
  const int muscle_count = static_cast<int>(muscles.parts.size());
  const double body_height = muscles.body_height;
  reportProgress(options.progress, "weighting the muscles' skin");
  const std::vector<double> radii = muscleWeightRadii(character, muscles, body_height, options.threads);
  // One welded surface over every skinned part, so a border between meshes gets one muscle weight
  // (pipeline/body_surface.h).
  BodySurface body = buildBodySurface(character, bodyWeldTolerance(body_height));
  MuscleShares shares =
      muscleShares(skeleton, body.skin(character), body.graph, muscles, radii, options.weights, options.threads);
  result->rigid_piece_vertices = static_cast<int>(std::count_if(body.graph.weld_of_vertex.begin(), body.graph.weld_of_vertex.end(),
                                                                 [&](int w) { return shares.rigid[w] != 0; }));
  result->muscles = muscles;
  chooseCarrierJoints(character, body, shares, &result->muscles);
  const MuscleSet& rigged = result->muscles;
  MuscleWeights out;
  out.muscle_joints.resize(muscle_count);
  for (int m = 0; m < muscle_count; ++m) out.muscle_joints[m] = skeleton.size() + m;
  for (size_t s = 0; s < body.mesh_part.size(); ++s) {
    const MeshPart& mesh = character.meshes[body.mesh_part[s]];
    InfluenceSet base = influencesFromMesh(mesh);
    if (!checkInfluences(base, skeleton.size()).empty())
      fail(errc::GLTF_ACCESSOR_INVALID, character.source, "mesh '" + mesh.name + "' has invalid skin weights (negative, NaN or all zero)");
    MeasuredPart part;
    part.mesh_part = body.mesh_part[s];
    part.input = normalizedInfluences(base, options.threads);
    part.rig = normalizedInfluences(addMuscleInfluences(part.input, body.partWelds(s), shares, rigged, out.muscle_joints,
                                                        options.weights, options.threads),
                                    options.threads);
    out.measured.push_back(std::move(part));
  }
  // Which vertices of the parts share a place, for the rounding; the rest of the surface and the
  // weight shares are done with: freed before the fit and the figures, whose peak they would otherwise
  // add to (2.9 MB at 100k vertices).
  out.weld_of_vertex = std::move(body.graph.weld_of_vertex);
  out.first_vertex = std::move(body.first_vertex);
  return out;
}

void fitResponses(const Character& character, const BakeOptions& options, const std::vector<MeasuredPart>& measured,
                  BakeResult* result) {
  const Skeleton& skeleton = character.skeleton;
  const MuscleSet& rigged = result->muscles;
  const int muscle_count = static_cast<int>(rigged.parts.size());
  std::vector<char> fit_part(muscle_count, 0);
  for (int m = 0; m < muscle_count; ++m)
    fit_part[m] = options.response == ResponseMode::kFit ||
                  (options.response == ResponseMode::kAuto && hasPresetResponse(rigged.parts[m]));
  if (std::find(fit_part.begin(), fit_part.end(), 1) == fit_part.end() || character.clips.empty()) return;
  std::vector<std::pair<int, double>> samples;
  for (size_t c = 0; c < character.clips.size(); ++c)
    for (double time : sampleTimes(character.clips[c], options.fps)) samples.emplace_back(static_cast<int>(c), time);
  const size_t wanted = static_cast<size_t>(std::max(1, options.fit.max_poses));
  std::vector<std::vector<double>> features;
  if (samples.size() > wanted) {
    const runtime::MuscleRig<double> start = buildMuscleRig(rigged, skeleton);
    for (const auto& [clip, time] : samples)
      features.push_back(driverFeatures(start, rigged, fit_part, sampleClip(skeleton, character.clips[clip], time)));
  } else {
    features.resize(samples.size());
  }
  std::vector<char> fitted(samples.size(), 0);
  std::vector<Pose> poses, checked;
  for (size_t i : chooseFitPoses(features, wanted)) {
    fitted[i] = 1;
    poses.push_back(sampleClip(skeleton, character.clips[samples[i].first], samples[i].second));
  }
  // With every_frame_regions, each frame the fit does not take is checked after it; beyond
  // kMaxCheckedFrames frames, every k-th (farthest-point sampling over more would cost more than the fit).
  if (options.fit.every_frame_regions) {
    constexpr size_t kMaxCheckedFrames = 4096;
    const size_t stride = (samples.size() + kMaxCheckedFrames - 1) / kMaxCheckedFrames;
    for (size_t i = 0; i < samples.size(); i += stride)
      if (!fitted[i]) checked.push_back(sampleClip(skeleton, character.clips[samples[i].first], samples[i].second));
  }
  // The prior keeps the weight it has against every frame (up to prior_poses of them) when the fit
  // takes fewer.
  ResponseFitOptions fit_options = options.fit;
  if (!fit_options.progress) fit_options.progress = options.progress;
  fit_options.pose_weight =
      static_cast<double>(std::min(samples.size(), static_cast<size_t>(std::max(1, fit_options.prior_poses)))) / poses.size();
  result->fit = fitMuscleResponses(character, options.regions, measured, poses, checked, fit_part, &result->muscles, fit_options, options.threads);
}

void bakeMuscleJoints(const Skeleton& skeleton, const runtime::MuscleRig<double>& rig, BakeResult* result) {
  const MuscleSet& rigged = result->muscles;
  const Pose rest = restPose(skeleton);
  const RigEvaluation at_bind = evaluateRig(rig, bindPose(skeleton), true);
  const RigEvaluation at_rest = evaluateRig(rig, rest, true);
  for (int m = 0; m < static_cast<int>(rigged.parts.size()); ++m) {
    const MusclePart& part = rigged.parts[m];
    for (MuscleJointRole role : kRoles) {
      BakedJoint joint;
      joint.name = muscleJointName(part, role);
      joint.muscle = m;
      joint.role = role;
      joint.parent = parentOf(part, role);
      joint.bind_world = role == MuscleJointRole::kSkinned ? muscleBindTransform(part, skeleton) : roleWorld(at_bind, m, role);
      joint.rest_local = localTrs(roleWorld(at_rest, m, role), rest, joint.parent);
      if (role == MuscleJointRole::kSkinned) result->skinned_joint_of_muscle.push_back(static_cast<int>(result->joints.size()));
      result->joints.push_back(joint);
    }
  }
}

std::vector<std::vector<SkinFrame>> sampleBakedClips(const Character& character, const runtime::MuscleRig<double>& rig,
                                                     const BakeOptions& options, BakeResult* result) {
  const Skeleton& skeleton = character.skeleton;
  const MuscleSet& rigged = result->muscles;
  const int muscle_count = static_cast<int>(rigged.parts.size());
  const bool sampled = options.motion != MuscleMotion::kRuntime;
  std::vector<Eigen::Affine3d> inverse_bind(static_cast<size_t>(skeleton.size()));
  for (int j = 0; j < skeleton.size(); ++j) inverse_bind[j] = skeleton.bind_world[j].inverse();
  std::vector<Eigen::Affine3d> inverse_muscle_bind(static_cast<size_t>(muscle_count));
  for (int m = 0; m < muscle_count; ++m) inverse_muscle_bind[m] = result->joints[result->skinned_joint_of_muscle[m]].bind_world.inverse();
  std::vector<std::vector<SkinFrame>> clip_frames;
  for (const Clip& clip : character.clips) {
    BakedClip baked;
    baked.gltf_animation = clip.gltf_animation;
    baked.measure_only = clip.measure_only;
    baked.name = clip.name;
    baked.times = sampleTimes(clip, options.fps);
    std::vector<SkinFrame> frames;
    std::vector<Pose> poses;  // kept for the jiggles only
    for (double time : baked.times) {
      const Pose pose = sampleClip(skeleton, clip, time);
      if (!options.jiggles.empty()) poses.push_back(pose);
      const RigEvaluation evaluation = evaluateRig(rig, pose, true);
      std::vector<double> ratios;
      SkinFrame skin(skeleton.size() + muscle_count);
      for (int j = 0; j < skeleton.size(); ++j) skin[j] = pose.world[j] * inverse_bind[j];
      for (int m = 0; m < muscle_count; ++m) {
        ratios.push_back(evaluation.drivers[m].ratio);
        skin[skeleton.size() + m] = matrixAt(evaluation.skinned, m) * inverse_muscle_bind[m];
      }
      if (sampled) {
        std::vector<Trs> locals;
        locals.reserve(kRoles.size() * static_cast<size_t>(muscle_count));
        for (int m = 0; m < muscle_count; ++m) {
          const MusclePart& part = rigged.parts[m];
          for (MuscleJointRole role : kRoles) locals.push_back(localTrs(roleWorld(evaluation, m, role), pose, parentOf(part, role)));
        }
        baked.local.push_back(std::move(locals));
      }
      baked.ratio.push_back(std::move(ratios));
      frames.push_back(std::move(skin));
    }
    if (!options.jiggles.empty()) baked.jiggles = bakeJiggles(skeleton, rigged, clip, poses, options, *result, &baked, &frames);
    clip_frames.push_back(std::move(frames));
    result->clips.push_back(std::move(baked));
  }
  return clip_frames;
}

void roundWeights(const Character& character, const BakeOptions& options, const MuscleWeights& weights,
                  std::vector<std::vector<SkinFrame>>* clip_frames, std::vector<MeasuredPart>* measured,
                  const std::function<double()>& lap, BakeTimings* timing, RoundedWeights* rounded, BakeResult* result) {
  const Skeleton& skeleton = character.skeleton;
  const int muscle_count = static_cast<int>(weights.muscle_joints.size());
  const bool unorm16 = options.gltf_weights == GltfWeights::kUnorm16;
  rounded->milli_beside.resize(unorm16 ? measured->size() : 0);
  rounded->fine_local.resize(unorm16 ? measured->size() : 0);
  // The rounding reads every clip's frames as one list: moved there and back after it, not copied (a
  // copy was a quarter of the bake's peak memory on a character with 22 clips).
  std::vector<SkinFrame> all_frames;
  for (std::vector<SkinFrame>& frames : *clip_frames) {
    for (SkinFrame& frame : frames) all_frames.push_back(std::move(frame));
  }
  reportProgress(options.progress, "rounding the weights against every frame");
  std::vector<InfluenceSet> pruned_parts;
  std::vector<MotionPart> motion_parts;
  for (const MeasuredPart& part : *measured) pruned_parts.push_back(pruneInfluences(part.rig, options.influences, options.threads));
  refitAtPlaces(character, *measured, weights, all_frames, options.threads, &pruned_parts);
  for (size_t a = 0; a < measured->size(); ++a)
    motion_parts.push_back(MotionPart{&pruned_parts[a], &character.meshes[(*measured)[a].mesh_part].positions});
  std::vector<QuantizedInfluences> quantized_parts = quantizeForMotion(motion_parts, all_frames, options.threads);
  shareSeamRoundings(weights.weld_of_vertex, weights.first_vertex, pruned_parts, &quantized_parts);
  {
    size_t next = 0;
    for (std::vector<SkinFrame>& frames : *clip_frames) {
      for (SkinFrame& frame : frames) frame = std::move(all_frames[next++]);
    }
    std::vector<SkinFrame>().swap(all_frames);
  }
  for (size_t a = 0; a < measured->size(); ++a) {
    const size_t p = static_cast<size_t>((*measured)[a].mesh_part);
    // (The fit is done: `measured` now changes to what the volumes are measured with.)
    const MeshPart& mesh = character.meshes[p];
    BakedPart baked;
    baked.mesh_part = (*measured)[a].mesh_part;
    baked.full = std::move((*measured)[a].rig);
    QuantizedInfluences quantized = std::move(quantized_parts[a]);
    const QuantizedInfluences quantized_fine =
        unorm16 ? quantizeInfluences(pruned_parts[a], kUnsignedShortScale, options.threads) : QuantizedInfluences{};
    InfluenceSet().joints.swap(pruned_parts[a].joints);
    std::vector<double>().swap(pruned_parts[a].weights);
    timing->weights += lap();
    if (unorm16) {
      rounded->milli_beside[a] = dequantizeInfluences(quantized, options.threads);
      (*measured)[a].rig = dequantizeInfluences(quantized_fine, options.threads);
      rounded->milli.emplace_back(static_cast<int>(p), &rounded->milli_beside[a]);
      rounded->fine.emplace_back(static_cast<int>(p), &(*measured)[a].rig);
    } else {
      (*measured)[a].rig = dequantizeInfluences(quantized, options.threads);
      rounded->milli.emplace_back(static_cast<int>(p), &(*measured)[a].rig);
    }
    baked.skin_joints = mesh.skin_joints;
    baked.skin_joints.insert(baked.skin_joints.end(), weights.muscle_joints.begin(), weights.muscle_joints.end());
    std::vector<int> local_of(skeleton.size() + muscle_count, -1);
    for (size_t k = 0; k < baked.skin_joints.size(); ++k) {
      if (local_of[baked.skin_joints[k]] < 0) local_of[baked.skin_joints[k]] = static_cast<int>(k);
    }
    auto skinLocal = [&](QuantizedInfluences influences) {
      for (size_t k = 0; k < influences.joints.size(); ++k) {
        if (influences.weights[k] == 0) {
          influences.joints[k] = 0;
          continue;
        }
        const int local = local_of[influences.joints[k]];
        if (local < 0)
          fail(errc::GLTF_SKIN_INVALID, character.source, "mesh '" + mesh.name + "' is weighted to a joint outside its skin");
        influences.joints[k] = local;
      }
      return influences;
    };
    baked.quantized = skinLocal(std::move(quantized));
    if (unorm16) rounded->fine_local[a] = skinLocal(quantized_fine);
    timing->pack += lap();
    result->vertex_count += baked.quantized.vertexCount();
    result->parts.push_back(std::move(baked));
  }
}

void measureBakeFigures(const Character& character, const BakeOptions& options, double body_height,
                        const std::vector<MeasuredPart>& measured,
                        const RoundedWeights& rounded, const std::vector<std::vector<SkinFrame>>& clip_frames,
                        const std::function<double()>& lap, BakeTimings* timing, BakeResult* result) {
  const MuscleSet& rigged = result->muscles;
  const bool unorm16 = options.gltf_weights == GltfWeights::kUnorm16;
  std::vector<std::vector<ErrorWeights>> error_weights(unorm16 ? 2 : 1);
  for (size_t a = 0; a < measured.size(); ++a) {
    error_weights[0].push_back(ErrorWeights{&result->parts[a].full, rounded.milli[a].second});
    if (unorm16) error_weights[1].push_back(ErrorWeights{&result->parts[a].full, rounded.fine[a].second});
  }
  std::vector<MeasuredClip> clips;
  for (size_t c = 0; c < result->clips.size(); ++c) {
    MeasuredClip clip;
    clip.name = result->clips[c].name;
    clip.times = result->clips[c].times;
    clip.frames = &clip_frames[c];
    if (options.measure_quality) {
      for (const std::vector<double>& ratios : result->clips[c].ratio) {
        std::vector<double> clamped(ratios.size());
        for (size_t m = 0; m < ratios.size(); ++m)
          clamped[m] = std::clamp(ratios[m], rigged.parts[m].compression, rigged.parts[m].stretch);
        clip.ratio.push_back(std::move(clamped));
      }
    }
    clips.push_back(std::move(clip));
  }
  reportProgress(options.progress, "measuring every frame");
  DeformationMeasures measures = measureDeformation(character, options.regions, measured, rigged, clips,
                                                    options.measure_quality, error_weights, options.threads);
  if (options.measure_quality) result->quality = std::move(measures.quality);
  if (options.measure_quality && options.measure_skin) {
    measureSeams(character, measured, clips, bodyWeldTolerance(body_height), options.threads, &result->quality);
    measureJointRegions(character, measured, clips, options.threads, &result->quality);
    measureSurfaceFigures(character, measured, clips, character.skeleton.size(), body_height, options.threads,
                          &result->quality, options.creases);
  }
  timing->quality = lap();
  result->error = deformationFigures(character, *result, rounded.milli, measures.screened[0], clip_frames, options.threads);
  if (unorm16)
    result->gltf_error = deformationFigures(character, *result, rounded.fine, measures.screened[1], clip_frames, options.threads);
  timing->error = lap();
}

void packWeights(const BakeOptions& options, RoundedWeights* rounded, BakeResult* result) {
  const bool unorm16 = options.gltf_weights == GltfWeights::kUnorm16;
  for (size_t a = 0; a < result->parts.size(); ++a) {
    BakedPart& baked = result->parts[a];
    const int skin_size = static_cast<int>(baked.skin_joints.size());
    baked.standard = standardSkinAttributes(unorm16 ? rounded->fine_local[a] : baked.quantized, skin_size, WeightStorage::kUnsignedShort,
                                            options.threads);
    if (unorm16) rounded->fine_local[a] = QuantizedInfluences{};
    baked.packed = packInfluences(baked.quantized, skin_size, packedIndexBytesFor(skin_size));
    baked.packed_attributes = packedGltfAttributes(baked.packed);
  }
}

}  // namespace
}  // namespace rigbake
