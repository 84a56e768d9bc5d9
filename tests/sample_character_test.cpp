#include "sample/sample_character.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <set>

#include "core/error.h"
#include "external_tools.h"
#include "formats/gltf_document.h"
#include "formats/gltf_write.h"
#include "formats/sample_gltf.h"
#include "test_support.h"

using namespace rigbake;
namespace ext = rigbake::test::external;

namespace {

const SampleCharacter& defaultSample() {
  static const SampleCharacter kSample = makeSampleCharacter({});
  return kSample;
}

const std::vector<std::string>& expectedJointNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> names = {"JOPelvis1", "JOBack1", "JOBack2", "JOBack3", "JONeck1", "JOHead1"};
    for (const char* side : {"Left", "Right"}) {
      std::string s = side;
      for (const std::string& n : {"JO" + s + "Clavicle1", "JO" + s + "Acromion1", "JO" + s + "Scapula1",
                                   "JO" + s + "UpperArm1", s + "UpperArm1Twist0", "JO" + s + "LowerArm1",
                                   s + "LowerArm1Twist0", "JO" + s + "Hand1", "JO" + s + "UpLeg1", "JO" + s + "Leg1",
                                   "JO" + s + "Foot1", "JO" + s + "Toe1"})
        names.push_back(n);
    }
    return names;
  }();
  return kNames;
}

int findRoot(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

// Connected components of the mesh, as a component id per triangle.
std::vector<int> triangleComponents(const SampleMesh& mesh, int* count) {
  std::vector<int> parent(mesh.positions.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.triangles) {
    parent[findRoot(parent, t[1])] = findRoot(parent, t[0]);
    parent[findRoot(parent, t[2])] = findRoot(parent, t[0]);
  }
  std::map<int, int> ids;
  std::vector<int> component;
  for (const auto& t : mesh.triangles) {
    int root = findRoot(parent, t[0]);
    auto it = ids.emplace(root, static_cast<int>(ids.size())).first;
    component.push_back(it->second);
  }
  *count = static_cast<int>(ids.size());
  return component;
}

Eigen::Vector3d jointWorld(const SampleCharacter& c, const std::string& name) {
  int j = c.findJoint(name);
  REQUIRE(j >= 0);
  return sampleBindWorld(c)[j].translation();
}

const SampleTrack& trackOf(const SampleClip& clip, int joint) {
  auto it = std::find_if(clip.tracks.begin(), clip.tracks.end(), [&](const SampleTrack& t) { return t.joint == joint; });
  INFO("clip " << clip.name << ", joint " << joint);
  REQUIRE(it != clip.tracks.end());
  return *it;
}

const SampleClip& clipNamed(const SampleCharacter& c, const std::string& name) {
  auto it = std::find_if(c.clips.begin(), c.clips.end(), [&](const SampleClip& clip) { return clip.name == name; });
  INFO("clip " << name);
  REQUIRE(it != c.clips.end());
  return *it;
}

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

double angleDegrees(const Eigen::Quaterniond& q) { return Eigen::AngleAxisd(q.normalized()).angle() * kDegreesPerRadian; }

}  // namespace

TEST_CASE("the sample has the talk's joints, a T-pose and 1.8 m height in metres") {
  const SampleCharacter& c = defaultSample();
  std::vector<std::string> names;
  for (const SampleJoint& joint : c.joints) names.push_back(joint.name);
  CHECK(std::set<std::string>(names.begin(), names.end()) ==
        std::set<std::string>(expectedJointNames().begin(), expectedJointNames().end()));
  CHECK(names.size() == expectedJointNames().size());
  for (size_t j = 0; j < c.joints.size(); ++j) CHECK(c.joints[j].parent < static_cast<int>(j));

  double min_y = 1e9, max_y = -1e9;
  for (const auto& p : c.mesh.positions) {
    min_y = std::min(min_y, p.y());
    max_y = std::max(max_y, p.y());
  }
  CHECK(min_y == 0.0);
  CHECK(max_y == kSampleHeight);
  // Faces +Z (toes in front of the ankles), its left at +X, arms straight out along X.
  CHECK(jointWorld(c, "JOLeftToe1").z() > jointWorld(c, "JOLeftFoot1").z() + 0.1);
  CHECK(jointWorld(c, "JOLeftUpperArm1").x() > 0.1);
  CHECK(jointWorld(c, "JOLeftHand1").y() == jointWorld(c, "JOLeftUpperArm1").y());
  // Acromion lateral to and above the glenohumeral joint; scapula joint medial and behind the ribcage.
  Eigen::Vector3d acromion = jointWorld(c, "JOLeftAcromion1"), shoulder = jointWorld(c, "JOLeftUpperArm1"),
                  scapula = jointWorld(c, "JOLeftScapula1"), back3 = jointWorld(c, "JOBack3");
  CHECK(acromion.x() > shoulder.x());
  CHECK(acromion.y() > shoulder.y());
  CHECK(scapula.x() < shoulder.x());
  CHECK(scapula.z() < back3.z() - 0.05);
}

