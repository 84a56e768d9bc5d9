#include "pipeline/pose.h"

#include <cmath>
#include <map>
#include <utility>

#include "formats/gltf_document.h"
#include "test_support.h"
#include "math_fixture.h"

using namespace rigbake;

namespace {

using test::kPi;
using test::maxDifference;

Track makeTrack(AnimatedPath path, Interpolation interpolation, std::vector<double> times, std::vector<double> values) {
  Track track;
  track.joint = 0;
  track.path = path;
  track.interpolation = interpolation;
  track.times = std::move(times);
  track.values = std::move(values);
  return track;
}

// x y z w of a rotation by `degrees` about +Z.
std::vector<double> zRotation(double degrees) {
  const double half = degrees * kPi / 360.0;
  return {0.0, 0.0, std::sin(half), std::cos(half)};
}

void checkQuaternion(const Eigen::Quaterniond& q, const std::vector<double>& xyzw, double margin) {
  CHECK(q.x() == Approx(xyzw[0]).margin(margin));
  CHECK(q.y() == Approx(xyzw[1]).margin(margin));
  CHECK(q.z() == Approx(xyzw[2]).margin(margin));
  CHECK(q.w() == Approx(xyzw[3]).margin(margin));
}

// A two-joint chain under a non-joint node that is rotated and moved, bind pose = rest pose.
Skeleton twoJointChain() {
  Skeleton skeleton;
  skeleton.names = {"upper", "lower"};
  skeleton.parents = {-1, 0};
  skeleton.nodes = {1, 2};
  Trs upper;
  upper.translation = {0.0, 1.0, 0.0};
  Trs lower;
  lower.translation = {0.5, 0.0, 0.0};
  skeleton.rest_local = {upper, lower};
  Eigen::Affine3d above = Eigen::Affine3d::Identity();
  above.translate(Eigen::Vector3d(2.0, 0.0, 0.0));
  above.rotate(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()));
  skeleton.root_parent_world = {above, Eigen::Affine3d::Identity()};
  skeleton.bind_world = {above * upper.matrix(), above * upper.matrix() * lower.matrix()};
  return skeleton;
}

// Linear blend skinning of every skinned or rigid vertex, with skin matrices computed once per pose.
std::vector<Eigen::Vector3d> skinCharacter(const Character& character, const Pose& pose) {
  std::vector<Eigen::Affine3d> skin(character.skeleton.size());
  for (int j = 0; j < character.skeleton.size(); ++j) skin[j] = skinMatrix(pose, character.skeleton, j);
  std::vector<Eigen::Vector3d> out;
  for (const MeshPart& part : character.meshes) {
    const int slots = part.influences_per_vertex;
    for (size_t v = 0; v < part.positions.size(); ++v) {
      if (part.skinned) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double weight_sum = 0.0;
        for (int k = 0; k < slots; ++k) {
          const double weight = part.weights[v * slots + k];
          if (weight == 0.0) continue;
          sum += weight * (skin[part.joints[v * slots + k]] * part.positions[v]);
          weight_sum += weight;
        }
        if (weight_sum > 0.0) out.push_back(sum / weight_sum);
      } else if (part.rigid_joint >= 0) {
        out.push_back(skin[part.rigid_joint] * part.positions[v]);
      }
    }
  }
  return out;
}

double extent(const std::vector<Eigen::Vector3d>& points, int axis) {
  double low = 1e300, high = -1e300;
  for (const Eigen::Vector3d& p : points) {
    low = std::min(low, p[axis]);
    high = std::max(high, p[axis]);
  }
  return high - low;
}

double farthest(const std::vector<Eigen::Vector3d>& points) {
  double radius = 0.0;
  for (const Eigen::Vector3d& p : points) radius = std::max(radius, p.norm());
  return radius;
}

const std::vector<std::string> kAnimatedAssets = {"CesiumMan.glb", "RobotExpressive.glb",
                                                  "Quaternius_Cyberpunk_Character.glb"};

}  // namespace

