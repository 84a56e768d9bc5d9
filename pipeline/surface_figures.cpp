#include "pipeline/surface_figures.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <limits>

#include "pipeline/centre_of_rotation.h"
#include "pipeline/crease_contact.h"
#include "pipeline/occupied_volume.h"
#include "pipeline/parallel.h"
#include "pipeline/skin_volume.h"
#include "pipeline/skinning.h"
#include "pipeline/surface_graph.h"

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
  // Per moving vertex, the triangles around it (indices into surface.whole.triangles): its normal.
  std::vector<std::vector<int>> around;
  std::vector<double> bind_roughness;  // per moving vertex
  // The strain figures' pieces: every triangle of the welded surface with a moving corner and its three
  // edges, with their bind areas and lengths (triangles of zero area are left out: no ratio).
  std::vector<std::array<int, 2>> strain_edges;
  std::vector<double> bind_edge_length;
  std::vector<int> strain_triangles;   // indices into surface.whole.triangles
  std::vector<double> bind_area;
};

// Per moving vertex, |L . n|: L the umbrella Laplacian, n the area-weighted normal of the triangles
// around it (as vertexNormals() weights them, for these vertices only).
std::vector<double> roughness(const SurfacePart& part, const std::vector<Eigen::Vector3d>& welded) {
  std::vector<double> out(part.moving.size(), 0.0);
  const auto& triangles = part.surface.whole.triangles;
  for (size_t i = 0; i < part.moving.size(); ++i) {
    const size_t w = static_cast<size_t>(part.moving[i]);
    if (part.ring[w].empty()) continue;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (int t : part.around[i]) {
      const auto& tri = triangles[static_cast<size_t>(t)];
      normal += (welded[tri[1]] - welded[tri[0]]).cross(welded[tri[2]] - welded[tri[0]]);
    }
    const double length = normal.norm();
    if (!(length > 0.0)) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int n : part.ring[w]) mean += welded[static_cast<size_t>(n)];
    mean /= static_cast<double>(part.ring[w].size());
    out[i] = std::abs((mean - welded[w]).dot(normal / length));
  }
  return out;
}

double triangleArea(const std::vector<Eigen::Vector3d>& welded, const std::array<int, 3>& tri) {
  const Eigen::Vector3d& a = welded[static_cast<size_t>(tri[0])];
  return 0.5 * (welded[static_cast<size_t>(tri[1])] - a).cross(welded[static_cast<size_t>(tri[2])] - a).norm();
}

// |posed / bind - 1| of every strain edge's length and every strain triangle's area, appended.
void appendStrains(const SurfacePart& part, const std::vector<Eigen::Vector3d>& welded, std::vector<double>* edges,
                   std::vector<double>* areas) {
  for (size_t e = 0; e < part.strain_edges.size(); ++e) {
    const auto& edge = part.strain_edges[e];
    const double length = (welded[static_cast<size_t>(edge[0])] - welded[static_cast<size_t>(edge[1])]).norm();
    edges->push_back(std::abs(length / part.bind_edge_length[e] - 1.0));
  }
  const auto& triangles = part.surface.whole.triangles;
  for (size_t t = 0; t < part.strain_triangles.size(); ++t) {
    const double area = triangleArea(welded, triangles[static_cast<size_t>(part.strain_triangles[t])]);
    areas->push_back(std::abs(area / part.bind_area[t] - 1.0));
  }
}