TEST_CASE("the spine lies on x = 0 in one sagittal line and only the neck is rotated, its Z to the back") {
  const SampleCharacter& c = defaultSample();
  std::vector<Eigen::Affine3d> world = sampleBindWorld(c);
  const double spine_z = jointWorld(c, "JOPelvis1").z();
  for (const char* name : {"JOPelvis1", "JOBack1", "JOBack2", "JOBack3", "JONeck1", "JOHead1"}) {
    INFO(name);
    CHECK(jointWorld(c, name).x() == 0.0);
    CHECK(jointWorld(c, name).z() == spine_z);
  }
  int neck = c.findJoint("JONeck1");
  for (int j = 0; j < static_cast<int>(c.joints.size()); ++j) {
    INFO(c.joints[j].name);
    if (j == neck) CHECK(world[j].linear().col(2).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
    else CHECK(world[j].linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  }
}

TEST_CASE("the sample mesh is large enough and follows the vertex target") {
  CHECK(defaultSample().mesh.positions.size() >= 10000);
  for (int target : {kMinSampleVertices, 12000, 100000}) {
    INFO(target);
    SampleOptions options;
    options.target_vertices = target;
    double count = static_cast<double>(makeSampleCharacter(options).mesh.positions.size());
    CHECK(std::abs(count - target) / target < 0.05);
  }
  SampleOptions too_small;
  too_small.target_vertices = kMinSampleVertices - 1;
  CHECK_THROWS_AS(makeSampleCharacter(too_small), Error);
}

TEST_CASE("every body part is a closed surface facing outwards") {
  for (int target : {kMinSampleVertices, 12000}) {
    INFO(target);
    SampleOptions options;
    options.target_vertices = target;
    SampleMesh mesh = makeSampleCharacter(options).mesh;
    // Each directed edge once and its reverse once: every edge is shared by exactly two triangles,
    // wound consistently.
    std::map<std::pair<int, int>, int> directed;
    for (const auto& t : mesh.triangles) {
      CHECK((t[0] != t[1] && t[1] != t[2] && t[0] != t[2]));
      for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    }
    int bad_edges = 0;
    for (const auto& [edge, count] : directed) {
      auto reverse = directed.find({edge.second, edge.first});
      if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad_edges;
    }
    CHECK(bad_edges == 0);
    int components = 0;
    std::vector<int> component = triangleComponents(mesh, &components);
    // Torso, neck, head, and per side upper arm, forearm, hand, thigh, shin, foot.
    CHECK(components == 15);
    std::vector<double> volume(components, 0.0);
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
      const auto& t = mesh.triangles[i];
      volume[component[i]] += mesh.positions[t[0]].dot(mesh.positions[t[1]].cross(mesh.positions[t[2]])) / 6.0;
    }
    for (double v : volume) CHECK(v > 0.0);
    // Every vertex is used, and normals are unit vectors.
    std::vector<char> used(mesh.positions.size(), 0);
    for (const auto& t : mesh.triangles)
      for (int v : t) used[v] = 1;
    CHECK(std::count(used.begin(), used.end(), 0) == 0);
    for (const auto& n : mesh.normals) CHECK(std::abs(n.norm() - 1.0) < 1e-9);
  }
}

TEST_CASE("skin weights: at most four influences, summing to 1, zero slots on joint 0") {
  const SampleCharacter& c = defaultSample();
  const SampleMesh& mesh = c.mesh;
  REQUIRE(mesh.joints.size() == mesh.positions.size());
  REQUIRE(mesh.weights.size() == mesh.positions.size());
  const int joint_count = static_cast<int>(c.joints.size());
  int bad = 0;
  std::set<int> skinned_joints;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    double sum = 0.0;
    std::set<int> seen;
    for (int k = 0; k < 4; ++k) {
      float w = mesh.weights[v][k];
      int j = mesh.joints[v][k];
      sum += w;
      if (w < 0.0f || j < 0 || j >= joint_count) ++bad;
      if (w == 0.0f) {
        if (j != 0) ++bad;
        continue;
      }
      if (!seen.insert(j).second) ++bad;
      if (k > 0 && w > mesh.weights[v][k - 1]) ++bad;  // largest first
      skinned_joints.insert(j);
    }
    if (std::abs(sum - 1.0) > 1e-6) ++bad;
  }
  CHECK(bad == 0);
  // The twist joints share the limb: both the upper arm and its roll bone carry skin.
  for (const char* name : {"JOLeftUpperArm1", "LeftUpperArm1Twist0", "JOLeftLowerArm1", "LeftLowerArm1Twist0",
                           "JORightUpperArm1", "RightUpperArm1Twist0", "JOLeftScapula1", "JOHead1"}) {
    INFO(name);
    CHECK(skinned_joints.count(c.findJoint(name)) == 1);
  }
}

