#include "pipeline/muscle_joint.h"

#include <cmath>

#include "anatomy/placement.h"
#include "formats/gltf_document.h"
#include "test_support.h"
#include "math_fixture.h"

using namespace rigbake;

namespace {

using test::kPi;
using test::maxDifference;

double degreesBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi;
}

// A part as the placement stage would hand it over; the driver rides the origin joint.
MusclePart makePart(const Skeleton& skeleton, int origin_joint, const Eigen::Vector3d& origin, int insertion_joint,
                    const Eigen::Vector3d& insertion, const Eigen::Vector3d& driver,
                    const Eigen::Vector2d& bulge = Eigen::Vector2d::Zero(), const std::string& side = "Left") {
  MusclePart part;
  part.group = "Test";
  part.name = skeleton.names[origin_joint] + "_" + skeleton.names[insertion_joint];
  part.side = side;
  part.origin = locatorOn(skeleton, origin_joint, origin);
  part.insertion = locatorOn(skeleton, insertion_joint, insertion);
  part.driver = locatorOn(skeleton, origin_joint, driver);
  part.compression = 0.5;
  part.stretch = 1.5;
  part.bulge = bulge;
  part.response = defaultMuscleResponse(part.compression, part.stretch, bulge);
  return part;
}

// chest (1.3 m up) -> upperarm.l -> lowerarm.l -> wrist.l, Y-up, facing +Z, arm in T-pose along +X.
// Bind pose = rest pose.
Skeleton syntheticArm() {
  Skeleton skeleton;
  skeleton.names = {"chest", "upperarm.l", "lowerarm.l", "wrist.l"};
  skeleton.parents = {-1, 0, 1, 2};
  skeleton.nodes = {0, 1, 2, 3};
  const std::vector<Eigen::Vector3d> offsets = {{0, 1.3, 0}, {0.2, 0.1, 0}, {0.3, 0, 0}, {0.25, 0, 0}};
  for (int j = 0; j < 4; ++j) {
    Trs trs;
    trs.translation = offsets[j];
    skeleton.rest_local.push_back(trs);
    skeleton.root_parent_world.push_back(Eigen::Affine3d::Identity());
    const Eigen::Affine3d above = j == 0 ? Eigen::Affine3d::Identity() : skeleton.bind_world[j - 1];
    skeleton.bind_world.push_back(above * trs.matrix());
  }
  return skeleton;
}

// Body axes measured on the bind skeleton, so that the sweeps mean the same on a Z-up bind pose.
struct BodyAxes {
  Eigen::Vector3d up, lateral, forward;  // lateral points to the left side
};

BodyAxes bodyAxes(const Skeleton& skeleton, const std::string& lower, const std::string& upper,
                  const std::string& left_arm, const std::string& right_arm) {
  BodyAxes axes;
  axes.up = (skeleton.bindPosition(skeleton.find(upper)) - skeleton.bindPosition(skeleton.find(lower))).normalized();
  Eigen::Vector3d across =
      skeleton.bindPosition(skeleton.find(left_arm)) - skeleton.bindPosition(skeleton.find(right_arm));
  axes.lateral = (across - across.dot(axes.up) * axes.up).normalized();
  axes.forward = axes.lateral.cross(axes.up);
  return axes;
}

// The bind pose with `joint` (and everything below it) turned about `axis` through its own position.
Pose turnFromBind(const Skeleton& skeleton, int joint, const Eigen::AngleAxisd& turn) {
  const Pose bind = bindPose(skeleton);
  std::vector<Trs> local = bind.local;
  const Eigen::Vector3d pivot = skeleton.bindPosition(joint);
  const Eigen::Affine3d world = Eigen::Translation3d(pivot) * turn * Eigen::Translation3d(-pivot) * skeleton.bind_world[joint];
  const int parent = skeleton.parents[joint];
  const Eigen::Affine3d& above = parent >= 0 ? bind.world[parent] : skeleton.root_parent_world[joint];
  local[joint] = decomposeTrs(above.inverse() * world);
  return composePose(skeleton, std::move(local));
}