TEST_CASE("LINEAR translation lerps between keys and clamps outside them", "[pose]") {
  Track track = makeTrack(AnimatedPath::kTranslation, Interpolation::kLinear, {1.0, 3.0}, {0, 0, 0, 2, 4, 6});
  CHECK(sampleVectorTrack(track, 2.0) == Eigen::Vector3d(1, 2, 3));
  CHECK(sampleVectorTrack(track, 1.5) == Eigen::Vector3d(0.5, 1, 1.5));
  CHECK(sampleVectorTrack(track, 1.0) == Eigen::Vector3d(0, 0, 0));
  CHECK(sampleVectorTrack(track, 0.0) == Eigen::Vector3d(0, 0, 0));
  CHECK(sampleVectorTrack(track, -7.0) == Eigen::Vector3d(0, 0, 0));
  CHECK(sampleVectorTrack(track, 3.0) == Eigen::Vector3d(2, 4, 6));
  CHECK(sampleVectorTrack(track, 9.0) == Eigen::Vector3d(2, 4, 6));
}

TEST_CASE("LINEAR with keys sharing a time jumps at that time", "[pose]") {
  Track track = makeTrack(AnimatedPath::kScale, Interpolation::kLinear, {0.0, 1.0, 1.0, 2.0},
                          {1, 1, 1, 2, 2, 2, 5, 5, 5, 7, 7, 7});
  CHECK(sampleVectorTrack(track, 0.5) == Eigen::Vector3d(1.5, 1.5, 1.5));
  CHECK(sampleVectorTrack(track, 1.0) == Eigen::Vector3d(5, 5, 5));
  CHECK(sampleVectorTrack(track, 1.5) == Eigen::Vector3d(6, 6, 6));
}

TEST_CASE("LINEAR rotation slerps along the shortest path", "[pose]") {
  const std::vector<double> half_way = zRotation(45.0);
  SECTION("plain keys") {
    std::vector<double> values = zRotation(0.0);
    for (double v : zRotation(90.0)) values.push_back(v);
    Track track = makeTrack(AnimatedPath::kRotation, Interpolation::kLinear, {0.0, 1.0}, values);
    checkQuaternion(sampleRotationTrack(track, 0.5), half_way, 1e-15);
    checkQuaternion(sampleRotationTrack(track, 0.25), zRotation(22.5), 1e-15);
    checkQuaternion(sampleRotationTrack(track, -1.0), zRotation(0.0), 0.0);
    checkQuaternion(sampleRotationTrack(track, 2.0), zRotation(90.0), 0.0);
  }
  SECTION("the second key stored with the opposite sign") {
    std::vector<double> values = zRotation(0.0);
    for (double v : zRotation(90.0)) values.push_back(-v);
    Track track = makeTrack(AnimatedPath::kRotation, Interpolation::kLinear, {0.0, 1.0}, values);
    checkQuaternion(sampleRotationTrack(track, 0.5), half_way, 1e-15);
  }
  SECTION("a 270 degree key is reached the short way round, through -45 degrees") {
    std::vector<double> values = zRotation(0.0);
    for (double v : zRotation(270.0)) values.push_back(v);
    Track track = makeTrack(AnimatedPath::kRotation, Interpolation::kLinear, {0.0, 1.0}, values);
    checkQuaternion(sampleRotationTrack(track, 0.5), zRotation(-45.0), 1e-15);
  }
  SECTION("identical keys") {
    std::vector<double> values = zRotation(30.0);
    for (double v : zRotation(30.0)) values.push_back(v);
    Track track = makeTrack(AnimatedPath::kRotation, Interpolation::kLinear, {0.0, 1.0}, values);
    checkQuaternion(sampleRotationTrack(track, 0.3), zRotation(30.0), 1e-15);
  }
}

TEST_CASE("STEP holds the key at or before the time", "[pose]") {
  Track track = makeTrack(AnimatedPath::kTranslation, Interpolation::kStep, {0.0, 1.0, 2.0},
                          {10, 0, 0, 20, 0, 0, 30, 0, 0});
  CHECK(sampleVectorTrack(track, -1.0).x() == 10);
  CHECK(sampleVectorTrack(track, 0.99).x() == 10);
  CHECK(sampleVectorTrack(track, 1.0).x() == 20);
  CHECK(sampleVectorTrack(track, 1.5).x() == 20);
  CHECK(sampleVectorTrack(track, 2.0).x() == 30);
  CHECK(sampleVectorTrack(track, 2.5).x() == 30);
  std::vector<double> rotations = zRotation(10.0);
  for (double v : zRotation(80.0)) rotations.push_back(v);
  Track rotation = makeTrack(AnimatedPath::kRotation, Interpolation::kStep, {0.0, 1.0}, rotations);
  checkQuaternion(sampleRotationTrack(rotation, 0.9), zRotation(10.0), 0.0);
  checkQuaternion(sampleRotationTrack(rotation, 1.0), zRotation(80.0), 0.0);
}