TEST_CASE("joints and mesh are exact mirror images across x = 0") {
  const SampleCharacter& c = defaultSample();
  std::vector<int> mirror = sampleMirrorJoints(c);
  std::vector<Eigen::Affine3d> world = sampleBindWorld(c);
  for (size_t j = 0; j < c.joints.size(); ++j) {
    INFO(c.joints[j].name);
    Eigen::Vector3d p = world[j].translation(), q = world[mirror[j]].translation();
    CHECK(q.x() == -p.x());
    CHECK(q.y() == p.y());
    CHECK(q.z() == p.z());
  }
  const SampleMesh& mesh = c.mesh;
  std::map<std::array<double, 3>, size_t> by_position;
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    by_position.emplace(std::array<double, 3>{mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z()}, v);
  int unmatched = 0, weight_mismatch = 0;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    auto it = by_position.find({-mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z()});
    if (it == by_position.end()) {
      ++unmatched;
      continue;
    }
    std::map<int, float> mine, theirs;
    for (int k = 0; k < 4; ++k) {
      if (mesh.weights[v][k] > 0.0f) mine[mirror[mesh.joints[v][k]]] = mesh.weights[v][k];
      if (mesh.weights[it->second][k] > 0.0f) theirs[mesh.joints[it->second][k]] = mesh.weights[it->second][k];
    }
    if (mine != theirs) ++weight_mismatch;
  }
  CHECK(unmatched == 0);
  CHECK(weight_mismatch == 0);
}

TEST_CASE("three 2 s clips at 30 keys per second work the elbow, the shoulder and the forearm on both sides") {
  const SampleCharacter& c = defaultSample();
  REQUIRE(c.clips.size() >= 3);
  std::vector<int> mirror = sampleMirrorJoints(c);
  for (const SampleClip& clip : c.clips) {
    INFO(clip.name);
    for (const SampleTrack& track : clip.tracks) {
      REQUIRE(track.times.size() == 61);
      CHECK(track.times.front() == 0.0);
      CHECK(track.times.back() == Approx(2.0).margin(1e-12));
      REQUIRE(track.rotations.size() == track.times.size());
      // Both sides move, mirrored.
      const SampleTrack& twin = trackOf(clip, mirror[track.joint]);
      for (size_t k = 0; k < track.rotations.size(); ++k) {
        const Eigen::Quaterniond& q = track.rotations[k];
        const Eigen::Quaterniond& m = twin.rotations[k];
        CHECK(std::abs(q.norm() - 1.0) < 1e-12);
        CHECK(m.coeffs().isApprox(Eigen::Vector4d(q.x(), -q.y(), -q.z(), q.w()), 1e-12));
      }
    }
  }
  auto peak = [&](const SampleClip& clip, const std::string& joint) {
    double most = 0.0;
    for (const Eigen::Quaterniond& q : trackOf(clip, c.findJoint(joint)).rotations) most = std::max(most, angleDegrees(q));
    return most;
  };
  const SampleClip& elbow = clipNamed(c, "ElbowFlexion");
  CHECK(peak(elbow, "JOLeftLowerArm1") == Approx(130.0).margin(0.5));
  // Flexion brings the left forearm from +X towards the front.
  const SampleTrack& flex = trackOf(elbow, c.findJoint("JOLeftLowerArm1"));
  Eigen::Vector3d forearm = flex.rotations[30] * Eigen::Vector3d::UnitX();
  CHECK(forearm.z() > 0.7);

  const SampleClip& raise = clipNamed(c, "ArmRaise");
  const SampleTrack& clavicle = trackOf(raise, c.findJoint("JOLeftClavicle1"));
  const SampleTrack& upper_arm = trackOf(raise, c.findJoint("JOLeftUpperArm1"));
  double highest = 0.0, lowest = 180.0;
  for (size_t k = 0; k < upper_arm.rotations.size(); ++k) {
    Eigen::Vector3d arm = clavicle.rotations[k] * upper_arm.rotations[k] * Eigen::Vector3d::UnitX();
    double abduction = std::acos(std::clamp(-arm.y(), -1.0, 1.0)) * kDegreesPerRadian;
    highest = std::max(highest, abduction);
    lowest = std::min(lowest, abduction);
  }
  CHECK(highest == Approx(170.0).margin(0.5));
  CHECK(lowest == Approx(10.0).margin(0.5));
  CHECK(peak(raise, "JOLeftClavicle1") > 5.0);
  CHECK(peak(raise, "JOLeftClavicle1") < 25.0);

  const SampleClip& twist = clipNamed(c, "ForearmTwist");
  // Twist about the forearm's long axis, shared between the forearm and its roll bone.
  for (const char* joint : {"JOLeftLowerArm1", "LeftLowerArm1Twist0"}) {
    INFO(joint);
    CHECK(peak(twist, joint) > 30.0);
    for (const Eigen::Quaterniond& q : trackOf(twist, c.findJoint(joint)).rotations)
      CHECK(std::abs(q.y()) + std::abs(q.z()) < 1e-12);
  }
}

