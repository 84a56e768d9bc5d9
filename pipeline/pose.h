// Evaluating a skeleton: the rest pose, the bind pose and glTF 2.0 animation sampling.
// Every pose is in the scene's world space, like Skeleton::bind_world, so a posed joint and its
// bind transform compare directly and skinMatrix() needs no extra space change.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "anatomy/character.h"

namespace rigbake {

// One joint transform per skeleton joint. local[j] is relative to the parent joint's world (or to
// Skeleton::root_parent_world[j] for a root joint); world[j] is that chain composed.
struct Pose {
  std::vector<Trs> local;
  std::vector<Eigen::Affine3d> world;
};

// The nodes' own TRS, composed: what a glTF viewer shows with no animation playing. It differs from
// the bind pose when the file was skinned in another pose (KayKit, RobotExpressive, the Quaternius
// characters); skinMatrix() is correct for either.
Pose restPose(const Skeleton& skeleton);

// world[j] is bind_world[j] exactly; local[j] is decomposed from it (exact unless the bind transforms
// carry shear, which glTF nodes cannot express).
Pose bindPose(const Skeleton& skeleton);

// Composes world = root_parent_world * local chain, relying on parents[j] < j.
// `local` must hold one Trs per joint.
Pose composePose(const Skeleton& skeleton, std::vector<Trs> local);

// The rest pose with every track of `clip` sampled at `time` (seconds) per glTF 2.0 Appendix C:
// LINEAR lerps translation/scale and slerps rotation along the shortest path, STEP holds the key at
// or before `time`, CUBICSPLINE is the Hermite spline with tangents scaled by the key interval and a
// normalized rotation. Before the first key the first value holds, after the last key the last one.
// When several tracks animate the same joint and path, the later track wins.
Pose sampleClip(const Skeleton& skeleton, const Clip& clip, double time);

// A translation or scale track (3 numbers per key) sampled at `time`.
Eigen::Vector3d sampleVectorTrack(const Track& track, double time);
// A rotation track (x y z w per key) sampled at `time`.
Eigen::Quaterniond sampleRotationTrack(const Track& track, double time);

// Times to bake a clip at, ascending. fps <= 0: the union of the clip's key times, with times closer
// than kSampleTimeTolerance merged (different tracks store the same key through float rounding).
// fps > 0: 0, 1/fps, 2/fps, ... and the clip's duration itself as the last sample.
constexpr double kSampleTimeTolerance = 1e-5;
std::vector<double> sampleTimes(const Clip& clip, double fps);

// m * p for a point, written out: the skinning loops call it billions of times, and Eigen's generic
// Transform * Vector product is not inlined in the sanitizer build, which made it 25x slower there.
inline Eigen::Vector3d transformPoint(const Eigen::Affine3d& m, const Eigen::Vector3d& p) {
  const double* a = m.data();  // column-major 4x4
  return {a[0] * p[0] + a[4] * p[1] + a[8] * p[2] + a[12], a[1] * p[0] + a[5] * p[1] + a[9] * p[2] + a[13],
          a[2] * p[0] + a[6] * p[1] + a[10] * p[2] + a[14]};
}

// Maps a bind-pose world position (MeshPart::positions) to its posed world position through joint j:
// pose.world[j] * bind_world[j]^-1 (the glTF joint matrix, moved to scene space).
Eigen::Affine3d skinMatrix(const Pose& pose, const Skeleton& skeleton, int joint);

// Splits an affine transform into T, R, S with the scale along R's own axes. Exact when the linear
// part's columns are orthogonal (any TRS-built matrix); a reflection becomes a negative x scale.
// Shear (a child of a non-uniformly scaled parent) has no TRS: R is then the rotation closest to the
// axis directions and S the axes' lengths along it. The transform must be invertible.
Trs decomposeTrs(const Eigen::Affine3d& transform);

}  // namespace rigbake