// `with_centres`: the rotation centres, which only the centre-of-rotation skinning needs (the mannequin's
// take 0.6 s: three times what the response fit's roughness cap costs without them).
SurfacePart surfacePart(const MeshPart& mesh, const MeasuredPart& weights, int skeleton_joints, double weld_tolerance, int threads,
                        bool with_centres) {
  SurfacePart part;
  part.surface = buildVolumeSurface(mesh, weld_tolerance);
  const size_t welded_count = static_cast<size_t>(part.surface.weldedCount());
  part.ring = oneRings(part.surface.whole.triangles, welded_count);
  if (with_centres) part.centres = optimizedRotationCentres(mesh, weights.input, threads);
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
  std::vector<int> moving_index(welded_count, -1);
  for (size_t i = 0; i < part.moving.size(); ++i) moving_index[static_cast<size_t>(part.moving[i])] = static_cast<int>(i);
  part.around.resize(part.moving.size());
  const auto& triangles = part.surface.whole.triangles;
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int corner : triangles[t])
      if (moving_index[static_cast<size_t>(corner)] >= 0) part.around[static_cast<size_t>(moving_index[static_cast<size_t>(corner)])].push_back(static_cast<int>(t));
  const std::vector<Eigen::Vector3d>& bind = part.surface.bind;
  part.bind_roughness = roughness(part, bind);
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    if (moving_index[static_cast<size_t>(tri[0])] < 0 && moving_index[static_cast<size_t>(tri[1])] < 0 &&
        moving_index[static_cast<size_t>(tri[2])] < 0)
      continue;
    const double area = triangleArea(bind, tri);
    if (!(area > 0.0)) continue;
    part.strain_triangles.push_back(static_cast<int>(t));
    part.bind_area.push_back(area);
    // Each triangle's three edges: an edge inside the surface counts once per side, so a body split
    // into meshes (where each piece has the border edge once) gives the whole's figure.
    for (int k = 0; k < 3; ++k) {
      const int a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      part.strain_edges.push_back({a, b});
      part.bind_edge_length.push_back((bind[static_cast<size_t>(a)] - bind[static_cast<size_t>(b)]).norm());
    }
  }
  return part;
}

double percentile95(std::vector<double>* values) {
  if (values->empty()) return 0.0;
  const size_t at = static_cast<size_t>(0.95 * static_cast<double>(values->size() - 1));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(at), values->end());
  return (*values)[at];
}

// Every vertex of one part posed by the four skinnings the figures compare, in kSurfaceSkinnings order:
// plain and dual quaternions of the input's weights, centres of rotation, plain of the rig's.
std::array<std::vector<Eigen::Vector3d>, kSurfaceSkinnings> poseSkinnings(const std::vector<Eigen::Vector3d>& bind,
                                                                          const MeasuredPart& weights, const SurfacePart& part,
                                                                          const SkinFrame& frame,
                                                                          const DualQuaternionFrame& rotations) {
  return {skinLinearBlend(bind, weights.input, frame), skinDualQuaternion(bind, weights.input, rotations),
          skinCentreOfRotation(bind, weights.input, part.centres, frame, rotations), skinLinearBlend(bind, weights.rig, frame)};
}

// One sample: each skinning's roughness rise percentile and occupied volume, and the centres of
// rotation's body volume.
struct SampleFigures {
  std::array<double, kSurfaceSkinnings> rise{};
  // The moving vertex whose rise under the rig exceeds plain skinning's most (part, its vertex), and
  // both rises there.
  int lump_part = -1, lump_vertex = -1;
  double lump_rig = 0.0, lump_input = 0.0;
  std::array<double, kSurfaceSkinnings> edge_strain{}, area_strain{};
  std::array<double, kSurfaceSkinnings> occupied{};
  double volume = 0.0;
};

// The grid the occupied volume is sampled on: a 256th of the bind body's largest extent (7 mm on a
// 1.8 m body): finer grids cost a bake's figures twice the time per halving and move a change by under
// 0.35 points, and the rig's difference from plain skinning by under 0.03 (docs/deformation-quality.md).
OccupancyGrid bindOccupancyGrid(const Character& character, const std::vector<MeasuredPart>& parts) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (const MeasuredPart& part : parts) {
    for (const Eigen::Vector3d& p : character.meshes[part.mesh_part].positions) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
  }
  return occupancyGrid(low, high, 256.0);
}

// The occupied volume of every part posed by one skinning.
double occupiedVolumeOf(const std::vector<SurfacePart>& surfaces, const std::vector<std::vector<Eigen::Vector3d>>& welded,
                        const OccupancyGrid& grid) {
  std::vector<PosedPatch> posed;
  for (size_t p = 0; p < surfaces.size(); ++p) posed.push_back({&surfaces[p].surface.whole, &welded[p]});
  return grid.step > 0.0 ? occupiedVolume(posed, grid.axis, grid.step) : 0.0;
}