TEST_CASE("the sample is deterministic and the VRM variants only rename joints") {
  SampleCharacter a = makeSampleCharacter({});
  SampleCharacter b = makeSampleCharacter({});
  REQUIRE(a.mesh.positions.size() == b.mesh.positions.size());
  CHECK(a.mesh.positions == b.mesh.positions);
  CHECK(a.mesh.weights == b.mesh.weights);
  CHECK(a.mesh.triangles == b.mesh.triangles);

  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    SampleOptions options;
    options.vrm = vrm;
    SampleCharacter v = makeSampleCharacter(options);
    INFO((vrm == SampleVrm::kVrm0 ? "VRM 0.x" : "VRM 1.0"));
    REQUIRE(v.joints.size() == a.joints.size());
    for (size_t j = 0; j < v.joints.size(); ++j) {
      CHECK(v.joints[j].name.rfind("bone_", 0) == 0);
      CHECK(v.joints[j].parent == a.joints[j].parent);
    }
    CHECK(v.mesh.positions.size() == a.mesh.positions.size());
    std::map<std::string, int> bones(v.humanoid_bones.begin(), v.humanoid_bones.end());
    for (const char* required : {"hips", "spine", "chest", "neck", "head", "leftUpperArm", "leftLowerArm", "leftHand",
                                 "rightUpperArm", "rightLowerArm", "rightHand", "leftUpperLeg", "leftLowerLeg",
                                 "leftFoot", "rightUpperLeg", "rightLowerLeg", "rightFoot"})
      CHECK(bones.count(required) == 1);
    CHECK(a.joints[bones["leftUpperArm"]].name == "JOLeftUpperArm1");
    CHECK(a.joints[bones["rightShoulder"]].name == "JORightClavicle1");
    std::vector<Eigen::Affine3d> world = sampleBindWorld(v);
    Eigen::Vector3d left_arm = world[bones["leftUpperArm"]].translation();
    if (vrm == SampleVrm::kVrm0) {
      // VRM 0.x faces -Z with unrotated bones: the same body turned about Y, its left at -X.
      CHECK(left_arm.x() < -0.1);
      for (const Eigen::Affine3d& w : world) CHECK(w.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
      CHECK(world[bones["leftToes"]].translation().z() < world[bones["leftFoot"]].translation().z());
    } else {
      CHECK(left_arm.x() > 0.1);
    }
    for (const char* spine : {"hips", "spine", "chest", "upperChest", "neck", "head"})
      CHECK(world[bones[spine]].translation().x() == 0.0);
  }
}

