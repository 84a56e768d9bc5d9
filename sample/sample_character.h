// A procedural skinned humanoid built by code, so the pipeline has a character whose anatomy is
// known exactly: a mannequin 1.8 m tall in metres, Y-up, facing +Z, its left at +X, arms in a T-pose,
// with the God of War Ragnarök animation-skeleton joint names (JOPelvis1 ... JOHead1, JOLeftClavicle1,
// JOLeftAcromion1, JOLeftScapula1, LeftUpperArm1Twist0, ...) and clips that work the shoulder and
// elbow muscles. Plain data only; formats/sample_gltf turns it into a glTF model.
//
// Guarantees the tests check: every spine joint (JOPelvis1 .. JOHead1) has x = 0 and z = 0, so a body
// frame built from them is exactly world-aligned; joints and mesh are exact mirror images across x = 0
// (negating x of any vertex or joint gives another one, bit for bit); the mesh is a union of closed
// surfaces (every edge shared by exactly two triangles); at most 4 influences per vertex, summing to 1.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "anatomy/character.h"

namespace rigbake {

// Which file convention the character is emitted for. The VRM variants rename every joint to a
// neutral "bone_NN" so that only the VRM extension says what each joint is.
enum class SampleVrm { kNone, kVrm0, kVrm1 };

struct SampleOptions {
  // Wanted vertex count; the mesh comes within a few percent of it.
  int target_vertices = 12000;
  SampleVrm vrm = SampleVrm::kNone;
  // false: the humanoid bone map leaves out upperChest (JOBack3 stays in the skeleton, unmapped), as
  // many VRM 0.x exports do; both VRM versions make the bone optional. Only the VRM variants write the
  // map, so only they change.
  bool upper_chest = true;
};

inline constexpr int kMinSampleVertices = 2000;
inline constexpr int kMaxSampleVertices = 2000000;
inline constexpr double kSampleHeight = 1.8;  // metres, feet at y = 0

struct SampleJoint {
  std::string name;
  int parent = -1;  // parent < own index
  Trs local;        // bind pose relative to the parent
};

// One skinned triangle mesh. Positions and normals are in the bind pose, world space (the mesh node
// has no transform). Weights are floats because that is how glTF stores them; the largest weight of
// each vertex takes what the others leave, so the four floats sum to 1 within float rounding and
// nothing downstream has to renormalise.
struct SampleMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
  std::vector<std::array<int, 4>> joints;     // zero-weight slots hold joint 0
  std::vector<std::array<float, 4>> weights;  // sorted largest first
};

// A rotation track sampled at 30 keys per second, interpolated LINEARly (slerp) between keys.
struct SampleTrack {
  int joint = -1;
  std::vector<double> times;                  // seconds, from 0
  std::vector<Eigen::Quaterniond> rotations;  // local rotation of the joint at each time
};

struct SampleClip {
  std::string name;
  std::vector<SampleTrack> tracks;
};

struct SampleCharacter {
  std::string name;
  std::vector<SampleJoint> joints;
  SampleMesh mesh;
  std::vector<SampleClip> clips;
  SampleVrm vrm = SampleVrm::kNone;
  // VRM humanoid bone name ("hips", "leftUpperArm", ...) -> joint index; filled for every variant
  // (without "upperChest" when SampleOptions::upper_chest is false).
  std::vector<std::pair<std::string, int>> humanoid_bones;

  int findJoint(const std::string& joint_name) const;  // -1 when absent
};

// Throws Error USAGE when options.target_vertices is outside [kMinSampleVertices, kMaxSampleVertices].
// The output depends only on the options (no randomness, no clock).
//
// VRM 0.x variant: VRM 0.x requires models to face -Z with unrotated bones, so that variant is the same
// body turned 180 degrees about Y (its left at -X) with every bind rotation identity; the neck's +Z
// axis then still points to the back. VRM 1.0 faces +Z like the plain variant.
SampleCharacter makeSampleCharacter(const SampleOptions& options);

// Bind pose world transform of every joint, composed from the local transforms.
std::vector<Eigen::Affine3d> sampleBindWorld(const SampleCharacter& character);

// Left/right twin of each joint (itself for joints on the midline), from the names of the plain
// variant; the VRM variants keep the same joint order.
std::vector<int> sampleMirrorJoints(const SampleCharacter& character);

}  // namespace rigbake
