// Jiggle dynamics: secondary motion of a joint driven by a damped spring, after "Joint-Based Skin
// Deformation in God of War Ragnarök" (Tenghao Wang, GDC 2023), "Jiggle Dynamics" and
// "Implementation": a jiggle point springs towards its animated target, the aim transformation turns
// it into a rotation of the jiggle joint, and a line–elliptical-cone intersection clamps it to
// ClampMajorAngle / ClampMinorAngle; "Combat Reaction": a hit gives the jiggle points of the part that
// was hit an initial velocity.
//
// Unlike a per-frame jiggle bone (the Unity JiggleBone script, whose spring constants act once per
// rendered frame), the spring runs on a fixed internal timestep (kJiggleTimestep) as Respawn's
// physical animation does ("simulated at a fixed frame time, regardless of the hardware"), so a clip
// baked at 30, 60 or 120 fps gives the same motion. docs/jiggle.md gives every equation.
//
// The equations live in the engine-facing runtime (runtime/jiggle.h, the double instantiation): this
// file resolves presets and hits by name, supplies the animation at every internal step, steps the
// runtime's JiggleJob through it and evaluates the runtime's output at the sample times, so a bake and
// a game run one implementation of the spring, the limits, the cone and the aim transformation.
//
// Plain functions over plain data: no I/O. Two hosts:
//  - kSkeletonJoint: the jiggle sits on an existing skeleton joint; its baked rotation channel
//    REPLACES that joint's animated rotation (translation and scale stay as animated). The jiggle
//    rotation is applied in the joint's own frame, so a jiggling joint's children ride on it and the
//    jiggles of a chain add up; each jiggle is simulated against the animated (not jiggled) pose.
//  - kMuscle: the jiggle sits on a muscle's skinned joint from the bake (the talk's biceps). The
//    caller evaluates the muscle and passes its world transforms (JiggleFrame) at jiggleFrameTimes().
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "runtime/jiggle.h"