TEST_CASE("without upperChest the VRM variants leave only that bone out of the humanoid map") {
  for (SampleVrm vrm : {SampleVrm::kVrm0, SampleVrm::kVrm1}) {
    INFO((vrm == SampleVrm::kVrm0 ? "VRM 0.x" : "VRM 1.0"));
    SampleOptions options;
    options.vrm = vrm;
    const SampleCharacter full = makeSampleCharacter(options);
    options.upper_chest = false;
    const SampleCharacter without = makeSampleCharacter(options);
    std::vector<std::pair<std::string, int>> expected;
    for (const auto& bone : full.humanoid_bones) {
      if (bone.first != "upperChest") expected.push_back(bone);
    }
    CHECK(expected.size() + 1 == full.humanoid_bones.size());
    CHECK(without.humanoid_bones == expected);
    // The skeleton keeps the joint, unmapped; the body and its clips do not change.
    REQUIRE(without.joints.size() == full.joints.size());
    for (size_t j = 0; j < full.joints.size(); ++j) {
      CHECK(without.joints[j].name == full.joints[j].name);
      CHECK(without.joints[j].parent == full.joints[j].parent);
    }
    CHECK(without.mesh.positions == full.mesh.positions);
    CHECK(without.mesh.weights == full.mesh.weights);
    // Loaded back, the file's humanoid map has no upperChest.
    ext::ScratchDir dir;
    const std::string path = dir.file("no-upper-chest.vrm");
    writeGltf(sampleToGltf(without), path);
    Character c = loadCharacter(path).character;
    CHECK(c.vrm_humanoid.count("upperChest") == 0);
    CHECK(c.vrm_humanoid.count("chest") == 1);
    CHECK(c.vrm_humanoid.size() == expected.size());
  }
  // The plain variant writes no humanoid map, so the option leaves its bytes as they are.
  SampleOptions plain;
  plain.upper_chest = false;
  CHECK(serializeGltf(sampleToGltf(makeSampleCharacter(plain)), true) ==
        serializeGltf(sampleToGltf(defaultSample()), true));
}

TEST_CASE("the written sample GLB and both VRM variants load back with the same rig") {
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  struct Variant {
    SampleVrm vrm;
    const char* file;
    const char* version;
  };
  for (const Variant& variant : {Variant{SampleVrm::kNone, "sample.glb", ""}, Variant{SampleVrm::kNone, "sample.gltf", ""},
                                 Variant{SampleVrm::kVrm0, "sample0.vrm", "0.x"},
                                 Variant{SampleVrm::kVrm1, "sample1.vrm", "1.0"}}) {
    INFO(variant.file);
    SampleOptions options;
    options.vrm = variant.vrm;
    SampleCharacter sample = makeSampleCharacter(options);
    std::string path = dir.file(variant.file);
    writeGltf(sampleToGltf(sample), path);
    Character c = loadCharacter(path).character;
    REQUIRE(c.skeleton.size() == static_cast<int>(sample.joints.size()));
    std::vector<Eigen::Affine3d> world = sampleBindWorld(sample);
    for (int j = 0; j < c.skeleton.size(); ++j) {
      CHECK(c.skeleton.names[j] == sample.joints[j].name);
      CHECK(c.skeleton.parents[j] == sample.joints[j].parent);
      CHECK((c.skeleton.bindPosition(j) - world[j].translation()).norm() < 1e-6);
    }
    REQUIRE(c.meshes.size() == 1);
    const MeshPart& part = c.meshes[0];
    CHECK(part.skinned);
    CHECK(part.positions.size() == sample.mesh.positions.size());
    CHECK(part.triangles.size() == sample.mesh.triangles.size());
    CHECK(part.influences_per_vertex == 4);
    double min_y = 1e9, max_y = -1e9;
    for (const auto& p : part.positions) {
      min_y = std::min(min_y, p.y());
      max_y = std::max(max_y, p.y());
    }
    CHECK(min_y == 0.0);
    CHECK(max_y == Approx(kSampleHeight).margin(1e-6));
    std::set<std::string> clips;
    for (const Clip& clip : c.clips) {
      clips.insert(clip.name);
      CHECK(clip.duration == Approx(2.0).margin(1e-6));
      for (const Track& track : clip.tracks) CHECK(track.interpolation == Interpolation::kLinear);
    }
    CHECK(clips == std::set<std::string>{"ElbowFlexion", "ArmRaise", "ForearmTwist"});
    CHECK(c.vrm_version == variant.version);
    if (variant.vrm == SampleVrm::kNone) {
      CHECK(c.vrm_humanoid.empty());
      // The spine survives float storage exactly on the sagittal line.
      for (const char* name : {"JOPelvis1", "JOBack1", "JOBack2", "JOBack3", "JONeck1", "JOHead1"}) {
        int j = c.skeleton.find(name);
        REQUIRE(j >= 0);
        CHECK(c.skeleton.bindPosition(j).x() == 0.0);
        CHECK(c.skeleton.bindPosition(j).z() == c.skeleton.bindPosition(0).z());
      }
    } else {
      // Only the extension says which joint is which: no joint keeps its JO name.
      for (const std::string& name : c.skeleton.names) CHECK(name.find("JO") == std::string::npos);
      CHECK(c.vrm_humanoid.size() == sample.humanoid_bones.size());
      for (const auto& [bone, joint] : sample.humanoid_bones) {
        INFO(bone);
        REQUIRE(c.vrm_humanoid.count(bone) == 1);
        CHECK(c.vrm_humanoid.at(bone) == joint);
      }
    }
  }
}

