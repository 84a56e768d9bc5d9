// The procedural mannequin (sample/sample_character.h): the joint table of sample/canonical_skeleton.h
// in the file convention asked for, the body of sample/sample_mesh.h, clips that work the shoulder and
// elbow muscles, and the VRM humanoid bone map.
//
// The neck joint is turned 180 degrees about Y so that its local +Z points to the back: the God of
// War Ragnarök talk's trapezius rule offsets the origin by neckJointWorldMatrix[8:11] * 0.02, i.e.
// along the neck joint's Z axis, towards the spinous processes.

#include "sample/sample_character.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>

#include "core/error.h"
#include "sample/canonical_skeleton.h"
#include "sample/sample_mesh.h"

namespace rigbake {

namespace sample_internal {
namespace {

constexpr double kDegree = kPi / 180.0;

// Clips: 2 s at 30 keys per second.
constexpr double kClipSeconds = 2.0;
constexpr int kKeysPerSecond = 30;

// ---------------------------------------------------------------------------------------------------
// Clips. Every animated joint has an identity bind rotation under an identity-rotated parent, so a
// local rotation about a world axis is the motion itself.

std::vector<double> clipTimes() {
  std::vector<double> times;
  const int keys = static_cast<int>(kClipSeconds * kKeysPerSecond) + 1;
  for (int i = 0; i < keys; ++i) times.push_back(static_cast<double>(i) / kKeysPerSecond);
  return times;
}

// 0 at the start and end of the clip, 1 in the middle, eased.
double riseAndFall(double time) { return 0.5 * (1.0 - std::cos(2.0 * kPi * time / kClipSeconds)); }

Eigen::Quaterniond rotation(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kDegree, axis));
}

// Reflection across x = 0 applied to a rotation: keeps the x part of the axis, negates y and z.
Eigen::Quaterniond mirrorRotation(const Eigen::Quaterniond& q) { return Eigen::Quaterniond(q.w(), q.x(), -q.y(), -q.z()); }

SampleTrack leftTrack(const CanonicalSkeleton& skeleton, const std::string& joint,
                      const std::function<Eigen::Quaterniond(double)>& pose) {
  SampleTrack track;
  track.joint = skeleton.at(joint);
  track.times = clipTimes();
  for (double time : track.times) track.rotations.push_back(pose(time));
  return track;
}

// Adds the right-side twin of every track, mirrored.
SampleClip bothSides(const CanonicalSkeleton& skeleton, const std::string& name, std::vector<SampleTrack> left) {
  SampleClip clip;
  clip.name = name;
  for (const SampleTrack& track : left) {
    clip.tracks.push_back(track);
    SampleTrack twin = track;
    twin.joint = skeleton.mirror[track.joint];
    for (Eigen::Quaterniond& q : twin.rotations) q = mirrorRotation(q);
    clip.tracks.push_back(twin);
  }
  return clip;
}

std::vector<SampleClip> buildClips(const CanonicalSkeleton& skeleton) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  std::vector<SampleClip> clips;
  // Elbow flexion to 130 degrees and back. In the T-pose the elbow's hinge axis is vertical and
  // flexion swings the left forearm from +X towards the front (+Z): a rotation about -Y.
  clips.push_back(bothSides(skeleton, "ElbowFlexion",
                            {leftTrack(skeleton, "JOLeftLowerArm1",
                                       [&](double t) { return rotation(130.0 * riseAndFall(t), -y); })}));
  // Shoulder abduction from 10 degrees (arm down) to 170 degrees (overhead) and back; the clavicle
  // elevates up to 15 degrees past 30 degrees of abduction (scapulohumeral rhythm), lifting the
  // acromion and scapula joints with it. The upper arm's local rotation subtracts the clavicle's so
  // that the arm's world abduction is exactly the target.
  auto abduction = [](double t) { return 10.0 + 160.0 * riseAndFall(t); };
  auto elevation = [&](double t) { return 15.0 * std::clamp((abduction(t) - 30.0) / 140.0, 0.0, 1.0); };
  clips.push_back(bothSides(
      skeleton, "ArmRaise",
      {leftTrack(skeleton, "JOLeftClavicle1", [&](double t) { return rotation(elevation(t), z); }),
       leftTrack(skeleton, "JOLeftUpperArm1",
                 [&](double t) { return rotation(abduction(t) - 90.0 - elevation(t), z); })}));
  // Pronation/supination of +-80 degrees about the forearm's long axis, shared by the forearm, its
  // roll bone and the hand: half at the elbow, the full amount at the roll bone and the wrist.
  auto twist = [](double t) { return 80.0 * std::sin(2.0 * kPi * t / kClipSeconds); };
  clips.push_back(bothSides(
      skeleton, "ForearmTwist",
      {leftTrack(skeleton, "JOLeftLowerArm1", [&](double t) { return rotation(0.5 * twist(t), x); }),
       leftTrack(skeleton, "LeftLowerArm1Twist0", [&](double t) { return rotation(0.5 * twist(t), x); }),
       leftTrack(skeleton, "JOLeftHand1", [&](double t) { return rotation(0.5 * twist(t), x); })}));
  return clips;
}

