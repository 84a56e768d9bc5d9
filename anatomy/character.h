// The plain data a loaded character becomes. formats/ fills it from glTF/GLB/VRM; anatomy/ and
// pipeline/ read it and never see a tinygltf type.
//
// Space: everything is in the scene's world space at the bind pose, in the scene's units (glTF says
// metres). A skin's bind space is mapped to the scene through its root joint (world at rest times its
// inverse bind matrix), so FBX2glTF files whose armature is scaled by 100 and Z-up exports both come
// out Y-up in metres, as a glTF viewer shows them.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace rigbake {

// A node's local transform split into translation, rotation and scale, as glTF animates it.
struct Trs {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  Eigen::Affine3d matrix() const;
};

// Joints are ordered so that parents[i] < i; a root joint has parent -1.
struct Skeleton {
  std::vector<std::string> names;
  std::vector<int> parents;
  std::vector<int> nodes;                   // glTF node index of each joint
  std::vector<Eigen::Affine3d> bind_world;  // bind pose, scene world space
  std::vector<Trs> rest_local;              // the node's own TRS (animation starts from it)
  // World transform of the non-joint node above each root joint, at rest: the frame the
  // animated local transforms of a root joint are composed into.
  std::vector<Eigen::Affine3d> root_parent_world;

  int size() const { return static_cast<int>(names.size()); }
  int find(const std::string& name) const;  // -1 when absent
  Eigen::Vector3d bindPosition(int joint) const { return bind_world[joint].translation(); }
  std::vector<int> children(int joint) const;
};

// One glTF primitive, with vertices moved to the scene's world space at bind pose.
struct MeshPart {
  std::string name;
  int gltf_mesh = -1;
  int gltf_primitive = -1;
  int gltf_node = -1;
  bool skinned = false;
  int gltf_skin = -1;
  // The skin's joint list as skeleton indices: JOINTS_n values index this list in the file.
  std::vector<int> skin_joints;
  // A rigid part rides this joint (the nearest joint above its node), -1 when none.
  int rigid_joint = -1;
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<int, 3>> triangles;
  // Skin influences in skeleton joint indices, as many slots per vertex as the file has (4 per set).
  int influences_per_vertex = 0;
  std::vector<int> joints;      // vertex-major: joints[v * influences_per_vertex + k]
  std::vector<double> weights;  // same layout
};

enum class Interpolation { kLinear, kStep, kCubicSpline };
enum class AnimatedPath { kTranslation, kRotation, kScale };

struct Track {
  int joint = -1;  // skeleton joint index
  AnimatedPath path = AnimatedPath::kTranslation;
  Interpolation interpolation = Interpolation::kLinear;
  std::vector<double> times;
  // Each key holds 3 (T, S) or 4 (R, x y z w) numbers; CUBICSPLINE keys hold in-tangent, value,
  // out-tangent in that order, as glTF stores them.
  std::vector<double> values;
};

struct Clip {
  std::string name;
  int gltf_animation = -1;  // -1 for a clip that is not in the file
  double duration = 0.0;
  std::vector<Track> tracks;
  // Added in memory to be measured on, never written: the range-of-motion clips of `bake --rom` and
  // `validate --rom` (pipeline/rom.h). Stages that measure treat it as any clip; writers skip it.
  bool measure_only = false;
};

struct Character {
  std::string source;  // the file name as given, for messages
  Skeleton skeleton;
  std::vector<MeshPart> meshes;
  std::vector<Clip> clips;
  // Per glTF skin, the transform from its bind space to the scene (see formats/gltf_read.cpp).
  std::vector<Eigen::Affine3d> skin_placement;
  // VRM humanoid bone name (e.g. "leftUpperArm") -> skeleton joint index, when the file is a VRM.
  std::map<std::string, int> vrm_humanoid;
  std::string vrm_version;  // "0.x", "1.0" or empty
};

}  // namespace rigbake