SampleFigures measureSample(const Character& character, const std::vector<MeasuredPart>& parts,
                            const std::vector<SurfacePart>& surfaces, const OccupancyGrid& grid, const SkinFrame& frame) {
  const DualQuaternionFrame rotations = dualQuaternionFrame(frame);
  std::array<std::vector<double>, kSurfaceSkinnings> rises, edge_strains, area_strains;
  std::array<std::vector<std::vector<Eigen::Vector3d>>, kSurfaceSkinnings> whole;  // per skinning, per part
  SampleFigures figures;
  for (size_t p = 0; p < parts.size(); ++p) {
    const std::vector<Eigen::Vector3d>& bind = character.meshes[parts[p].mesh_part].positions;
    const SurfacePart& part = surfaces[p];
    // Every vertex posed by each skinning: the occupied volume takes them all.
    const std::array<std::vector<Eigen::Vector3d>, kSurfaceSkinnings> posed = poseSkinnings(bind, parts[p], part, frame, rotations);
    std::vector<double> plain;  // the input skinning's roughness per moving vertex
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      whole[s].push_back(weldedPositions(part.surface, posed[s]));
      const std::vector<double> r = roughness(part, whole[s].back());
      for (size_t i = 0; i < r.size(); ++i) rises[s].push_back(r[i] - part.bind_roughness[i]);
      if (s == 0) plain = r;
      for (size_t i = 0; s == kSurfaceSkinnings - 1 && i < r.size(); ++i) {
        if (!(r[i] - plain[i] > figures.lump_rig - figures.lump_input)) continue;
        figures.lump_part = static_cast<int>(p);
        figures.lump_vertex = part.surface.vertex_of_weld[static_cast<size_t>(part.moving[i])];
        figures.lump_rig = r[i] - part.bind_roughness[i];
        figures.lump_input = plain[i] - part.bind_roughness[i];
      }
      appendStrains(part, whole[s].back(), &edge_strains[s], &area_strains[s]);
      if (s == 2) figures.volume += enclosedVolume(part.surface.whole, whole[s].back());
    }
  }
  for (int s = 0; s < kSurfaceSkinnings; ++s) {
    figures.rise[s] = percentile95(&rises[s]);
    figures.edge_strain[s] = percentile95(&edge_strains[s]);
    figures.area_strain[s] = percentile95(&area_strains[s]);
    figures.occupied[s] = occupiedVolumeOf(surfaces, whole[s], grid);
  }
  return figures;
}


// The creases that peak at one sample (`creases`), measured on one skinning of the parts they touch: each
// part is posed by each skinning once, with its normals, and every crease's two sides read from that.
std::vector<CreaseContact> measureCreases(const Character& character, const std::vector<MeasuredPart>& parts,
                                          const std::vector<SurfacePart>& surfaces, const std::vector<const Crease*>& creases,
                                          const SkinFrame& frame) {
  const DualQuaternionFrame rotations = dualQuaternionFrame(frame);
  std::vector<std::array<CreaseSide, kSurfaceSkinnings>> proximal(creases.size()), distal(creases.size());
  for (size_t p = 0; p < parts.size(); ++p) {
    const size_t mesh = static_cast<size_t>(parts[p].mesh_part);
    bool touched = false;
    for (const Crease* crease : creases) touched = touched || !crease->proximal[mesh].empty() || !crease->distal[mesh].empty();
    if (!touched) continue;
    const std::vector<Eigen::Vector3d>& bind = character.meshes[mesh].positions;
    const SurfacePart& part = surfaces[p];
    const std::array<std::vector<Eigen::Vector3d>, kSurfaceSkinnings> posed = poseSkinnings(bind, parts[p], part, frame, rotations);
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      const std::vector<Eigen::Vector3d> normals = vertexNormals(part.surface.whole, weldedPositions(part.surface, posed[s]));
      auto add = [&](const std::vector<int>& vertices, CreaseSide* side) {
        for (int v : vertices) {
          side->bind.push_back(bind[static_cast<size_t>(v)]);
          side->posed.push_back(posed[s][static_cast<size_t>(v)]);
          side->normal.push_back(normals[static_cast<size_t>(part.surface.weld_of_vertex[static_cast<size_t>(v)])]);
        }
      };
      for (size_t k = 0; k < creases.size(); ++k) {
        add(creases[k]->proximal[mesh], &proximal[k][s]);
        add(creases[k]->distal[mesh], &distal[k][s]);
      }
    }
  }
  std::vector<CreaseContact> contacts(creases.size());
  for (size_t k = 0; k < creases.size(); ++k) {
    const Crease& crease = *creases[k];
    contacts[k].crease = crease.name;
    contacts[k].bend = relativeTurn(frame[static_cast<size_t>(crease.proximal_joint)], frame[static_cast<size_t>(crease.distal_joint)]);
    // Skin closer than a quarter of the crease's reach at bind is the same skin across the fold's line.
    for (int s = 0; s < kSurfaceSkinnings; ++s)
      contacts[k].skinning[s] = creaseContact(proximal[k][s], distal[k][s], 0.25 * crease.radius);
  }
  return contacts;
}

}  // namespace