// VRM humanoid bones and the joints they map to.
const std::vector<std::pair<const char*, const char*>>& humanoidMapping() {
  static const std::vector<std::pair<const char*, const char*>> kMapping = {
      {"hips", "JOPelvis1"},
      {"spine", "JOBack1"},
      {"chest", "JOBack2"},
      {"upperChest", "JOBack3"},
      {"neck", "JONeck1"},
      {"head", "JOHead1"},
      {"leftShoulder", "JOLeftClavicle1"},
      {"leftUpperArm", "JOLeftUpperArm1"},
      {"leftLowerArm", "JOLeftLowerArm1"},
      {"leftHand", "JOLeftHand1"},
      {"rightShoulder", "JORightClavicle1"},
      {"rightUpperArm", "JORightUpperArm1"},
      {"rightLowerArm", "JORightLowerArm1"},
      {"rightHand", "JORightHand1"},
      {"leftUpperLeg", "JOLeftUpLeg1"},
      {"leftLowerLeg", "JOLeftLeg1"},
      {"leftFoot", "JOLeftFoot1"},
      {"leftToes", "JOLeftToe1"},
      {"rightUpperLeg", "JORightUpLeg1"},
      {"rightLowerLeg", "JORightLeg1"},
      {"rightFoot", "JORightFoot1"},
      {"rightToes", "JORightToe1"},
  };
  return kMapping;
}

}  // namespace
}  // namespace sample_internal

int SampleCharacter::findJoint(const std::string& joint_name) const {
  for (size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == joint_name) return static_cast<int>(i);
  }
  return -1;
}

