// Exports jiggle setups as VRM spring bones so VRM runtimes simulate them live: VRMC_springBone 1.0
// (vrm-c/vrm-specification, specification/VRMC_springBone-1.0) for VRM 1.0 models, and the
// "secondaryAnimation.boneGroups" of the VRM 0.x "VRM" extension for VRM 0.x models. docs/jiggle.md
// gives the parameter mapping.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pipeline/jiggle.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

// Reference frame time at which VRM's per-frame (Verlet) spring constants are matched to the fixed-
// step spring: VRM runtimes step once per rendered frame, commonly 60 Hz.
constexpr double kVrmReferenceFrameTime = 1.0 / 60.0;
// hitRadius as a fraction of the jiggle length: only used against colliders, which rigbake does not
// write, so it just sizes the tail sphere for a runtime that adds some.
constexpr double kVrmHitRadiusFraction = 0.2;

struct VrmSpring {
  std::string name;
  int head_node = -1;  // glTF node that rotates (the jiggling joint)
  // The tail, in the head node's local coordinates: a new empty child node is added there, so every
  // spring is its own chain [head, tail] and no joint belongs to two chains (the spec forbids it).
  Eigen::Vector3d tail_local = Eigen::Vector3d::UnitY();
  double stiffness = 0.0;      // VRM stiffness (stiffnessForce)
  double drag_force = 0.0;     // VRM dragForce, [0, 1]
  double gravity_power = 0.0;  // the jiggle rests on its animated target: no gravity
  Eigen::Vector3d gravity_dir{0.0, -1.0, 0.0};
  double hit_radius = 0.0;     // metres
};

// The VRM parameters equivalent to a jiggle at kVrmReferenceFrameTime: stiffness = k L dt,
// dragForce = 1 - exp(-beta dt), hitRadius = kVrmHitRadiusFraction L. `head_node` is the node of the
// jiggling joint in the written model and `head_scale` its local scale (the tail is in node units).
VrmSpring vrmSpringFor(const JiggleSetup& setup, int head_node, const Eigen::Vector3d& head_scale = Eigen::Vector3d::Ones());

// For kSkeletonJoint setups: skeleton.nodes gives the node, rest_local the scale. kMuscle setups are
// skipped (their nodes exist only once the bake has written them: use vrmSpringFor).
std::vector<VrmSpring> vrmSpringsForSkeleton(const Skeleton& skeleton, const std::vector<JiggleSetup>& setups);

// Adds the springs (and their tail nodes) to a model carrying "VRMC_vrm" (as VRMC_springBone, appended
// to an existing one) or "VRM" (as secondaryAnimation boneGroups). Throws USAGE when the model is not
// a VRM, GLTF_PARSE_FAILED when a head node is out of range or the VRM extension is malformed.
void addVrmSpringBones(tinygltf::Model* model, const std::vector<VrmSpring>& springs);

}  // namespace rigbake