std::vector<size_t> surfaceSamples(const MeasuredClip& clip, const ClipQuality& figures) {
  const size_t frames = clip.frames->size();
  std::vector<size_t> picked;
  if (frames == 0) return picked;
  auto frameAt = [&](double time) {
    return static_cast<size_t>(std::lower_bound(clip.times.begin(), clip.times.end(), time) - clip.times.begin());
  };
  if (figures.worst_frame >= 0) picked.push_back(static_cast<size_t>(figures.worst_frame));
  picked.push_back(std::min(frameAt(figures.body.input.time), frames - 1));
  picked.push_back(std::min(frameAt(figures.body.dual_quaternion.time), frames - 1));
  picked.push_back(frames - 1);
  std::sort(picked.begin(), picked.end());
  picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
  return picked;
}

std::vector<double> inputRoughnessRise(const Character& character, const std::vector<MeasuredPart>& parts, int skeleton_joints,
                                       double body_height, int threads, const std::vector<SkinFrame>& frames) {
  std::vector<double> rise(frames.size(), 0.0);
  if (parts.empty()) return rise;
  std::vector<SurfacePart> surfaces;
  for (const MeasuredPart& part : parts)
    surfaces.push_back(surfacePart(character.meshes[part.mesh_part], part, skeleton_joints, bodyWeldTolerance(body_height), threads, false));
  parallelForEach(threads, frames.size(), [&](size_t i) {
    std::vector<double> rises;
    for (size_t p = 0; p < parts.size(); ++p) {
      const std::vector<Eigen::Vector3d> posed = skinLinearBlend(character.meshes[parts[p].mesh_part].positions, parts[p].input, frames[i]);
      const std::vector<double> r = roughness(surfaces[p], weldedPositions(surfaces[p].surface, posed));
      for (size_t k = 0; k < r.size(); ++k) rises.push_back(r[k] - surfaces[p].bind_roughness[k]);
    }
    if (!rises.empty()) rise[i] = percentile95(&rises);
  });
  return rise;
}