SampleCharacter makeSampleCharacter(const SampleOptions& options) {
  if (options.target_vertices < kMinSampleVertices || options.target_vertices > kMaxSampleVertices)
    fail(errc::USAGE, "", "the sample's vertex count must be between " + std::to_string(kMinSampleVertices) + " and " +
                          std::to_string(kMaxSampleVertices) + ", got " + std::to_string(options.target_vertices));
  const sample_internal::CanonicalSkeleton skeleton = sample_internal::buildCanonicalSkeleton();
  const int joint_count = static_cast<int>(skeleton.names.size());

  SampleCharacter character;
  character.name = "rigbake_mannequin";
  character.vrm = options.vrm;
  character.mesh = sample_internal::buildSampleMesh(skeleton, options.target_vertices);
  character.clips = sample_internal::buildClips(skeleton);
  for (const auto& [bone, joint] : sample_internal::humanoidMapping()) {
    if (!options.upper_chest && std::string(bone) == "upperChest") continue;
    character.humanoid_bones.emplace_back(bone, skeleton.at(joint));
  }

  // Bind pose: world rotations are identity except the neck's (its +Z to the back). The VRM 0.x
  // variant turns the whole body 180 degrees about Y, which makes every world rotation identity,
  // the neck's included, as VRM 0.x asks.
  const Eigen::Quaterniond half_turn(0.0, 0.0, 1.0, 0.0);  // 180 degrees about Y, exact
  const bool turned = options.vrm == SampleVrm::kVrm0;
  const int neck = skeleton.at("JONeck1");
  auto turn = [](const Eigen::Vector3d& p) { return Eigen::Vector3d(-p.x(), p.y(), -p.z()); };
  std::vector<Eigen::Vector3d> world(joint_count);
  std::vector<Eigen::Quaterniond> world_rotation(joint_count, Eigen::Quaterniond::Identity());
  for (int j = 0; j < joint_count; ++j) {
    world[j] = turned ? turn(skeleton.world[j]) : skeleton.world[j];
    if (!turned && j == neck) world_rotation[j] = half_turn;
  }
  // glTF stores node translations as JSON numbers but inverse bind matrices as floats. Rounding the
  // local translations to float keeps the root's node transform and its inverse bind matrix exact
  // inverses, so a loader that maps bind space to the scene through them (world(root) * IBM(root))
  // gets exactly the identity and the feet stay exactly on y = 0. Rounding is symmetric in sign, so
  // the mirror symmetry survives it.
  // Through a volatile float: GCC 12's vectorizer at -O2 folds the double -> float -> double round
  // trip of a vector's components back into the original doubles.
  auto toFloatPrecision = [](const Eigen::Vector3d& v) {
    auto round = [](double x) {
      volatile float narrowed = static_cast<float>(x);
      return static_cast<double>(narrowed);
    };
    return Eigen::Vector3d(round(v.x()), round(v.y()), round(v.z()));
  };
  for (int j = 0; j < joint_count; ++j) {
    SampleJoint joint;
    joint.name = skeleton.names[j];
    if (options.vrm != SampleVrm::kNone) {
      joint.name = std::string(j < 10 ? "bone_0" : "bone_") + std::to_string(j);
    }
    joint.parent = skeleton.parents[j];
    if (joint.parent < 0) {
      joint.local.translation = toFloatPrecision(world[j]);
      joint.local.rotation = world_rotation[j];
    } else {
      Eigen::Quaterniond parent_inverse = world_rotation[joint.parent].conjugate();
      joint.local.translation = toFloatPrecision(parent_inverse * (world[j] - world[joint.parent]));
      joint.local.rotation = parent_inverse * world_rotation[j];
    }
    character.joints.push_back(joint);
  }
  if (turned) {
    for (Eigen::Vector3d& p : character.mesh.positions) p = turn(p);
    for (Eigen::Vector3d& n : character.mesh.normals) n = turn(n);
    // A local rotation R about world axes becomes T R T^-1 in the turned body (T = half turn about
    // Y): the axis' x and z change sign.
    for (SampleClip& clip : character.clips) {
      for (SampleTrack& track : clip.tracks) {
        for (Eigen::Quaterniond& q : track.rotations) q = Eigen::Quaterniond(q.w(), -q.x(), q.y(), -q.z());
      }
    }
  }
  return character;
}

std::vector<Eigen::Affine3d> sampleBindWorld(const SampleCharacter& character) {
  std::vector<Eigen::Affine3d> world(character.joints.size());
  for (size_t j = 0; j < character.joints.size(); ++j) {
    const SampleJoint& joint = character.joints[j];
    world[j] = joint.parent < 0 ? joint.local.matrix() : world[joint.parent] * joint.local.matrix();
  }
  return world;
}

std::vector<int> sampleMirrorJoints(const SampleCharacter& character) {
  std::vector<int> mirror = sample_internal::buildCanonicalSkeleton().mirror;
  assert(mirror.size() == character.joints.size());
  (void)character;
  return mirror;
}

}  // namespace rigbake