TEST_CASE("Blender imports the sample GLB with an armature of the talk's joints and a skinned mesh") {
  if (!ext::requireTool(ext::onPath("blender"), "blender (Debian package blender)")) return;
  ext::ScratchDir dir;
  REQUIRE(!dir.path().empty());
  const SampleCharacter& sample = defaultSample();
  std::string glb = dir.file("sample.glb");
  writeGltf(sampleToGltf(sample), glb);
  std::string script = dir.file("inspect.py");
  std::ofstream(script) << R"PY(import sys, json
import numpy
# Debian's Blender 3.4 glTF importer still uses numpy.bool and friends, which numpy 1.24 removed.
for name, alias in (("bool", bool), ("int", int), ("float", float), ("object", object)):
    if name not in numpy.__dict__:
        setattr(numpy, name, alias)
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=sys.argv[sys.argv.index("--") + 1])
armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
report = {
    "armatures": [{"name": a.name, "bones": {b.name: list(a.matrix_world @ b.head_local) for b in a.data.bones}}
                  for a in armatures],
    "meshes": [{"name": m.name, "vertices": len(m.data.vertices), "groups": [g.name for g in m.vertex_groups],
                "parent": m.parent.name if m.parent else ""} for m in meshes],
    "actions": sorted(a.name for a in bpy.data.actions),
}
print("RIGBAKE_BLENDER " + json.dumps(report))
)PY";
  ext::CommandResult run = ext::runCommand("blender --background --factory-startup --python-exit-code 1 --python " +
                                             ext::shellQuote(script) + " -- " + ext::shellQuote(glb) + " 2>&1");
  INFO(run.output);
  REQUIRE(run.exit_code == 0);
  size_t at = run.output.find("RIGBAKE_BLENDER ");
  REQUIRE(at != std::string::npos);
  std::string line = run.output.substr(at + 16, run.output.find('\n', at) - at - 16);
  nlohmann::json report = nlohmann::json::parse(line);
  REQUIRE(report["armatures"].size() == 1);
  const nlohmann::json& bones = report["armatures"][0]["bones"];
  for (const std::string& name : expectedJointNames()) CHECK(bones.contains(name));
  // Blender is Z-up: glTF (x, y, z) lands at (x, -z, y); the left arm stays at +X.
  std::vector<double> shoulder = bones["JOLeftUpperArm1"].get<std::vector<double>>();
  Eigen::Vector3d expected = jointWorld(sample, "JOLeftUpperArm1");
  CHECK(shoulder[0] == Approx(expected.x()).margin(1e-4));
  CHECK(shoulder[1] == Approx(-expected.z()).margin(1e-4));
  CHECK(shoulder[2] == Approx(expected.y()).margin(1e-4));
  REQUIRE(report["meshes"].size() == 1);
  const nlohmann::json& body = report["meshes"][0];
  CHECK(body["vertices"].get<size_t>() == sample.mesh.positions.size());
  CHECK(body["groups"].size() == sample.joints.size());
  CHECK(body["parent"] == report["armatures"][0]["name"]);
  std::string actions = report["actions"].dump();
  for (const char* clip : {"ElbowFlexion", "ArmRaise", "ForearmTwist"}) CHECK(actions.find(clip) != std::string::npos);
}