void measureSurfaceFigures(const Character& character, const std::vector<MeasuredPart>& parts,
                           const std::vector<MeasuredClip>& clips, int skeleton_joints, double body_height, int threads,
                           DeformationQuality* quality, const std::vector<Crease>& creases) {
  assert(quality->clips.size() == clips.size());
  if (parts.empty()) return;
  const double height = std::max(body_height, 1e-3);
  const double weld_tolerance = bodyWeldTolerance(body_height);
  std::vector<SurfacePart> surfaces;
  double bind_volume = 0.0;
  std::vector<std::vector<Eigen::Vector3d>> bind_welded;
  for (const MeasuredPart& part : parts) {
    surfaces.push_back(surfacePart(character.meshes[part.mesh_part], part, skeleton_joints, weld_tolerance, threads, true));
    bind_welded.push_back(surfaces.back().surface.bind);
    bind_volume += enclosedVolume(surfaces.back().surface.whole, bind_welded.back());
  }
  const OccupancyGrid grid = bindOccupancyGrid(character, parts);
  const double bind_occupied = occupiedVolumeOf(surfaces, bind_welded, grid);
  // Every clip's samples in one list, measured on the threads, then read back in order.
  std::vector<std::pair<size_t, size_t>> samples;  // (clip, frame)
  for (size_t c = 0; c < clips.size(); ++c) {
    for (size_t t : surfaceSamples(clips[c], quality->clips[c])) samples.emplace_back(c, t);
  }
  std::vector<SampleFigures> figures(samples.size());
  parallelForEach(threads, samples.size(), [&](size_t i) {
    figures[i] = measureSample(character, parts, surfaces, grid, (*clips[samples[i].first].frames)[samples[i].second]);
  });
  std::vector<double> roughest(clips.size(), -1.0);  // per clip, the rig's largest rise so far
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto [c, t] = samples[i];
    SurfaceFigures& surface = quality->clips[c].surface;
    surface.measured = true;
    if (figures[i].rise[kSurfaceSkinnings - 1] > roughest[c]) {
      roughest[c] = figures[i].rise[kSurfaceSkinnings - 1];
      const SampleFigures& sample = figures[i];
      surface.lumpiest = LumpPlace{};
      if (sample.lump_part >= 0)
        surface.lumpiest = {skinPlace(character, parts[static_cast<size_t>(sample.lump_part)].mesh_part, sample.lump_vertex),
                            sample.lump_rig, sample.lump_input, clips[c].times[t]};
    }
    surface.roughness_floor = kRoughnessFloorPerHeight * height;
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      surface.roughness_rise[s] = std::max(surface.roughness_rise[s], figures[i].rise[s]);
      surface.edge_strain[s] = std::max(surface.edge_strain[s], figures[i].edge_strain[s]);
      surface.area_strain[s] = std::max(surface.area_strain[s], figures[i].area_strain[s]);
    }
    const double change = bind_volume != 0.0 ? figures[i].volume / bind_volume - 1.0 : 0.0;
    if (std::abs(change) > std::abs(surface.centre_of_rotation.change)) surface.centre_of_rotation = {change, clips[c].times[t]};
    for (int s = 0; s < kSurfaceSkinnings; ++s) {
      const double occupied = bind_occupied > 0.0 ? figures[i].occupied[s] / bind_occupied - 1.0 : 0.0;
      if (std::abs(occupied) > std::abs(surface.occupied[s].change)) surface.occupied[s] = {occupied, clips[c].times[t]};
    }
  }
  // Creases: per clip and crease, the sample where the bend peaks (the first of equal ones).
  struct CreaseSample {
    size_t clip, crease, frame;
  };
  std::vector<CreaseSample> crease_samples;
  for (size_t c = 0; c < clips.size(); ++c) {
    const std::vector<SkinFrame>& frames = *clips[c].frames;
    for (size_t k = 0; k < creases.size(); ++k) {
      const size_t a = static_cast<size_t>(creases[k].proximal_joint), b = static_cast<size_t>(creases[k].distal_joint);
      double peak = 0.0;
      size_t at = 0;
      for (size_t t = 0; t < frames.size(); ++t) {
        const double bend = relativeTurn(frames[t][a], frames[t][b]);
        if (bend > peak) {
          peak = bend;
          at = t;
        }
      }
      if (peak >= kMinCreaseBend) crease_samples.push_back({c, k, at});
    }
  }
  // Creases that peak at the same sample (both elbows of a symmetric clip, often its last frame) share
  // its skinning: the samples in order of their first crease, each with its creases.
  std::vector<std::pair<size_t, size_t>> sample_of_group;  // (clip, frame)
  std::vector<std::vector<size_t>> group_samples;          // indices into crease_samples
  for (size_t i = 0; i < crease_samples.size(); ++i) {
    const std::pair<size_t, size_t> at{crease_samples[i].clip, crease_samples[i].frame};
    const auto it = std::find(sample_of_group.begin(), sample_of_group.end(), at);
    if (it == sample_of_group.end()) {
      sample_of_group.push_back(at);
      group_samples.push_back({i});
    } else {
      group_samples[static_cast<size_t>(it - sample_of_group.begin())].push_back(i);
    }
  }
  std::vector<CreaseContact> contacts(crease_samples.size());
  parallelForEach(threads, sample_of_group.size(), [&](size_t g) {
    const auto [c, t] = sample_of_group[g];
    std::vector<const Crease*> at_sample;
    for (size_t i : group_samples[g]) at_sample.push_back(&creases[crease_samples[i].crease]);
    std::vector<CreaseContact> measured = measureCreases(character, parts, surfaces, at_sample, (*clips[c].frames)[t]);
    for (size_t k = 0; k < measured.size(); ++k) {
      measured[k].time = clips[c].times[t];
      contacts[group_samples[g][k]] = std::move(measured[k]);
    }
  });
  for (size_t i = 0; i < crease_samples.size(); ++i) quality->clips[crease_samples[i].clip].creases.push_back(std::move(contacts[i]));
}

}  // namespace rigbake