TEST_CASE("CUBICSPLINE is the glTF Hermite spline with tangents scaled by the key interval", "[pose]") {
  // Keys at t = 0 and 2 (interval 2). Per key: in-tangent, value, out-tangent. Key 0's in-tangent and
  // key 1's out-tangent are never used: they hold 100 so that reading them would show.
  Track track = makeTrack(AnimatedPath::kTranslation, Interpolation::kCubicSpline, {0.0, 2.0},
                          {100, 100, 100, /*v0*/ 0, 1, 2, /*b0*/ 1, 0, -1,
                           /*a1*/ 0, 3, 0, /*v1*/ 1, 1, 1, 100, 100, 100});
  // At u = 1/2: h00 = 1/2, h10 = 1/8, h01 = 1/2, h11 = -1/8, and the tangent terms carry t_d = 2:
  // p = v0/2 + 2 b0/8 + v1/2 - 2 a1/8.
  const Eigen::Vector3d middle = sampleVectorTrack(track, 1.0);
  CHECK(middle.x() == Approx(0.75).epsilon(1e-15));  // 0.625 if the tangents were not scaled
  CHECK(middle.y() == Approx(0.25).epsilon(1e-15));
  CHECK(middle.z() == Approx(1.25).epsilon(1e-15));
  // u = 1/4: h00 = 27/32, h10 = 9/64, h01 = 5/32, h11 = -3/64.
  const Eigen::Vector3d quarter = sampleVectorTrack(track, 0.5);
  CHECK(quarter.x() == Approx(2 * 9.0 / 64 + 5.0 / 32).epsilon(1e-15));
  CHECK(sampleVectorTrack(track, 0.0) == Eigen::Vector3d(0, 1, 2));
  CHECK(sampleVectorTrack(track, -3.0) == Eigen::Vector3d(0, 1, 2));
  CHECK(sampleVectorTrack(track, 2.0) == Eigen::Vector3d(1, 1, 1));
  CHECK(sampleVectorTrack(track, 5.0) == Eigen::Vector3d(1, 1, 1));
}

TEST_CASE("CUBICSPLINE rotation is normalized", "[pose]") {
  std::vector<double> values = {0, 0, 0, 0};
  for (double v : zRotation(0.0)) values.push_back(v);
  for (double v : {0, 0, 0, 0, 0, 0, 0, 0}) values.push_back(v);
  for (double v : zRotation(90.0)) values.push_back(v);
  for (double v : {0, 0, 0, 0}) values.push_back(v);
  Track track = makeTrack(AnimatedPath::kRotation, Interpolation::kCubicSpline, {0.0, 1.0}, values);
  // With zero tangents the midpoint is (q0 + q1) / 2, of norm cos(22.5 deg) before normalization;
  // normalized it is the 45 degree rotation.
  const Eigen::Quaterniond middle = sampleRotationTrack(track, 0.5);
  CHECK(middle.norm() == Approx(1.0).epsilon(1e-15));
  checkQuaternion(middle, zRotation(45.0), 1e-15);
  checkQuaternion(sampleRotationTrack(track, 7.0), zRotation(90.0), 0.0);
}