// One muscle per bone of a real skeleton: origin on the parent a third of the way down the bone and
// off it, insertion just past the child joint, belly offset across the bone; alternate sides so the
// Right bulge sign is exercised too.
std::vector<MusclePart> musclesAlongBones(const Skeleton& skeleton) {
  std::vector<MusclePart> parts;
  for (int j = 0; j < skeleton.size(); ++j) {
    const int parent = skeleton.parents[j];
    if (parent < 0) continue;
    const Eigen::Vector3d start = skeleton.bindPosition(parent);
    const Eigen::Vector3d end = skeleton.bindPosition(j);
    const Eigen::Vector3d bone = end - start;
    if (bone.norm() < 1e-3) continue;
    const std::vector<int> children = skeleton.children(j);
    const Eigen::Vector3d beyond =
        children.empty() ? Eigen::Vector3d(0.1 * bone) : Eigen::Vector3d(0.2 * (skeleton.bindPosition(children[0]) - end));
    Eigen::Vector3d across = bone.cross(Eigen::Vector3d(0.3, 0.5, 0.8));
    if (across.norm() < 1e-9 * bone.norm()) across = bone.cross(Eigen::Vector3d::UnitX());
    across = across.normalized() * 0.1 * bone.norm();
    const Eigen::Vector3d origin = start + 0.3 * bone + 0.5 * across;
    const Eigen::Vector3d insertion = end + beyond + 0.3 * across;
    if ((insertion - origin).norm() < 1e-3) continue;
    const Eigen::Vector3d driver = 0.5 * (origin + insertion) + across;
    parts.push_back(makePart(skeleton, parent, origin, j, insertion, driver, Eigen::Vector2d(0.03, -0.02),
                             j % 2 ? "Left" : "Right"));
  }
  return parts;
}

