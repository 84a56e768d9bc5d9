// Deformation quality: volumes of skinned surfaces (pipeline/skin_volume.h) under linear blend and
// dual-quaternion skinning (pipeline/skinning.h) and the baked rig, and the muscles' skin displacement
// along the normal. docs/deformation-quality.md.
#include "pipeline/deformation_quality.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>

#include "pipeline/parallel.h"
#include "pipeline/skinning.h"

namespace rigbake {
namespace {

struct PreparedPart {
  const MeshPart* mesh = nullptr;
  const MeasuredPart* weights = nullptr;
  VolumeSurface surface;
  std::vector<ClosedPatch> regions;  // one per DeformationQuality::regions entry (possibly empty)
};

void keepExtreme(double change, double time, VolumeExtreme* extreme) {
  if (std::abs(change) > std::abs(extreme->change)) *extreme = {change, time};
}

struct FrameVolumes {
  double body[3] = {0, 0, 0};  // input, dual quaternion, rig
  std::vector<std::array<double, 3>> regions;
};

}  // namespace

DeformationQuality measureDeformationQuality(const Character& character, const std::vector<BodyRegion>& regions,
                                             const std::vector<MeasuredPart>& parts, const MuscleSet& muscles,
                                             const std::vector<MeasuredClip>& clips, int threads) {
  const Skeleton& skeleton = character.skeleton;
  const int joint_count = skeleton.size();
  DeformationQuality quality;

  // Weld each part once; cut each region out of it and close it. Regions too flat to enclose a
  // meaningful volume are left out of the figures (and listed).
  std::vector<int> mesh_parts;
  for (const MeasuredPart& part : parts) mesh_parts.push_back(part.mesh_part);
  std::vector<std::vector<std::vector<int>>> region_triangles;
  for (const BodyRegion& region : regions) region_triangles.push_back(region.triangles);
  MeasuredSurfaces measured = measuredSurfaces(character, mesh_parts, region_triangles, 1e-6 * std::max(muscles.body_height, 1e-3));
  std::vector<size_t> kept;
  quality.regions.clear();
  for (size_t r = 0; r < regions.size(); ++r) {
    if (measured.region_measured[r]) {
      kept.push_back(r);
      quality.regions.push_back(regions[r].name);
    } else {
      quality.unmeasured_regions.push_back(regions[r].name);
    }
  }
  std::vector<PreparedPart> prepared;
  for (size_t p = 0; p < parts.size(); ++p) {
    PreparedPart part;
    part.mesh = &character.meshes[parts[p].mesh_part];
    part.weights = &parts[p];
    part.surface = std::move(measured.surfaces[p]);
    for (size_t r : kept) part.regions.push_back(std::move(measured.regions[p][r]));
    prepared.push_back(std::move(part));
  }
  const size_t region_count = kept.size();

  // The posed vertices of the three skinnings, kept from frame to frame by each chunk of frames.
  struct Scratch {
    std::vector<Eigen::Vector3d> posed[3];
  };
  auto volumesOf = [&](const std::vector<Eigen::Affine3d>* frame, Scratch* scratch) {
    FrameVolumes out;
    out.regions.assign(region_count, {0, 0, 0});
    DualQuaternionFrame dual_quaternions;  // of the skeleton's joints, split once per frame
    if (frame != nullptr && !prepared.empty()) {
      const std::vector<Eigen::Affine3d> skeleton_frame(frame->begin(), frame->begin() + joint_count);
      dual_quaternions = dualQuaternionFrame(skeleton_frame);
    }
    std::vector<Eigen::Vector3d>* posed = scratch->posed;
    const std::array<const std::vector<Eigen::Vector3d>*, 3> skinnings = {&posed[0], &posed[1], &posed[2]};
    for (const PreparedPart& part : prepared) {
      if (frame == nullptr) {
        posed[0] = weldedPositions(part.surface, part.mesh->positions);
        posed[1] = posed[2] = posed[0];
      } else {
        skinInputAndRig(part.mesh->positions, part.weights->input, part.weights->rig, *frame, dual_quaternions,
                        part.surface.vertex_of_weld, &posed[0], &posed[1], &posed[2]);
      }
      const std::array<double, 3> body = enclosedVolumes(part.surface.whole, skinnings);
      for (int k = 0; k < 3; ++k) out.body[k] += body[k];
      for (size_t r = 0; r < region_count; ++r) {
        const std::array<double, 3> region = enclosedVolumes(part.regions[r], skinnings);
        for (int k = 0; k < 3; ++k) out.regions[r][k] += region[k];
      }
    }
    return out;
  };

  Scratch bind_scratch;
  const FrameVolumes bind = volumesOf(nullptr, &bind_scratch);
  quality.body_volume = bind.body[0];
  for (size_t r = 0; r < region_count; ++r) quality.region_volumes.push_back(bind.regions[r][0]);
  auto change = [](double volume, double reference) { return reference != 0.0 ? volume / reference - 1.0 : 0.0; };

  // Each muscle's most compressed and most stretched sample over every clip.
  const int muscle_count = static_cast<int>(muscles.parts.size());
  struct Sample {
    int clip = -1, frame = -1;
    double ratio = 1.0;
  };
  std::vector<Sample> most_compressed(muscle_count), most_stretched(muscle_count);

  // Every frame's volumes at once, all clips' frames in one loop (chunks of a few frames reuse their
  // posed vertices), then each clip's extremes in frame order, as one thread would find them.
  std::vector<std::pair<size_t, size_t>> clip_frame;  // (clip, frame) in clip order
  std::vector<size_t> first_frame;
  for (size_t c = 0; c < clips.size(); ++c) {
    first_frame.push_back(clip_frame.size());
    for (size_t t = 0; t < clips[c].times.size(); ++t) clip_frame.emplace_back(c, t);
  }
  std::vector<FrameVolumes> all_volumes(clip_frame.size());
  constexpr size_t kFramesPerChunk = 4;
  parallelFor(threads, clip_frame.size(), kFramesPerChunk, [&](size_t, size_t begin, size_t end) {
    Scratch scratch;
    for (size_t i = begin; i < end; ++i)
      all_volumes[i] = volumesOf(&(*clips[clip_frame[i].first].frames)[clip_frame[i].second], &scratch);
  });

  for (size_t c = 0; c < clips.size(); ++c) {
    const MeasuredClip& clip = clips[c];
    ClipQuality figures;
    figures.clip = clip.name;
    figures.regions.resize(region_count);
    double worst = -1.0;
    const FrameVolumes* clip_volumes = all_volumes.data() + first_frame[c];
    for (size_t t = 0; t < clip.times.size(); ++t) {
      const FrameVolumes& volumes = clip_volumes[t];
      const double time = clip.times[t];
      keepExtreme(change(volumes.body[0], bind.body[0]), time, &figures.body.input);
      keepExtreme(change(volumes.body[1], bind.body[1]), time, &figures.body.dual_quaternion);
      const double rig_change = change(volumes.body[2], bind.body[2]);
      keepExtreme(rig_change, time, &figures.body.rig);
      if (std::abs(rig_change) > worst) {
        worst = std::abs(rig_change);
        figures.worst_frame = static_cast<int>(t);
      }
      for (size_t r = 0; r < region_count; ++r) {
        keepExtreme(change(volumes.regions[r][0], bind.regions[r][0]), time, &figures.regions[r].input);
        keepExtreme(change(volumes.regions[r][1], bind.regions[r][1]), time, &figures.regions[r].dual_quaternion);
        keepExtreme(change(volumes.regions[r][2], bind.regions[r][2]), time, &figures.regions[r].rig);
      }
      for (int m = 0; m < muscle_count; ++m) {
        const double ratio = clip.ratio[t][m];
        if (ratio < most_compressed[m].ratio) most_compressed[m] = {static_cast<int>(c), static_cast<int>(t), ratio};
        if (ratio > most_stretched[m].ratio) most_stretched[m] = {static_cast<int>(c), static_cast<int>(t), ratio};
      }
    }
    quality.clips.push_back(std::move(figures));
  }

  // The skin's move along the input skinning's normal at those samples; posed surfaces are cached by
  // sample, as several muscles peak together.
  struct PosedSample {
    std::vector<std::vector<Eigen::Vector3d>> input, rig, normals;  // per part, welded
  };
  std::map<std::pair<int, int>, PosedSample> cache;
  auto posedAt = [&](const Sample& sample) -> const PosedSample& {
    auto it = cache.find({sample.clip, sample.frame});
    if (it != cache.end()) return it->second;
    const std::vector<Eigen::Affine3d>& frame = (*clips[sample.clip].frames)[sample.frame];
    PosedSample posed;
    for (const PreparedPart& part : prepared) {
      posed.input.emplace_back();
      posed.rig.emplace_back();
      skinLinearBlend(part.mesh->positions, part.weights->input, frame, part.surface.vertex_of_weld, &posed.input.back());
      skinLinearBlend(part.mesh->positions, part.weights->rig, frame, part.surface.vertex_of_weld, &posed.rig.back());
      posed.normals.push_back(vertexNormals(part.surface.whole, posed.input.back()));
    }
    return cache.emplace(std::make_pair(sample.clip, sample.frame), std::move(posed)).first->second;
  };
  auto skinMove = [&](int m, const Sample& sample, bool wanted) {
    MuscleSkinMove move;
    if (!wanted || sample.clip < 0) return move;
    const PosedSample& posed = posedAt(sample);
    double weighted = 0.0, total = 0.0;
    for (size_t p = 0; p < prepared.size(); ++p) {
      const PreparedPart& part = prepared[p];
      const InfluenceSet& rig = part.weights->rig;
      const int slots = rig.slots_per_vertex;
      for (int w = 0; w < part.surface.weldedCount(); ++w) {
        const int v = part.surface.vertex_of_weld[w];
        double weight = 0.0;
        for (int k = 0; k < slots; ++k) {
          if (rig.joints[v * slots + k] == joint_count + m) weight += rig.weights[v * slots + k];
        }
        if (weight < kMuscleSkinWeight) continue;
        const double along = (posed.rig[p][w] - posed.input[p][w]).dot(posed.normals[p][w]);
        weighted += weight * along;
        total += weight;
        move.max_out = std::max(move.max_out, along);
        move.max_in = std::max(move.max_in, -along);
        ++move.vertices;
      }
    }
    if (move.vertices == 0) return MuscleSkinMove{};
    move.measured = true;
    move.clip = clips[sample.clip].name;
    move.time = clips[sample.clip].times[sample.frame];
    move.ratio = sample.ratio;
    move.mean = weighted / total;
    return move;
  };
  for (int m = 0; m < muscle_count; ++m) {
    MuscleQuality figures;
    figures.muscle = muscles.parts[m].fullName();
    figures.kind = muscles.parts[m].kind;
    figures.compressed = skinMove(m, most_compressed[m], most_compressed[m].ratio < 1.0);
    figures.stretched = skinMove(m, most_stretched[m], most_stretched[m].ratio > 1.0);
    quality.muscles.push_back(std::move(figures));
  }
  return quality;
}

}  // namespace rigbake
