#include "pipeline/joint_regions.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include "pipeline/parallel.h"
#include "pipeline/pose.h"
#include "pipeline/skinning.h"

namespace rigbake {
namespace {

// The joint with the largest weight at vertex v (the lowest index on a tie), -1 when it has none.
int strongestJoint(const InfluenceSet& influences, int v) {
  int best = -1;
  double best_weight = 0.0;
  for (int k = 0; k < influences.slots_per_vertex; ++k) {
    const int joint = influences.joints[v * influences.slots_per_vertex + k];
    const double weight = influences.weights[v * influences.slots_per_vertex + k];
    if (weight > best_weight || (weight == best_weight && weight > 0.0 && joint < best)) {
      best = joint;
      best_weight = weight;
    }
  }
  return best;
}

// Six times the signed volume of the triangles about `origin`.
double coneVolume(const std::vector<std::array<int, 3>>& triangles, const std::vector<Eigen::Vector3d>& positions,
                  const Eigen::Vector3d& origin) {
  double sum = 0.0;
  for (const auto& tri : triangles)
    sum += (positions[tri[0]] - origin).dot((positions[tri[1]] - origin).cross(positions[tri[2]] - origin));
  return sum;
}

}  // namespace

void measureJointRegions(const Character& character, const std::vector<MeasuredPart>& parts,
                         const std::vector<MeasuredClip>& clips, int threads, DeformationQuality* quality) {
  assert(quality->clips.size() == clips.size());
  const Skeleton& skeleton = character.skeleton;
  const size_t joint_count = static_cast<size_t>(skeleton.size());
  // Per part and joint, the triangles whose corners all have that joint strongest.
  std::vector<std::vector<std::vector<int>>> listed(parts.size(), std::vector<std::vector<int>>(joint_count));
  std::vector<int> triangle_count(joint_count, 0);
  for (size_t p = 0; p < parts.size(); ++p) {
    const MeshPart& mesh = character.meshes[static_cast<size_t>(parts[p].mesh_part)];
    std::vector<int> strongest(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) strongest[v] = strongestJoint(parts[p].input, static_cast<int>(v));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      const int joint = strongest[static_cast<size_t>(tri[0])];
      if (joint < 0 || joint >= static_cast<int>(joint_count) || strongest[static_cast<size_t>(tri[1])] != joint ||
          strongest[static_cast<size_t>(tri[2])] != joint)
        continue;
      listed[p][static_cast<size_t>(joint)].push_back(static_cast<int>(t));
      ++triangle_count[static_cast<size_t>(joint)];
    }
  }
  std::vector<int> joints;
  for (size_t j = 0; j < joint_count; ++j)
    if (triangle_count[j] >= kMinJointRegionTriangles) joints.push_back(static_cast<int>(j));
  quality->joint_regions.clear();
  for (int j : joints) quality->joint_regions.push_back(skeleton.names[static_cast<size_t>(j)]);
  // Per part, the vertices of those regions' triangles (the only ones skinned), their bind positions,
  // and per region its triangles with corners numbered in that list.
  std::vector<std::vector<int>> needed(parts.size());
  std::vector<std::vector<Eigen::Vector3d>> needed_bind(parts.size());
  std::vector<std::vector<std::vector<std::array<int, 3>>>> corners(parts.size(), std::vector<std::vector<std::array<int, 3>>>(joints.size()));
  for (size_t p = 0; p < parts.size(); ++p) {
    const MeshPart& mesh = character.meshes[static_cast<size_t>(parts[p].mesh_part)];
    std::vector<int> slot(mesh.positions.size(), -1);
    for (int j : joints)
      for (int t : listed[p][static_cast<size_t>(j)])
        for (int corner : mesh.triangles[static_cast<size_t>(t)]) slot[static_cast<size_t>(corner)] = 0;
    for (size_t v = 0; v < slot.size(); ++v) {
      if (slot[v] < 0) continue;
      slot[v] = static_cast<int>(needed[p].size());
      needed[p].push_back(static_cast<int>(v));
      needed_bind[p].push_back(mesh.positions[v]);
    }
    for (size_t r = 0; r < joints.size(); ++r)
      for (int t : listed[p][static_cast<size_t>(joints[r])]) {
        const auto& tri = mesh.triangles[static_cast<size_t>(t)];
        corners[p][r].push_back({slot[static_cast<size_t>(tri[0])], slot[static_cast<size_t>(tri[1])], slot[static_cast<size_t>(tri[2])]});
      }
  }
  // Bind volumes about each joint's bind origin.
  std::vector<double> bind(joints.size(), 0.0);
  for (size_t r = 0; r < joints.size(); ++r) {
    const Eigen::Vector3d origin = skeleton.bind_world[joints[r]].translation();
    for (size_t p = 0; p < parts.size(); ++p) bind[r] += coneVolume(corners[p][r], needed_bind[p], origin);
  }
  for (size_t c = 0; c < clips.size(); ++c) {
    const std::vector<SkinFrame>& frames = *clips[c].frames;
    // Per sample and region: the plain and the rig change.
    std::vector<std::vector<std::array<double, 2>>> change(frames.size(), std::vector<std::array<double, 2>>(joints.size()));
    parallelForEach(threads, frames.size(), [&](size_t t) {
      std::vector<std::array<double, 2>> volume(joints.size(), {0.0, 0.0});
      for (size_t p = 0; p < parts.size(); ++p) {
        const MeshPart& mesh = character.meshes[static_cast<size_t>(parts[p].mesh_part)];
        if (needed[p].empty()) continue;
        std::vector<Eigen::Vector3d> plain, rig;
        skinLinearBlend(mesh.positions, parts[p].input, frames[t], needed[p], &plain);
        skinLinearBlend(mesh.positions, parts[p].rig, frames[t], needed[p], &rig);
        for (size_t r = 0; r < joints.size(); ++r) {
          if (corners[p][r].empty()) continue;
          const Eigen::Vector3d origin = frames[t][static_cast<size_t>(joints[r])] * skeleton.bind_world[joints[r]].translation();
          volume[r][0] += coneVolume(corners[p][r], plain, origin);
          volume[r][1] += coneVolume(corners[p][r], rig, origin);
        }
      }
      for (size_t r = 0; r < joints.size(); ++r)
        for (int s = 0; s < 2; ++s) change[t][r][static_cast<size_t>(s)] = bind[r] != 0.0 ? volume[r][static_cast<size_t>(s)] / bind[r] - 1.0 : 0.0;
    });
    std::vector<JointRegionLoss>& out = quality->clips[c].joint_regions;
    out.assign(joints.size(), JointRegionLoss{});
    for (size_t r = 0; r < joints.size(); ++r) {
      JointRegionLoss& loss = out[r];
      for (size_t t = 0; t < frames.size(); ++t) {
        const double plain = change[t][r][0], rig = change[t][r][1];
        const double beyond = std::max(0.0, std::min(plain, 0.0) - rig);
        const bool take = beyond > loss.loss || (loss.loss == 0.0 && beyond == 0.0 && std::abs(rig) > std::abs(loss.rig));
        if (!take) continue;
        loss.loss = beyond;
        loss.input = plain;
        loss.rig = rig;
        loss.time = clips[c].times[t];
      }
    }
  }
}

}  // namespace rigbake