// The invariants of one evaluated muscle that hold in every pose.
void checkMuscleInvariants(const Skeleton& skeleton, const MusclePart& part, const MuscleJointState& state, const Pose& pose) {
  INFO(part.name);
  const Eigen::Vector3d fibre = (state.insertion - state.origin).normalized();
  const Eigen::Matrix3d base = state.base.linear();
  CHECK((base.col(0) - fibre).norm() < 1e-12);
  CHECK((base.transpose() * base - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(base.determinant() == Approx(1.0).epsilon(1e-12));
  CHECK((state.base.translation() - state.origin).norm() < 1e-15);
  const Eigen::Matrix3d tip = state.tip.linear();
  CHECK((tip.col(0) + fibre).norm() < 1e-12);
  CHECK((tip.col(1) - base.col(1)).norm() < 1e-15);
  CHECK(tip.determinant() == Approx(1.0).epsilon(1e-12));
  CHECK((state.tip.translation() - state.insertion).norm() < 1e-15);
  CHECK(state.clamped_ratio >= part.compression);
  CHECK(state.clamped_ratio <= part.stretch);
  CHECK(state.scale > 0.0);
  // The skinned joint rides its carrier: W_carrier B_carrier^-1 K T(0, up, side) diag(1, s, s), K its
  // bind transform, so at rest response it moves exactly as the carrier's skin does.
  const int carrier = muscleCarrierJoint(part);
  const Eigen::Affine3d bind = muscleBindTransform(part, skeleton);
  Eigen::Affine3d response = Eigen::Affine3d::Identity();
  response.translation() = Eigen::Vector3d(0.0, state.offset_up, state.offset_side);
  response.linear() = Eigen::Vector3d(1.0, state.scale, state.scale).asDiagonal();
  const Eigen::Affine3d expected = skinMatrix(pose, skeleton, carrier) * bind * response;
  CHECK(maxDifference(state.skinned, expected) < 1e-9 * std::max(1.0, expected.matrix().cwiseAbs().maxCoeff()));
  // Written as a TRS channel under the carrier, it comes back exactly when that joint's world
  // transform is a similarity. Real files compose float keys, whose rounding leaves the parent up to
  // ~1e-6 away from one; the shear that cannot go into a TRS is of that order, no more.
  const Trs trs = skinnedLocalTrs(state, pose, carrier);
  const Eigen::Matrix3d parent_linear = pose.world[carrier].linear();
  const double parent_scale_squared = std::pow(std::abs(parent_linear.determinant()), 2.0 / 3.0);
  const double parent_shear =
      (parent_linear.transpose() * parent_linear / parent_scale_squared - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double tolerance = 1e-12 + 2.0 * parent_shear * state.skinned.matrix().cwiseAbs().maxCoeff();
  CHECK(maxDifference(pose.world[carrier] * trs.matrix(), state.skinned) <= tolerance);
}

struct SweepResult {
  double max_up_step = 0.0;     // degrees the base frame's up axis turned in one 1-degree step, at most
  double max_fibre_step = 0.0;  // degrees the fibre itself turned in one step, at most
  double arm_end_alignment = 0.0;  // arm direction . body up at the last step
};

// Swings the arm from hanging down (0) to 180 degrees in the plane spanned by -up and `towards`, one
// degree per step, evaluating every muscle at every step. A flipping up vector would turn by ~180
// degrees in one step; a continuous one turns with the fibre: by the fibre's own step, up to the
// 1/cos(theta/2) the minimal rotation adds at theta away from the carried rest fibre (< 2 here).
SweepResult sweepArm(const Skeleton& skeleton, int arm, int forearm, const BodyAxes& axes,
                     const Eigen::Vector3d& towards, const std::vector<MusclePart>& parts) {
  SweepResult result;
  const Eigen::Vector3d down = -axes.up;
  const Eigen::Vector3d bind_direction =
      (skeleton.bindPosition(forearm) - skeleton.bindPosition(arm)).normalized();
  // First bring the bind arm down to the side, then swing it.
  const Eigen::Quaterniond to_down = Eigen::Quaterniond::FromTwoVectors(bind_direction, down);
  const Eigen::Vector3d swing_axis = down.cross(towards).normalized();
  std::vector<Eigen::Vector3d> previous_up(parts.size()), previous_fibre(parts.size());
  for (int degrees = 0; degrees <= 180; ++degrees) {
    const Eigen::Quaterniond turn = Eigen::Quaterniond(Eigen::AngleAxisd(degrees * kPi / 180.0, swing_axis)) * to_down;
    const Pose pose = turnFromBind(skeleton, arm, Eigen::AngleAxisd(turn));
    for (size_t p = 0; p < parts.size(); ++p) {
      const MuscleJointState state = evaluateMuscle(parts[p], skeleton, pose);
      checkMuscleInvariants(skeleton, parts[p], state, pose);
      const Eigen::Vector3d up = state.base.linear().col(1);
      const Eigen::Vector3d fibre = state.base.linear().col(0);
      if (degrees > 0) {
        const double up_step = degreesBetween(previous_up[p], up);
        const double fibre_step = degreesBetween(previous_fibre[p], fibre);
        INFO(parts[p].name << " at " << degrees << " degrees: up turned " << up_step << ", fibre " << fibre_step);
        CHECK(up_step <= 2.0 * fibre_step + 0.01);
        result.max_up_step = std::max(result.max_up_step, up_step);
        result.max_fibre_step = std::max(result.max_fibre_step, fibre_step);
      }
      previous_up[p] = up;
      previous_fibre[p] = fibre;
    }
    const Eigen::Vector3d arm_direction = (pose.world[forearm].translation() - pose.world[arm].translation()).normalized();
    result.arm_end_alignment = arm_direction.dot(axes.up);
  }
  return result;
}

}  // namespace

TEST_CASE("the talk's response: bulge and volume-preserving scale when compressed, nothing when stretched", "[muscle]") {
  const Skeleton skeleton = syntheticArm();
  const int upperarm = skeleton.find("upperarm.l");
  const int lowerarm = skeleton.find("lowerarm.l");
  // A bicep: from just below the shoulder to just past the elbow, belly in front of the arm.
  const Eigen::Vector3d origin(0.23, 1.4, 0.04);
  const Eigen::Vector3d insertion(0.53, 1.39, 0.03);
  const Eigen::Vector3d driver = 0.5 * (origin + insertion) + Eigen::Vector3d(0, 0, 0.02);
  const Eigen::Vector2d bulge(0.02, 0.01);
  const MusclePart left = makePart(skeleton, upperarm, origin, lowerarm, insertion, driver, bulge, "Left");
  const MusclePart right = makePart(skeleton, upperarm, origin, lowerarm, insertion, driver, bulge, "Right");
  const double rest_length = (insertion - origin).norm();
  const MuscleRestFrame rest = muscleRestFrame(left, skeleton);
  CHECK(rest.length == rest_length);
  // The belly is in front of the arm, so the muscle's up axis is the body's forward axis.
  CHECK(rest.up.z() > 0.99);

  const Pose bind = bindPose(skeleton);
  for (int step = 4; step <= 40; ++step) {
    const double r = step * 0.05;
    INFO("r = " << r);
    // Slide the elbow along the upper arm so that the fibre has exactly length r * L_rest:
    // the fibre is (x, -0.01, -0.01) with x the elbow's offset minus the origin's 0.03.
    std::vector<Trs> local = bind.local;
    local[lowerarm].translation.x() = std::sqrt(r * r * rest_length * rest_length - 2e-4);
    const Pose pose = composePose(skeleton, local);
    const MuscleJointState state = evaluateMuscle(left, skeleton, pose);
    checkMuscleInvariants(skeleton, left, state, pose);
    CHECK(state.ratio == Approx(r).epsilon(1e-12));
    const double clamped = std::min(1.5, std::max(0.5, r));
    CHECK(state.clamped_ratio == Approx(clamped).epsilon(1e-12));
    // Linear keys: nothing while stretched, the full bulge vector and scale 1/sqrt(0.5) at full
    // compression; x along the up axis, y along the side axis (mirrored on the right side).
    const double weight = r >= 1.0 ? 0.0 : (1.0 - clamped) / 0.5;
    CHECK(state.offset_up == Approx(weight * bulge.x()).margin(1e-15));
    CHECK(state.offset_side == Approx(weight * bulge.y()).margin(1e-15));
    CHECK(state.scale == Approx(1.0 + weight * (1.0 / std::sqrt(0.5) - 1.0)).epsilon(1e-12));
    const MuscleJointState mirrored = evaluateMuscle(right, skeleton, pose);
    CHECK(mirrored.offset_side == Approx(-weight * bulge.y()).margin(1e-15));
    // The elbow slides along the upper arm, so nothing twists.
    CHECK(std::abs(state.twist) < 1e-12);
  }
}

TEST_CASE("at the bind pose every muscle joint sits exactly at its bind transform", "[muscle]") {
  double worst = 0.0;
  auto checkAtBind = [&worst](const Skeleton& skeleton, const std::vector<MusclePart>& parts) {
    const Pose bind = bindPose(skeleton);
    for (const MusclePart& part : parts) {
      INFO(part.name);
      REQUIRE(musclePartProblem(part, skeleton).empty());
      const MuscleJointState state = evaluateMuscle(part, skeleton, bind);
      const double error = maxDifference(state.skinned, muscleBindTransform(part, skeleton));
      worst = std::max(worst, error);
      CHECK(error < 1e-9);
      CHECK((state.driver.translation() - part.driver.world).norm() < 1e-9);
      CHECK((state.origin - part.origin.world).norm() < 1e-9);
      CHECK((state.insertion - part.insertion.world).norm() < 1e-9);
      CHECK(state.ratio == Approx(1.0).epsilon(1e-12));
      CHECK(std::abs(state.offset_up) + std::abs(state.offset_side) < 1e-12);
      CHECK(state.scale == Approx(1.0).epsilon(1e-12));
      checkMuscleInvariants(skeleton, part, state, bind);
    }
  };

  const Skeleton arm = syntheticArm();
  std::vector<MusclePart> synthetic = musclesAlongBones(arm);
  // A part drawn straight from joint to joint with the belly on that line has no "outward"
  // direction; the origin joint's axis most nearly across the fibre (here +Y) stands in.
  synthetic.push_back(makePart(arm, 1, arm.bindPosition(1), 2, arm.bindPosition(2),
                               0.5 * (arm.bindPosition(1) + arm.bindPosition(2)), Eigen::Vector2d(0.02, 0.02)));
  CHECK((muscleRestFrame(synthetic.back(), arm).up - Eigen::Vector3d::UnitY()).norm() < 1e-15);
  checkAtBind(arm, synthetic);

  for (const std::string& name : test::sharedAssetNames()) {
    const std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    INFO(name);
    const Skeleton skeleton = loadCharacter(path).character.skeleton;
    const std::vector<MusclePart> parts = musclesAlongBones(skeleton);
    CHECK(parts.size() >= 15);
    checkAtBind(skeleton, parts);
  }
  CHECK(worst < 1e-12);
}

TEST_CASE("KayKit's rest pose differs from its bind pose: muscles follow the common skin matrix", "[muscle]") {
  const std::string path = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (path.empty()) return;
  const Skeleton skeleton = loadCharacter(path).character.skeleton;
  const Pose rest = restPose(skeleton);
  const Eigen::Affine3d upright = skinMatrix(rest, skeleton, 0);
  for (const MusclePart& part : musclesAlongBones(skeleton)) {
    INFO(part.name);
    const MuscleJointState state = evaluateMuscle(part, skeleton, rest);
    CHECK(maxDifference(state.skinned, upright * muscleBindTransform(part, skeleton)) < 1e-5);
    CHECK(state.ratio == Approx(1.0).epsilon(1e-6));
  }
}

TEST_CASE("base aims at the insertion and tip at the origin through every real clip", "[muscle]") {
  for (const std::string name : {"CesiumMan.glb", "RobotExpressive.glb", "Quaternius_Cyberpunk_Character.glb"}) {
    const std::string path = test::requireAsset(name);
    if (path.empty()) continue;
    const Character character = loadCharacter(path).character;
    const std::vector<MusclePart> parts = musclesAlongBones(character.skeleton);
    for (const Clip& clip : character.clips) {
      for (double time : sampleTimes(clip, 0.0)) {
        INFO(name << " clip " << clip.name << " t = " << time);
        const Pose pose = sampleClip(character.skeleton, clip, time);
        for (const MusclePart& part : parts)
          checkMuscleInvariants(character.skeleton, part, evaluateMuscle(part, character.skeleton, pose), pose);
      }
    }
  }
}

TEST_CASE("the up axis does not flip as the arm goes overhead (synthetic arm)", "[muscle]") {
  const Skeleton skeleton = syntheticArm();
  const int chest = skeleton.find("chest");
  const int upperarm = skeleton.find("upperarm.l");
  const int lowerarm = skeleton.find("lowerarm.l");
  const BodyAxes axes{Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()};
  const Eigen::Vector3d shoulder = skeleton.bindPosition(upperarm);
  const std::vector<MusclePart> parts = {
      // Bicep: rides the upper arm, belly in front.
      makePart(skeleton, upperarm, shoulder + Eigen::Vector3d(0.03, 0, 0.04), lowerarm,
               skeleton.bindPosition(lowerarm) + Eigen::Vector3d(0.03, -0.01, 0.03),
               shoulder + Eigen::Vector3d(0.17, 0, 0.06), Eigen::Vector2d(0.02, 0.0)),
      // Deltoid-like: from above the shoulder on the chest to the upper arm, so its fibre turns
      // through ~180 degrees relative to its origin joint over the sweep.
      makePart(skeleton, chest, shoulder + Eigen::Vector3d(-0.03, 0.06, 0.02), upperarm,
               shoulder + Eigen::Vector3d(0.12, -0.01, 0.0), shoulder + Eigen::Vector3d(0.05, 0.05, 0.01),
               Eigen::Vector2d(0.01, 0.0)),
  };
  const SweepResult abduction = sweepArm(skeleton, upperarm, lowerarm, axes, axes.lateral, parts);
  CHECK(abduction.arm_end_alignment > 0.999);
  CHECK(abduction.max_up_step < 5.0);
  const SweepResult flexion = sweepArm(skeleton, upperarm, lowerarm, axes, axes.forward, parts);
  CHECK(flexion.arm_end_alignment > 0.999);
  CHECK(flexion.max_up_step < 5.0);
}

TEST_CASE("the up axis does not flip as the arm goes overhead (KayKit upperarm.l)", "[muscle]") {
  const std::string path = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (path.empty()) return;
  const Skeleton skeleton = loadCharacter(path).character.skeleton;
  const int chest = skeleton.find("chest");
  const int upperarm = skeleton.find("upperarm.l");
  const int lowerarm = skeleton.find("lowerarm.l");
  const int wrist = skeleton.find("wrist.l");
  REQUIRE(chest >= 0);
  REQUIRE(upperarm >= 0);
  REQUIRE(lowerarm >= 0);
  REQUIRE(wrist >= 0);
  const BodyAxes axes = bodyAxes(skeleton, "hips", "head", "upperarm.l", "upperarm.r");
  const Eigen::Vector3d shoulder = skeleton.bindPosition(upperarm);
  const Eigen::Vector3d elbow = skeleton.bindPosition(lowerarm);
  const Eigen::Vector3d along_arm = (elbow - shoulder).normalized();
  const Eigen::Vector3d along_forearm = (skeleton.bindPosition(wrist) - elbow).normalized();
  const std::vector<MusclePart> parts = {
      // Bicep: upperarm.l -> lowerarm.l, in front of the arm.
      makePart(skeleton, upperarm, shoulder + 0.03 * along_arm + 0.04 * axes.forward, lowerarm,
               elbow + 0.04 * along_forearm + 0.03 * axes.forward,
               0.5 * (shoulder + elbow) + 0.06 * axes.forward, Eigen::Vector2d(0.02, 0.0)),
      // Deltoid-like: chest above the shoulder -> upper arm.
      makePart(skeleton, chest, shoulder - 0.03 * axes.lateral + 0.06 * axes.up + 0.02 * axes.forward, upperarm,
               shoulder + 0.1 * along_arm - 0.01 * axes.up, shoulder + 0.02 * along_arm + 0.05 * axes.up,
               Eigen::Vector2d(0.01, 0.0)),
  };
  const SweepResult abduction = sweepArm(skeleton, upperarm, lowerarm, axes, axes.lateral, parts);
  CHECK(abduction.arm_end_alignment > 0.99);
  CHECK(abduction.max_up_step < 5.0);
  const SweepResult flexion = sweepArm(skeleton, upperarm, lowerarm, axes, axes.forward, parts);
  CHECK(flexion.arm_end_alignment > 0.99);
  CHECK(flexion.max_up_step < 5.0);
}

TEST_CASE("a fibre reversed relative to its origin joint still gets a valid frame", "[muscle]") {
  // The one configuration where the minimal rotation is undefined: the insertion has passed through
  // the origin. The carried up axis is kept (a half turn about it).
  const Skeleton skeleton = syntheticArm();
  const int upperarm = skeleton.find("upperarm.l");
  const int lowerarm = skeleton.find("lowerarm.l");
  const MusclePart part = makePart(skeleton, upperarm, Eigen::Vector3d(0.25, 1.4, 0), lowerarm,
                                   Eigen::Vector3d(0.6, 1.4, 0), Eigen::Vector3d(0.4, 1.45, 0));
  const MuscleRestFrame rest = muscleRestFrame(part, skeleton);
  std::vector<Trs> local = bindPose(skeleton).local;
  local[lowerarm].translation.x() = -0.2;  // insertion at x = 0.1, behind the origin at 0.25
  const Pose pose = composePose(skeleton, local);
  const MuscleJointState state = evaluateMuscle(part, skeleton, pose);
  checkMuscleInvariants(skeleton, part, state, pose);
  CHECK((state.base.linear().col(0) + rest.fibre).norm() < 1e-15);
  CHECK((state.base.linear().col(1) - rest.up).norm() < 1e-15);
  CHECK(state.clamped_ratio == 0.5);
}

TEST_CASE("musclePartProblem names what makes a part unusable", "[muscle]") {
  const Skeleton skeleton = syntheticArm();
  const MusclePart good = makePart(skeleton, 1, Eigen::Vector3d(0.25, 1.4, 0), 2, Eigen::Vector3d(0.6, 1.4, 0),
                                   Eigen::Vector3d(0.4, 1.45, 0));
  CHECK(musclePartProblem(good, skeleton).empty());
  MusclePart bad = good;
  bad.insertion.joint = 9;
  CHECK(musclePartProblem(bad, skeleton) == "insertion.joint 9 is not a joint of the 4-joint skeleton");
  bad = good;
  bad.origin.joint = -1;
  CHECK(musclePartProblem(bad, skeleton).rfind("origin.joint -1", 0) == 0);
  bad = good;
  bad.insertion.world = bad.origin.world;
  CHECK(musclePartProblem(bad, skeleton).find("apart") != std::string::npos);
  bad = good;
  bad.compression = 1.2;
  CHECK(musclePartProblem(bad, skeleton).rfind("compression", 0) == 0);
  bad = good;
  bad.stretch = 0.9;
  CHECK(musclePartProblem(bad, skeleton).rfind("stretch", 0) == 0);
  bad = good;
  bad.bulge.x() = std::nan("");
  CHECK(musclePartProblem(bad, skeleton) == "bulge is not finite");
}
