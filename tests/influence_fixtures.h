// Influence data for the influence and packing tests: every skinned part of every shared asset, as the
// file stores it (at most 4 influences) and widened deterministically to up to 16 influences so 7 and
// 10 are exercised (and pruned) on real meshes and skeletons.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "formats/gltf_document.h"
#include "pipeline/influences.h"
#include "pipeline/pose.h"
#include "pipeline/quantize_for_motion.h"
#include "test_support.h"

namespace rigbake::test {

struct PartInfluences {
  std::string name;  // "asset#part index name"
  std::vector<Eigen::Vector3d> positions;
  InfluenceSet real;  // as loaded, zero slots on joint 0
  InfluenceSet wide;  // widened over neighbouring joints, 16 slots
};

struct AssetInfluences {
  std::string asset;
  Skeleton skeleton;
  double height = 0.0;  // the character's extent along Y, rigid parts included (scene units, metres)
  std::vector<PartInfluences> parts;
};

// std::mt19937's output sequence is fixed by the standard; std::uniform_real_distribution is not, so
// the fraction comes from the raw bits: 27 bits, exact in a double, in [0, 1).
inline double unitInterval(std::mt19937& rng) { return static_cast<double>(rng() >> 5) * (1.0 / 134217728.0); }

// Moves a random 10-70% of each vertex's weight onto 2..12 joints near its own in the hierarchy
// (parents, grandparents, children, grandchildren, siblings, the parent's siblings). Every 7th vertex gets two exactly equal new weights so
// the joint-index tie-break is exercised on real data.
inline InfluenceSet widenInfluences(const InfluenceSet& real, const Skeleton& skeleton, std::uint32_t seed) {
  constexpr int kSlots = 16;
  std::mt19937 rng(seed);
  std::vector<std::vector<int>> children(skeleton.size());
  for (int j = 0; j < skeleton.size(); ++j) {
    if (skeleton.parents[j] >= 0) children[skeleton.parents[j]].push_back(j);
  }
  InfluenceSet wide;
  wide.slots_per_vertex = kSlots;
  wide.joints.assign(static_cast<size_t>(real.vertexCount()) * kSlots, 0);
  wide.weights.assign(static_cast<size_t>(real.vertexCount()) * kSlots, 0.0);
  for (int v = 0; v < real.vertexCount(); ++v) {
    std::vector<int> own;
    std::vector<double> own_weights;
    for (int k = 0; k < real.slots_per_vertex; ++k) {
      size_t index = static_cast<size_t>(v) * real.slots_per_vertex + k;
      if (real.weights[index] == 0.0) continue;
      own.push_back(real.joints[index]);
      own_weights.push_back(real.weights[index]);
    }
    std::vector<int> candidates;
    auto offer = [&](int joint) {
      if (joint >= 0 && std::find(own.begin(), own.end(), joint) == own.end()) candidates.push_back(joint);
    };
    for (int joint : own) {
      int parent = skeleton.parents[joint];
      offer(parent);
      if (parent >= 0) {
        int grandparent = skeleton.parents[parent];
        offer(grandparent);
        for (int sibling : children[parent]) offer(sibling);
        if (grandparent >= 0) {
          for (int uncle : children[grandparent]) offer(uncle);
        }
      }
      for (int child : children[joint]) {
        offer(child);
        for (int grandchild : children[child]) offer(grandchild);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    int extra = std::min<int>(static_cast<int>(candidates.size()), 2 + static_cast<int>(rng() % 11));
    // Partial Fisher-Yates: the first `extra` candidates become a random selection.
    for (int i = 0; i < extra; ++i) {
      int pick = i + static_cast<int>(rng() % static_cast<std::uint32_t>(candidates.size() - i));
      std::swap(candidates[i], candidates[pick]);
    }
    double moved = extra > 0 ? 0.1 + 0.6 * unitInterval(rng) : 0.0;
    std::vector<double> shares(extra);
    double share_sum = 0.0;
    for (int i = 0; i < extra; ++i) {
      shares[i] = 0.05 + unitInterval(rng);
      if (i == 1 && v % 7 == 0) shares[i] = shares[0];
      share_sum += shares[i];
    }
    size_t base = static_cast<size_t>(v) * kSlots;
    int slot = 0;
    for (size_t i = 0; i < own.size(); ++i, ++slot) {
      wide.joints[base + slot] = own[i];
      wide.weights[base + slot] = own_weights[i] * (1.0 - moved);
    }
    for (int i = 0; i < extra; ++i, ++slot) {
      wide.joints[base + slot] = candidates[i];
      wide.weights[base + slot] = moved * shares[i] / share_sum;
    }
  }
  return wide;
}

// Loaded once per test run. Missing assets WARN (FAIL under CI=true) and are left out.
inline const std::vector<AssetInfluences>& assetInfluences() {
  static std::vector<AssetInfluences> assets;
  static bool loaded = false;
  if (loaded) return assets;
  std::uint32_t seed = 20240601u;
  for (const std::string& name : sharedAssetNames()) {
    std::string path = requireAsset(name);
    if (path.empty()) continue;
    Character character = loadCharacter(path).character;
    AssetInfluences asset;
    asset.asset = name;
    asset.skeleton = character.skeleton;
    double min_y = 1e300, max_y = -1e300;
    for (size_t p = 0; p < character.meshes.size(); ++p) {
      const MeshPart& mesh = character.meshes[p];
      if (!mesh.skinned && mesh.rigid_joint < 0) continue;
      for (const Eigen::Vector3d& position : mesh.positions) {
        min_y = std::min(min_y, position.y());
        max_y = std::max(max_y, position.y());
      }
      if (!mesh.skinned) continue;
      PartInfluences part;
      part.name = name + "#" + std::to_string(p) + " " + mesh.name;
      part.positions = mesh.positions;
      part.real = influencesFromMesh(mesh);
      part.wide = widenInfluences(part.real, character.skeleton, seed++);
      asset.parts.push_back(std::move(part));
    }
    asset.height = max_y - min_y;
    assets.push_back(std::move(asset));
  }
  loaded = true;
  return assets;
}

// A deterministic pose: each joint turns up to `max_degrees` about a random axis through its own bind
// position, on top of its parent's motion (skin_j = skin_parent * rotation about c_j), so rotations
// accumulate down the limbs as in a real pose.
inline std::vector<Eigen::Affine3d> randomPoseSkinMatrices(const Skeleton& skeleton, std::uint32_t seed,
                                                           double max_degrees) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Affine3d> skin(skeleton.size(), Eigen::Affine3d::Identity());
  for (int j = 0; j < skeleton.size(); ++j) {
    Eigen::Vector3d axis;
    do {
      axis = Eigen::Vector3d(unitInterval(rng), unitInterval(rng), unitInterval(rng)) * 2.0 -
             Eigen::Vector3d::Ones();
    } while (axis.norm() < 0.1 || axis.norm() > 1.0);
    double angle = (2.0 * unitInterval(rng) - 1.0) * max_degrees * 3.14159265358979323846 / 180.0;
    Eigen::Vector3d center = skeleton.bindPosition(j);
    Eigen::Affine3d turn = Eigen::Translation3d(center) * Eigen::AngleAxisd(angle, axis.normalized()) *
                           Eigen::Translation3d(-center);
    int parent = skeleton.parents[j];
    skin[j] = (parent >= 0 ? skin[parent] : Eigen::Affine3d::Identity()) * turn;
  }
  return skin;
}

// Skin matrices at every key time of every clip: the asset's own motion, no muscles (the frames the
// rounding and the refit are tested against).
inline std::vector<SkinFrame> ownClipFrames(const Character& character) {
  std::vector<SkinFrame> frames;
  for (const Clip& clip : character.clips) {
    for (double time : sampleTimes(clip, 0.0)) {
      const Pose pose = sampleClip(character.skeleton, clip, time);
      SkinFrame skin(character.skeleton.size());
      for (int j = 0; j < character.skeleton.size(); ++j) skin[j] = skinMatrix(pose, character.skeleton, j);
      frames.push_back(std::move(skin));
    }
  }
  return frames;
}

}  // namespace rigbake::test
