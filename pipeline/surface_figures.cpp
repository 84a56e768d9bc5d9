#include "pipeline/surface_figures.h"

#include <algorithm>
#include <array>
#include <cassert>

#include "pipeline/centre_of_rotation.h"
#include "pipeline/parallel.h"
#include "pipeline/skin_volume.h"
#include "pipeline/skinning.h"

namespace rigbake {
namespace {

constexpr double kMovingWeight = 0.05;

// One part as the figures need it: its welded surface, one-rings, rotation centres, which welded
// vertices move, and their bind roughness.
struct SurfacePart {
  VolumeSurface surface;
  std::vector<std::vector<int>> ring;  // welded one-rings
  RotationCentres centres;
  std::vector<int> moving;             // welded vertices
  std::vector<double> bind_roughness;  // per welded vertex
};

std::vector<double> roughness(const SurfacePart& part, const std::vector<Eigen::Vector3d>& welded) {
  const std::vector<Eigen::Vector3d> normals = vertexNormals(part.surface.whole, welded);
  std::vector<double> out(welded.size(), 0.0);
  for (size_t w = 0; w < welded.size(); ++w) {
    if (part.ring[w].empty()) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int n : part.ring[w]) mean += welded[static_cast<size_t>(n)];
    mean /= static_cast<double>(part.ring[w].size());
    out[w] = std::abs((mean - welded[w]).dot(normals[w]));
  }
  return out;
}

SurfacePart surfacePart(const MeshPart& mesh, const MeasuredPart& weights, int skeleton_joints, double weld_tolerance, int threads) {
  SurfacePart part;
  part.surface = buildVolumeSurface(mesh, weld_tolerance);
  const size_t welded_count = static_cast<size_t>(part.surface.weldedCount());
  part.ring.resize(welded_count);
  for (const auto& triangle : part.surface.whole.triangles) {
    for (int k = 0; k < 3; ++k) {
      part.ring[static_cast<size_t>(triangle[k])].push_back(triangle[(k + 1) % 3]);
      part.ring[static_cast<size_t>(triangle[k])].push_back(triangle[(k + 2) % 3]);
    }
  }
  for (std::vector<int>& ring : part.ring) {
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  }
  part.centres = optimizedRotationCentres(mesh, weights.input, threads);
  const int in_slots = weights.input.slots_per_vertex, rig_slots = weights.rig.slots_per_vertex;
  for (size_t w = 0; w < welded_count; ++w) {
    const size_t v = static_cast<size_t>(part.surface.vertex_of_weld[w]);
    int blended = 0;
    for (int k = 0; k < in_slots; ++k) blended += weights.input.weights[v * in_slots + k] >= kMovingWeight;
    double muscle = 0.0;
    for (int k = 0; k < rig_slots; ++k)
      if (weights.rig.joints[v * rig_slots + k] >= skeleton_joints) muscle += weights.rig.weights[v * rig_slots + k];
    if (blended >= 2 || muscle >= kMovingWeight) part.moving.push_back(static_cast<int>(w));
  }
  part.bind_roughness = roughness(part, weldedPositions(part.surface, mesh.positions));
  return part;
}

double percentile95(std::vector<double>* values) {
  if (values->empty()) return 0.0;
  const size_t at = static_cast<size_t>(0.95 * static_cast<double>(values->size() - 1));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(at), values->end());
  return (*values)[at];
}

// One sample: each skinning's roughness rise percentile and the centres of rotation's body volume.
struct SampleFigures {
  std::array<double, kSurfaceSkinnings> rise{};
  double volume = 0.0;
};

SampleFigures measureSample(const Character& character, const std::vector<MeasuredPart>& parts,
                            const std::vector<SurfacePart>& surfaces, const SkinFrame& frame) {
  const DualQuaternionFrame rotations = dualQuaternionFrame(frame);
  std::array<std::vector<double>, kSurfaceSkinnings> rises;
  SampleFigures figures;
  for (size_t p = 0; p < parts.size(); ++p) {
    const std::vector<Eigen::Vector3d>& bind = character.meshes[parts[p].mesh_part].positions;
    const SurfacePart& part = surfaces[p];
    const std::array<std::vector<Eigen::Vector3d>, kSurfaceSkinnings> posed = {
        skinLinearBlend(bind, parts[p].input, frame), skinDualQuaternion(bind, parts[p].input, rotations),
        skinCentreOfRotation(bind, parts[p].input, part.centres, frame, rotations), skinLinearBlend(bind, parts[p].rig, frame)};
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      const std::vector<Eigen::Vector3d> welded = weldedPositions(part.surface, posed[s]);
      const std::vector<double> r = roughness(part, welded);
      for (int w : part.moving) rises[s].push_back(r[w] - part.bind_roughness[w]);
      if (s == 2) figures.volume += enclosedVolume(part.surface.whole, welded);
    }
  }
  for (int s = 0; s < kSurfaceSkinnings; ++s) figures.rise[s] = percentile95(&rises[s]);
  return figures;
}

}  // namespace

void measureSurfaceFigures(const Character& character, const std::vector<MeasuredPart>& parts,
                           const std::vector<MeasuredClip>& clips, int skeleton_joints, double weld_tolerance, int threads,
                           DeformationQuality* quality) {
  assert(quality->clips.size() == clips.size());
  if (parts.empty()) return;
  std::vector<SurfacePart> surfaces;
  double bind_volume = 0.0;
  for (const MeasuredPart& part : parts) {
    surfaces.push_back(surfacePart(character.meshes[part.mesh_part], part, skeleton_joints, weld_tolerance, threads));
    bind_volume += enclosedVolume(surfaces.back().surface.whole,
                                  weldedPositions(surfaces.back().surface, character.meshes[part.mesh_part].positions));
  }
  // Every clip's samples in one list, measured on the threads, then read back in order.
  std::vector<std::pair<size_t, size_t>> samples;  // (clip, frame)
  for (size_t c = 0; c < clips.size(); ++c) {
    const size_t frames = clips[c].frames->size();
    const size_t taken = std::min<size_t>(frames, kSurfaceSamples);
    for (size_t i = 0; i < taken; ++i) samples.emplace_back(c, taken == 1 ? frames - 1 : i * (frames - 1) / (taken - 1));
  }
  std::vector<SampleFigures> figures(samples.size());
  parallelForEach(threads, samples.size(), [&](size_t i) {
    figures[i] = measureSample(character, parts, surfaces, (*clips[samples[i].first].frames)[samples[i].second]);
  });
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto [c, t] = samples[i];
    SurfaceFigures& surface = quality->clips[c].surface;
    surface.measured = true;
    for (int s = 0; s < kSurfaceSkinnings; ++s) surface.roughness_rise[s] = std::max(surface.roughness_rise[s], figures[i].rise[s]);
    const double change = bind_volume != 0.0 ? figures[i].volume / bind_volume - 1.0 : 0.0;
    if (std::abs(change) > std::abs(surface.centre_of_rotation.change)) surface.centre_of_rotation = {change, clips[c].times[t]};
  }
}

}  // namespace rigbake