namespace rigbake {

struct LandmarkSet;
struct MuscleSet;

// The constants of the runtime jiggle (runtime/jiggle.h), which computes every jiggle the bake writes:
// the internal fixed step (240 Hz: h * omega <= 0.32 at the stiffest spring, a multiple of the usual
// 24/30/60/120 fps), stiffness 0..1 log-linearly onto 1..12 Hz, damping 0..1 linearly onto the damping
// ratio [0.02, 1] (the floor keeps damping 0 from ringing forever), the smallest cone half-angle, and
// the distance limit to the target in jiggle lengths (1.5 > sqrt(2) still lets a 90-degree cone reach
// its rim). docs/jiggle.md.
constexpr double kJiggleTimestep = runtime::kJiggleStepSeconds;
constexpr double kMinJiggleHz = runtime::kJiggleMinHz;
constexpr double kMaxJiggleHz = runtime::kJiggleMaxHz;
constexpr double kMinDampingRatio = runtime::kJiggleMinDampingRatio;
constexpr double kMinClampDeg = runtime::kJiggleMinClampDeg;
constexpr double kMaxJiggleOffset = runtime::kJiggleMaxOffset;

// The talk's attributes.
struct JiggleParams {
  double stiffness = 0.1;        // 0..1
  double damping = 0.1;          // 0..1
  double clamp_major_deg = 90.0;  // 0..90, half-angle of the cone towards major_axis
  double clamp_minor_deg = 90.0;  // 0..90, half-angle towards aim x major
};

// Physical spring per unit mass: x'' = -k x - beta x'.
struct SpringConstants {
  double k = 0.0;     // 1/s^2, = omega^2
  double beta = 0.0;  // 1/s,   = 2 zeta omega
};
SpringConstants springConstants(const JiggleParams& params);  // params must be in range

enum class JiggleHost { kSkeletonJoint, kMuscle };

struct JiggleSetup {
  std::string name;  // the jiggling joint's name (skeleton joint, or the muscle's skinned joint)
  JiggleHost host = JiggleHost::kSkeletonJoint;
  int joint = -1;   // kSkeletonJoint: the skeleton joint that jiggles (the talk's pivot)
  int muscle = -1;  // kMuscle: index into MuscleSet::parts
  int root = -1;    // skeleton joint whose frame gives the up vector (the talk's root joint)
  // In the jiggling joint's own frame: the rest direction of the jiggle point (unit) and the
  // direction the major half-angle opens towards (unit, perpendicular to aim_axis).
  Eigen::Vector3d aim_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d major_axis = Eigen::Vector3d::UnitY();
  // The root joint's up axis in its own frame (the talk's rootJoint.upAxis()), unit.
  Eigen::Vector3d root_up = Eigen::Vector3d::UnitY();
  double length = 0.0;  // pivot to jiggle point, scene units, > 0
  JiggleParams params;
  // Names a hit's `joints` may list to reach this jiggle: the joint, its root, the preset target.
  std::vector<std::string> parts;
};

// A velocity change of the jiggle points of the part that was hit ("Combat Reaction").
struct HitImpulse {
  std::string clip;  // clip name; empty: every clip
  double time = 0.0;  // seconds into the clip
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // world space, any length > 0
  double magnitude = 0.0;  // m/s (scene units per second) added to the jiggle point's velocity
  std::vector<std::string> joints;  // parts hit: any name in JiggleSetup::parts
  std::string where;  // file#pointer, for messages
};

// World transforms of one sample time for a kMuscle jiggle (or any caller-driven jiggle).
struct JiggleFrame {
  Eigen::Affine3d parent = Eigen::Affine3d::Identity();  // the jiggling joint's parent
  Eigen::Affine3d root = Eigen::Affine3d::Identity();    // the root joint (up vector)
  Eigen::Affine3d pivot = Eigen::Affine3d::Identity();   // the jiggling joint as animated
};

struct JiggleTrack {
  std::string name;
  JiggleHost host = JiggleHost::kSkeletonJoint;
  int joint = -1;
  int muscle = -1;
  std::vector<double> times;
  // local[t]: the jiggling joint relative to its parent, to write as its T, R and S channels.
  std::vector<Trs> local;
  std::vector<Eigen::Vector3d> point;   // simulated jiggle point, world
  std::vector<Eigen::Vector3d> target;  // animated jiggle point, world
  // Angle between the jiggle and its animated direction, and the cone's half-angle at that azimuth
  // (both degrees), for the report's plots: angle_deg <= clamp_deg always holds.
  std::vector<double> angle_deg;
  std::vector<double> clamp_deg;
};

// "" when `setup` can be simulated on `skeleton` (indices in range, unit perpendicular axes, length
// > 0, parameters in range), otherwise what is wrong. simulate* assert it.
std::string jiggleSetupProblem(const JiggleSetup& setup, const Skeleton& skeleton);

// A kSkeletonJoint setup on `joint` with the defaults docs/jiggle.md lists: root = parent joint, aim
// towards the first child (a leaf continues its bone, at half its length), major axis the joint axis
// most perpendicular to the aim, root_up the root axis most perpendicular to the aim, all at the rest
// pose. `aim_axis`/`length` override (aim_axis in the joint's frame, length in scene units; zero
// vector / 0 = default).
JiggleSetup makeJointJiggle(const Skeleton& skeleton, int joint, const JiggleParams& params,
                            const Eigen::Vector3d& aim_axis = Eigen::Vector3d::Zero(), double length = 0.0);

// Every kSkeletonJoint setup, simulated over `clip`. Only the tracks of kSkeletonJoint setups are
// returned, in setup order (kMuscle setups are skipped: use simulateJiggleFrames). The animation is
// sampled at every internal step, so the result does not depend on `sample_times` except where it is
// read. Each setup's track has one entry per sample time (ascending, at least one).
std::vector<JiggleTrack> simulateJiggle(const Skeleton& skeleton, const Clip& clip, const std::vector<double>& sample_times,
                                        const std::vector<JiggleSetup>& setups, const std::vector<HitImpulse>& hits);

// The times a caller-driven jiggle wants its frames at: every internal step over
// [sample_times.front(), sample_times.back()] and every sample time (merged within 1e-9 s), ascending.
// Frames given at these times make the result independent of the sample rate, as for skeleton joints.
std::vector<double> jiggleFrameTimes(const std::vector<double>& sample_times);

// One jiggle driven by caller-supplied world transforms: frames[f] at frame_times[f] (ascending,
// containing every sample time to within 1e-9 s; best jiggleFrameTimes(sample_times), or just
// sample_times). Between frame times the frames are interpolated by a cubic Hermite (Catmull-Rom)
// path. The track has one entry per sample time. `clip_name` selects the hits. setup.root/joint are
// not read; setup.host is copied to the track.
JiggleTrack simulateJiggleFrames(const JiggleSetup& setup, const std::vector<double>& sample_times,
                                 const std::vector<double>& frame_times, const std::vector<JiggleFrame>& frames,
                                 const std::vector<HitImpulse>& hits, const std::string& clip_name);

// The talk's cone constraint on a point q in the jiggling joint's frame (pivot at the origin): when q
// is outside the elliptical cone around aim_axis (half-angles params.clamp_major/minor towards
// major_axis / aim x major), it is moved along the segment from length * aim_axis to q onto the
// cone surface (the smallest root of the talk's A t^2 + B t + C = 0). Points inside are returned
// unchanged, bit for bit.
Eigen::Vector3d clampToCone(const JiggleSetup& setup, const Eigen::Vector3d& q);

// Angle of direction q from aim_axis, and the cone's half-angle in q's azimuth, degrees.
struct ConeAngle {
  double angle_deg = 0.0;
  double clamp_deg = 0.0;
};
ConeAngle coneAngle(const JiggleSetup& setup, const Eigen::Vector3d& q);

// The jiggle rotation in the jiggling joint's frame for a jiggle point q there (the talk's aim
// transformation with the root's up axis `up`, also in that frame). Identity when q is exactly
// length * aim_axis.
Eigen::Quaterniond aimRotation(const JiggleSetup& setup, const Eigen::Vector3d& q, const Eigen::Vector3d& up);

// The runtime rig of `setups` (all of them, in order) for an engine's joint matrices laid out as the
// skeleton's joints (0 .. skeleton.size() - 1) followed by the muscle rig's skinned joints (muscle m at
// skeleton.size() + m, as runtime::MuscleRigJob writes them): joint_count = skeleton.size() +
// muscle_count. A skeleton joint jiggle's parent is its skeleton parent (-1 at a root: model space); a
// muscle jiggle's parent is `carriers[m]`, the joint its skinned joint rides (muscleCarrierJoint). Every
// setup must pass jiggleSetupProblem().
template <typename Real>
runtime::JiggleRig<Real> buildJiggleRig(const std::vector<JiggleSetup>& setups, const Skeleton& skeleton,
                                        const std::vector<int>& carriers);

// The target names a preset jiggle can give, resolved by resolveJiggles.
struct JigglePresetEntry {
  std::string where;     // file#pointer, for messages
  std::string joint;     // exactly one of joint, landmark, muscle is set
  std::string landmark;  // canonical landmark (must come from a joint)
  std::string muscle;    // muscle part full name, e.g. LeftBicep
  std::string root;      // optional joint name or landmark for the up vector
  JiggleParams params;
  bool has_axis = false;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // aim axis in the jiggling joint's frame
  bool has_major_axis = false;
  Eigen::Vector3d major_axis = Eigen::Vector3d::UnitY();
  double length = 0.0;  // scene units; 0 = default
};

struct JigglePreset {
  std::string file;
  std::string name;
  std::vector<JigglePresetEntry> jiggles;
};

// Turns preset entries into setups. `landmarks` and `muscles` may be null when the preset names none.
// Throws JIGGLE_UNRESOLVED (naming the entry) for an unknown joint, landmark or muscle, a landmark
// not on a joint, a duplicate jiggle target or a degenerate axis.
// kMuscle setups: aim +X (the skinned joint's fibre axis), major +Y (its up axis: the talk's
// "rotate around z" major swing), root the muscle's origin attach joint, length half the rest length.
std::vector<JiggleSetup> resolveJiggles(const JigglePreset& preset, const Skeleton& skeleton, const LandmarkSet* landmarks,
                                        const MuscleSet* muscles);

// Throws HITS_INVALID when a hit names a part no setup answers to.
void checkHits(const std::vector<HitImpulse>& hits, const std::vector<JiggleSetup>& setups);

}  // namespace rigbake
