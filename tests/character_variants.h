// Variants of a loaded character that a studio's export could give for the same body (issue 29 asks the
// skin to be judged on them): moved and turned in its scene, or hung under a new armature root. Each
// keeps every joint's world bind pose and every clip's world motion, so anything measured on the body
// must come out as on the original.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "anatomy/character.h"

namespace rigbake::test {

// The whole character (joints, meshes, the frame root joints' clips compose into) moved by `motion`. The
// joints' local transforms, and so every clip, are unchanged: a root joint's frame is its parent node's
// world transform.
inline Character movedBy(Character c, const Eigen::Affine3d& motion) {
  for (Eigen::Affine3d& bind : c.skeleton.bind_world) bind = motion * bind;
  for (Eigen::Affine3d& parent : c.skeleton.root_parent_world) parent = motion * parent;
  for (MeshPart& part : c.meshes) {
    for (Eigen::Vector3d& p : part.positions) p = motion * p;
  }
  for (Eigen::Affine3d& placement : c.skin_placement) placement = motion * placement;
  return c;
}

// A rotation or translation track's keys carried into a new parent frame `a` (turning by `turn`, a's
// rotation without its scale): a rotation key turns, a translation key moves as a point. A cubic
// spline's tangents are derivatives: a quaternion's turned, not renormalized; a translation's turned,
// not moved.
inline void changeTrackFrame(const Eigen::Affine3d& a, const Eigen::Quaterniond& turn, Track* track) {
  std::vector<double>& values = track->values;
  if (track->path == AnimatedPath::kRotation) {
    for (size_t k = 0; k + 4 <= values.size(); k += 4) {
      const Eigen::Quaterniond turned = turn * Eigen::Quaterniond(values[k + 3], values[k], values[k + 1], values[k + 2]);
      values[k] = turned.x();
      values[k + 1] = turned.y();
      values[k + 2] = turned.z();
      values[k + 3] = turned.w();
    }
    return;
  }
  const bool cubic = track->interpolation == Interpolation::kCubicSpline;
  for (size_t k = 0; k + 3 <= values.size(); k += 3) {
    const Eigen::Vector3d t(values[k], values[k + 1], values[k + 2]);
    const bool tangent = cubic && (k / 3) % 3 != 1;
    const Eigen::Vector3d moved = tangent ? Eigen::Vector3d(a.linear() * t) : Eigen::Vector3d(a * t);
    for (int i = 0; i < 3; ++i) values[k + i] = moved[i];
  }
}

// A new armature root joint named `root`, with local transform `root_local` in the first root's parent
// frame (a rotation and a translation: Blender's armature object turned a quarter about X, or a root
// bone at the feet), under which the old roots hang. Every joint keeps its world bind pose; the old
// roots' rest transforms and animation keys are re-expressed in the new root's frame, so every clip
// moves every old joint as before (the new root is not animated).
inline Character withNewRoot(Character c, const Trs& root_local) {
  Skeleton& s = c.skeleton;
  auto shifted = [](int joint) { return joint < 0 ? joint : joint + 1; };
  const Eigen::Affine3d root_parent = s.root_parent_world[0];
  const Eigen::Affine3d root = root_parent * root_local.matrix();
  // An old root's local frame was its parent node's; `into_root[j]` takes it into the new root's. The
  // roots of one armature can hang under different nodes (Cowboy's second root is not under the scaled
  // armature node the first is), so `into_root[j]` may scale as well as turn and move; uniformly, as a
  // node's world transform in these files does. So a rotation key turns by its rotation, a translation
  // key moves as a point, and a scale key grows by its scale.
  std::vector<Eigen::Affine3d> into_root(s.size(), Eigen::Affine3d::Identity());
  std::vector<double> root_scale(s.size(), 1.0);
  std::vector<Eigen::Quaterniond> root_turn(s.size(), Eigen::Quaterniond::Identity());
  for (int j = 0; j < s.size(); ++j) {
    if (s.parents[j] >= 0) continue;
    into_root[j] = root.inverse() * s.root_parent_world[j];
    root_scale[j] = std::cbrt(into_root[j].linear().determinant());
    root_turn[j] = Eigen::Quaterniond(into_root[j].linear() / root_scale[j]).normalized();
    s.rest_local[j].translation = into_root[j] * s.rest_local[j].translation;
    s.rest_local[j].rotation = root_turn[j] * s.rest_local[j].rotation;
    s.rest_local[j].scale *= root_scale[j];
    s.root_parent_world[j] = root;
  }
  for (Clip& clip : c.clips) {
    for (Track& track : clip.tracks) {
      if (s.parents[track.joint] >= 0) continue;
      if (track.path == AnimatedPath::kScale) {
        for (double& value : track.values) value *= root_scale[track.joint];  // tangents grow alike
      } else {
        changeTrackFrame(into_root[track.joint], root_turn[track.joint], &track);
      }
    }
  }
  for (int& parent : s.parents) parent = parent < 0 ? 0 : parent + 1;
  s.parents.insert(s.parents.begin(), -1);
  s.names.insert(s.names.begin(), "root");
  s.nodes.insert(s.nodes.begin(), -1);
  s.bind_world.insert(s.bind_world.begin(), root);
  s.rest_local.insert(s.rest_local.begin(), root_local);
  s.root_parent_world.insert(s.root_parent_world.begin(), root_parent);
  for (MeshPart& part : c.meshes) {
    for (int& joint : part.skin_joints) joint = shifted(joint);
    for (int& joint : part.joints) joint = shifted(joint);
    part.rigid_joint = shifted(part.rigid_joint);
  }
  for (Clip& clip : c.clips) {
    for (Track& track : clip.tracks) track.joint = shifted(track.joint);
  }
  for (auto& [bone, joint] : c.vrm_humanoid) joint = shifted(joint);
  return c;
}

// `joint` moved under its sibling `new_parent`, as 3ds Max's Biped hangs the clavicles from the neck
// where most rigs hang them from the chest. Every joint keeps its world bind pose and every clip moves
// it as before: the sibling must carry no clip's track and no scale, so the move is one rigid change
// of frame, applied to the joint's rest transform and its keys.
inline Character withJointUnderSibling(Character c, int joint, int new_parent) {
  Skeleton& s = c.skeleton;
  bool rigid = s.parents[joint] == s.parents[new_parent] && new_parent < joint &&
               s.rest_local[new_parent].scale.isApprox(Eigen::Vector3d::Ones());
  for (const Clip& clip : c.clips)
    for (const Track& track : clip.tracks) rigid = rigid && track.joint != new_parent;
  if (!rigid) throw std::invalid_argument("withJointUnderSibling: the sibling moves, scales or comes later");
  const Eigen::Affine3d into_sibling = s.rest_local[new_parent].matrix().inverse();
  const Eigen::Quaterniond turn(into_sibling.linear());
  s.rest_local[joint].translation = into_sibling * s.rest_local[joint].translation;
  s.rest_local[joint].rotation = turn * s.rest_local[joint].rotation;
  for (Clip& clip : c.clips)
    for (Track& track : clip.tracks)
      if (track.joint == joint && track.path != AnimatedPath::kScale) changeTrackFrame(into_sibling, turn, &track);
  s.parents[joint] = new_parent;
  return c;
}

// Every skinned mesh part's vertices in another order, as another exporter may write them: vertex v
// of the original is vertex order[v] of the variant, with order[v] = (v * stride + 1) mod n for a
// stride coprime with n (a shuffle, not a reversal a loop could undo), and the triangles listed in
// reverse order, each starting at its second corner (same winding). `order` gets each part's map.
inline Character withVerticesReordered(Character c, std::vector<std::vector<int>>* order) {
  order->assign(c.meshes.size(), {});
  for (size_t p = 0; p < c.meshes.size(); ++p) {
    MeshPart& part = c.meshes[p];
    const int n = static_cast<int>(part.positions.size());
    if (!part.skinned || n == 0) continue;
    int stride = 7919;
    while (std::gcd(stride, n) != 1) stride += 2;
    std::vector<int>& to = (*order)[p];
    to.resize(n);
    for (int v = 0; v < n; ++v) to[v] = static_cast<int>((static_cast<long long>(v) * stride + 1) % n);
    const MeshPart original = part;
    const int slots = part.influences_per_vertex;
    for (int v = 0; v < n; ++v) {
      part.positions[to[v]] = original.positions[v];
      for (int k = 0; k < slots; ++k) {
        part.joints[static_cast<size_t>(to[v]) * slots + k] = original.joints[static_cast<size_t>(v) * slots + k];
        part.weights[static_cast<size_t>(to[v]) * slots + k] = original.weights[static_cast<size_t>(v) * slots + k];
      }
    }
    const size_t t = part.triangles.size();
    for (size_t i = 0; i < t; ++i) {
      const std::array<int, 3>& tri = original.triangles[t - 1 - i];
      part.triangles[i] = {to[tri[1]], to[tri[2]], to[tri[0]]};
    }
  }
  return c;
}

}  // namespace rigbake::test