TEST_CASE("poses compose root_parent_world and the local chain", "[pose]") {
  const Skeleton skeleton = twoJointChain();
  const Pose rest = restPose(skeleton);
  REQUIRE(rest.world.size() == 2);
  // The root node turns +X into -Z, so the lower joint sits 0.5 m along -Z of the upper one.
  CHECK((rest.world[0].translation() - Eigen::Vector3d(2, 1, 0)).norm() < 1e-15);
  CHECK((rest.world[1].translation() - Eigen::Vector3d(2, 1, -0.5)).norm() < 1e-15);

  const Pose bind = bindPose(skeleton);
  for (int j = 0; j < 2; ++j) CHECK(bind.world[j].matrix() == skeleton.bind_world[j].matrix());
  const Pose recomposed = composePose(skeleton, bind.local);
  for (int j = 0; j < 2; ++j) CHECK(maxDifference(recomposed.world[j], skeleton.bind_world[j]) < 1e-15);

  Clip clip;
  clip.duration = 1.0;
  std::vector<double> rotations = zRotation(0.0);
  for (double v : zRotation(90.0)) rotations.push_back(v);
  clip.tracks.push_back(makeTrack(AnimatedPath::kRotation, Interpolation::kLinear, {0.0, 1.0}, rotations));
  const Pose posed = sampleClip(skeleton, clip, 1.0);
  // Rotating the upper joint 90 degrees about its local Z swings the lower joint from local +X to +Y.
  CHECK((posed.world[1].translation() - Eigen::Vector3d(2, 1.5, 0)).norm() < 1e-15);
  CHECK(posed.local[1].translation == skeleton.rest_local[1].translation);
  CHECK(posed.local[0].translation == skeleton.rest_local[0].translation);
  // The skin matrix carries the lower joint's bind position to its posed position.
  CHECK((skinMatrix(posed, skeleton, 0) * skeleton.bindPosition(1) - posed.world[1].translation()).norm() < 1e-15);
}

TEST_CASE("decomposeTrs splits T, R, S exactly, a mirror into a negative scale", "[pose]") {
  Trs trs;
  trs.translation = {1, -2, 3};
  trs.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  trs.scale = {0.5, 2.0, 3.0};
  const Trs split = decomposeTrs(trs.matrix());
  CHECK((split.translation - trs.translation).norm() < 1e-15);
  CHECK((split.scale - trs.scale).norm() < 1e-14);
  CHECK(split.rotation.angularDistance(trs.rotation) < 1e-14);
  Eigen::Affine3d mirrored = trs.matrix() * Eigen::Scaling(-1.0, 1.0, 1.0);
  const Trs mirror = decomposeTrs(mirrored);
  CHECK(mirror.scale.x() == Approx(-0.5).epsilon(1e-14));
  CHECK(maxDifference(mirror.matrix(), mirrored) < 1e-14);
}

TEST_CASE("sampleTimes: key times merged within the tolerance, or uniform to the duration", "[pose]") {
  Clip clip;
  clip.duration = 2.0;
  clip.tracks.push_back(makeTrack(AnimatedPath::kTranslation, Interpolation::kLinear, {0.0, 0.5, 1.0},
                                  std::vector<double>(9, 0.0)));
  clip.tracks.push_back(makeTrack(AnimatedPath::kScale, Interpolation::kLinear, {0.5 + 1e-9, 2.0},
                                  std::vector<double>(6, 0.0)));
  CHECK(sampleTimes(clip, 0.0) == std::vector<double>{0.0, 0.5, 1.0, 2.0});
  CHECK(sampleTimes(clip, -1.0) == std::vector<double>{0.0, 0.5, 1.0, 2.0});
  CHECK(sampleTimes(clip, 2.0) == std::vector<double>{0.0, 0.5, 1.0, 1.5, 2.0});
  clip.duration = 1.1;
  CHECK(sampleTimes(clip, 4.0) == std::vector<double>{0.0, 0.25, 0.5, 0.75, 1.0, 1.1});
  clip.duration = 0.0;
  CHECK(sampleTimes(clip, 30.0) == std::vector<double>{0.0});
  // 30 fps over one second: 31 samples, the last one the duration itself, no drift.
  clip.duration = 1.0;
  const std::vector<double> times = sampleTimes(clip, 30.0);
  REQUIRE(times.size() == 31);
  CHECK(times[29] == 29.0 / 30.0);
  CHECK(times.back() == 1.0);
}

TEST_CASE("real clips sampled at t = 0 give their first key exactly", "[pose]") {
  for (const std::string& name : kAnimatedAssets) {
    const std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    const Character character = loadCharacter(path).character;
    REQUIRE(!character.clips.empty());
    for (const Clip& clip : character.clips) {
      INFO(name << " clip " << clip.name);
      const Pose pose = sampleClip(character.skeleton, clip, 0.0);
      // The last track on a joint and path is the one that shows.
      std::map<std::pair<int, int>, const Track*> shown;
      for (const Track& track : clip.tracks) shown[{track.joint, static_cast<int>(track.path)}] = &track;
      for (const auto& entry : shown) {
        const Track& track = *entry.second;
        REQUIRE(!track.times.empty());
        const size_t first = track.interpolation == Interpolation::kCubicSpline ? 1 : 0;
        const Trs& local = pose.local[track.joint];
        if (track.path == AnimatedPath::kRotation) {
          const double* key = &track.values[first * 4];
          CHECK(local.rotation.x() == key[0]);
          CHECK(local.rotation.y() == key[1]);
          CHECK(local.rotation.z() == key[2]);
          CHECK(local.rotation.w() == key[3]);
        } else {
          const double* key = &track.values[first * 3];
          const Eigen::Vector3d& value =
              track.path == AnimatedPath::kTranslation ? local.translation : local.scale;
          CHECK(value == Eigen::Vector3d(key[0], key[1], key[2]));
        }
      }
      // Joints no track animates keep their rest transform.
      for (int j = 0; j < character.skeleton.size(); ++j) {
        bool animated = false;
        for (const Track& track : clip.tracks) animated = animated || track.joint == j;
        if (!animated) CHECK(pose.local[j].matrix().matrix() == character.skeleton.rest_local[j].matrix().matrix());
      }
    }
  }
}

TEST_CASE("CesiumMan's skinned walk stays a plausible body", "[pose]") {
  const std::string path = test::requireAsset("CesiumMan.glb");
  if (path.empty()) return;
  const Character character = loadCharacter(path).character;
  const std::vector<Eigen::Vector3d> bind = skinCharacter(character, bindPose(character.skeleton));
  const double bind_height = extent(bind, 1);
  CHECK(bind_height == Approx(1.5).margin(0.05));
  // CesiumMan's rest pose is its bind pose: skinning at rest leaves the mesh where it was bound.
  const std::vector<Eigen::Vector3d> rest = skinCharacter(character, restPose(character.skeleton));
  double rest_error = 0.0;
  for (size_t v = 0; v < rest.size(); ++v) rest_error = std::max(rest_error, (rest[v] - bind[v]).norm());
  CHECK(rest_error < 1e-5);

  const Clip& walk = character.clips.at(0);
  const std::vector<double> times = sampleTimes(walk, 0.0);
  CHECK(times.size() >= 40);
  for (double time : times) {
    INFO("t = " << time);
    const std::vector<Eigen::Vector3d> posed = skinCharacter(character, sampleClip(character.skeleton, walk, time));
    CHECK(farthest(posed) < 2.0);
    CHECK(std::abs(extent(posed, 1) - bind_height) < 0.1 * bind_height);
  }
}

TEST_CASE("every real clip keeps the skinned character near its bind-pose size", "[pose]") {
  // A skin matrix that lost the bind inverse or the 100x armature scale would throw vertices metres
  // (or hundreds of metres) away; real motion (a jump, a fall) stays well inside twice the body size.
  for (const std::string& name : kAnimatedAssets) {
    const std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    const Character character = loadCharacter(path).character;
    const double bind_radius = farthest(skinCharacter(character, bindPose(character.skeleton)));
    for (const Clip& clip : character.clips) {
      for (double time : sampleTimes(clip, 0.0)) {
        INFO(name << " clip " << clip.name << " t = " << time);
        CHECK(farthest(skinCharacter(character, sampleClip(character.skeleton, clip, time))) < 2.0 * bind_radius);
      }
    }
  }
}

TEST_CASE("KayKit's rest pose is its bind pose stood upright: one skin matrix for every joint", "[pose]") {
  const std::string path = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (path.empty()) return;
  const Character character = loadCharacter(path).character;
  const Skeleton& skeleton = character.skeleton;
  const Pose rest = restPose(skeleton);
  const Eigen::Affine3d first = skinMatrix(rest, skeleton, 0);
  for (int j = 1; j < skeleton.size(); ++j) {
    INFO(skeleton.names[j]);
    CHECK(maxDifference(skinMatrix(rest, skeleton, j), first) < 1e-6);
  }
  // glTF scenes are Y-up: whatever space the bind pose is in, the rest pose stands along +Y.
  const std::vector<Eigen::Vector3d> standing = skinCharacter(character, rest);
  CHECK(extent(standing, 1) == Approx(2.2).margin(0.05));
}
