// rigbake runtime: jiggle dynamics an engine steps every frame (the God of War Ragnarök talk's
// "Jiggle Dynamics": a jiggle point springs towards its animated target, the aim transformation turns
// it into a rotation of the jiggling joint, an elliptical cone clamps it; "Combat Reaction": a hit
// gives the jiggle points of the part that was hit an initial velocity). The spring runs at a fixed
// 240 Hz whatever the frame rate, carrying the leftover time from frame to frame ("simulated at a fixed
// frame time, regardless of the hardware", Respawn's physical animation talk). No dependency beyond the
// C++17 standard library, no allocation, no exception and no I/O in Run(). docs/runtime.md ("Jiggle")
// says how an engine drives it; docs/jiggle.md gives every equation.
//
// Conventions as in runtime/muscle_rig.h: matrices are 4x4 affine transforms stored column-major, 16
// numbers each (m[12], m[13], m[14] the translation); "model space" is whatever space the caller's joint
// matrices are in, and every model-space output is in that space. Quaternions are (x, y, z, w).
//
// Real is float for engines and double for rigbake's own bake: pipeline/jiggle.cpp steps these very
// jobs and evaluates these very outputs, so a bake and a game cannot disagree about the equations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/muscle_rig.h"  // Span

namespace rigbake::runtime {

// The internal fixed step: 240 Hz keeps h * omega <= 0.32 at the stiffest spring (kJiggleMaxHz), well
// inside semi-implicit Euler's stability region, and is a multiple of the usual 24/30/60/120 fps.
constexpr double kJiggleStepSeconds = 1.0 / 240.0;
// Stiffness 0..1 maps log-linearly onto the undamped natural frequency, kJiggleMinHz..kJiggleMaxHz.
constexpr double kJiggleMinHz = 1.0;
constexpr double kJiggleMaxHz = 12.0;
// Damping 0..1 maps linearly onto the damping ratio zeta in [kJiggleMinDampingRatio, 1] (critical).
constexpr double kJiggleMinDampingRatio = 0.02;
// Cone half-angles below this (degrees) are raised to it: a zero-angle elliptical cone is degenerate.
constexpr double kJiggleMinClampDeg = 0.01;
// Distance limit of the jiggle point to its target, in jiggle lengths (Respawn's linear limit to the
// animation target): 1.5 > sqrt(2) still lets a 90-degree cone reach its rim.
constexpr double kJiggleMaxOffset = 1.5;

// Physical spring per unit mass: x'' = -k x - beta x' (x the jiggle point minus its target).
struct JiggleSpring {
  double k = 0.0;     // 1/s^2, = omega^2
  double beta = 0.0;  // 1/s,   = 2 zeta omega
};
// The talk's Stiffness and Damping (each 0..1) as a spring: f = 1 Hz * 12^stiffness, omega = 2 pi f,
// zeta = 0.02 + 0.98 damping (R. Juckett, "Damped Springs": frequency and damping ratio).
JiggleSpring jiggleSpring(double stiffness, double damping);

// One jiggle as a preset or a file gives it: the talk's attributes, its axes and its joints. Offline
// data: buildJiggleSettings() turns it into the runtime's JiggleSettings once.
template <typename Real>
struct JiggleSpec {
  // Indices into the joint matrices a job is given (JiggleRig::joint_count of them).
  int joint = -1;   // the jiggling joint (the talk's pivot), animated and not jiggled
  int parent = -1;  // its parent, for the parent-relative outputs; -1: model space itself
  int root = -1;    // the talk's root joint, whose frame carries the up vector; -1: model space itself
  // In the jiggling joint's frame: the rest direction of the jiggle point (unit) and the direction the
  // major half-angle opens towards (unit, perpendicular to aim_axis).
  Real aim_axis[3] = {1, 0, 0};
  Real major_axis[3] = {0, 1, 0};
  Real root_up[3] = {0, 1, 0};  // the root's up axis in the root's frame (rootJoint.upAxis()), unit
  Real length = 1;              // pivot to jiggle point, model-space units, > 0
  Real stiffness = Real(0.1);   // 0..1
  Real damping = Real(0.1);     // 0..1
  Real clamp_major_deg = 90;    // 0..90: half-angle of the cone towards major_axis
  Real clamp_minor_deg = 90;    // 0..90: half-angle towards aim_axis x major_axis
};

// "" when `spec` can be built for a skeleton of `joint_count` matrices, else what is wrong.
template <typename Real>
const char* jiggleSpecProblem(const JiggleSpec<Real>& spec, int joint_count);

// Runtime data of one jiggle: the spec's joints and axes with the spring and the cone made ready.
template <typename Real>
struct JiggleSettings {
  int joint = -1, parent = -1, root = -1;  // as in JiggleSpec
  Real aim_axis[3] = {1, 0, 0};
  Real major_axis[3] = {0, 1, 0};
  Real minor_axis[3] = {0, 0, 1};  // aim_axis x major_axis
  Real root_up[3] = {0, 1, 0};
  Real length = 1;
  Real rest_point[3] = {1, 0, 0};  // length * aim_axis: the jiggle point at rest, joint frame
  Real max_offset = Real(1.5);     // kJiggleMaxOffset * length
  Real spring_k = 0, spring_beta = 0;
  // The cone y^2 = x^2 / tan^2 a + z^2 / tan^2 b in (major, aim, minor) = (x, y, z), times
  // sin^2 a sin^2 b so 90-degree half-angles stay finite: G = gx x^2 + gz z^2 - gy y^2 <= 0 inside.
  Real cone_gx = 0, cone_gy = 1, cone_gz = 0;
  Real cone_sin_major = 1, cone_cos_major = 0, cone_sin_minor = 1, cone_cos_minor = 0;
};

// No checks: a spec jiggleSpecProblem() accepts gives settings every job can run.
template <typename Real>
JiggleSettings<Real> buildJiggleSettings(const JiggleSpec<Real>& spec);

template <typename Real>
struct JiggleRig {
  int joint_count = 0;  // how many joint matrices a job must be given
  std::vector<JiggleSettings<Real>> jiggles;
};

// "" when every jiggle's joints lie inside the rig's joint matrices and its numbers are usable.
template <typename Real>
const char* jiggleRigProblem(const JiggleRig<Real>& rig);

// One jiggle's simulation state, owned by the caller (one per JiggleRig::jiggles entry), carried from
// frame to frame. Zero-initialized it has not started: the first JiggleJob::Run starts it at rest.
//
// Double whatever Real is, and so are the steps: the state integrates the spring over thousands of
// steps, where float's rounding of each step adds up (measured on the sample's clips: up to 1.8e-4
// degrees from the double runtime given the very same float matrices, and more once a jiggle touches
// its limits), while a frame's own evaluation (matrices in, rotations out) does not accumulate and
// runs in Real. 200 bytes a jiggle; a double step costs what a float one does in this scalar code.
struct JiggleState {
  // At the last step, in quantities relative to the target (precision of the jiggle's length, not of
  // the model-space coordinates): the jiggle point minus its target (model space), the point's
  // velocity minus the target's over that step, the target's velocity over that step (model-space
  // units per second), and the target minus the joint's position at the last frame.
  double offset[3] = {0, 0, 0};
  double relative_velocity[3] = {0, 0, 0};
  double target_velocity[3] = {0, 0, 0};
  double target_from_frame[3] = {0, 0, 0};
  // The offset in the jiggling joint's frame after the limits, at the last step and at the one before:
  // what the outputs are read from.
  double local_offset[3] = {0, 0, 0};
  double previous_local_offset[3] = {0, 0, 0};
  // The jiggling joint's rigid frame (scale removed) at the last frame, for interpolating the targets
  // of the steps between it and the next frame.
  double frame_translation[3] = {0, 0, 0};
  double frame_rotation[4] = {0, 0, 0, 1};
  double since_step = 0;  // seconds from the last step to the last frame, in [0, kJiggleStepSeconds)
  double impulse[3] = {0, 0, 0};  // velocity to add at the next step (applyJiggleImpulse)
  bool started = false;
};

// What one jiggle looks like for an offset in its joint's frame (a JiggleState's local offset, or a
// blend of two). Everything the outputs of JiggleJob hold.
template <typename Real>
struct JiggleOutput {
  // The jiggle rotation in the jiggling joint's own frame: jiggled local rotation = animated local
  // rotation * correction (x, y, z, w). Exactly identity when the jiggle is at rest.
  Real correction[4] = {0, 0, 0, 1};
  bool at_rest = true;                // the clamped jiggle point is exactly the rest point
  Real point[3] = {0, 0, 0};          // the jiggle point after the cone clamp, model space
  Real target[3] = {0, 0, 0};         // the animated jiggle point, model space
  Real angle_deg = 0;                 // angle between the jiggle and its animated direction
  Real clamp_deg = 0;                 // the cone's half-angle at that azimuth: angle_deg <= clamp_deg
};

// Starts jiggles at rest on their targets: position on the target, and moving with it when a second
// pose is given. Impulses given before the reset act at it (a hit in the frame a character appears).
template <typename Real>
struct JiggleResetJob {
  const JiggleRig<Real>* rig = nullptr;
  // Input: rig->joint_count model-space joint matrices (16 numbers each), animated and not jiggled.
  Span<const Real> joint_matrices;
  // Optional (leave empty for a jiggle at rest, velocity zero): the same joints at another time, and
  // that time relative to joint_matrices' in seconds (!= 0; negative for the previous frame). The jiggle
  // point starts with its target's velocity (target(other) - target(this)) / velocity_time, so a
  // character that appears in motion does not get a kick.
  Span<const Real> velocity_matrices;
  Real velocity_time = 0;
  // In/out: one state per jiggle.
  Span<JiggleState> states;

  bool Validate() const;
  bool Run() const;  // false (and nothing written) when Validate() fails
};

// Advances every jiggle from the last frame to this one: the internal steps of kJiggleStepSeconds that
// fall in delta_time (plus the time left over from earlier frames), each against its target
// interpolated between the last frame's and this frame's animated joint, then the outputs for this
// frame's time. A state that has not started is started at rest on this frame (no step).
template <typename Real>
struct JiggleJob {
  const JiggleRig<Real>* rig = nullptr;
  // Input: rig->joint_count model-space joint matrices (16 numbers each) of this frame's animated pose,
  // not jiggled: the jiggling joints, their parents and their roots as the animation (and any muscle
  // rig, see docs/runtime.md) put them.
  Span<const Real> joint_matrices;
  Real delta_time = 0;  // seconds since the previous Run, >= 0 (0: no time passes, no step)
  // More steps than this in one Run (a hitch) are not taken: the frame is simulated as if it lasted
  // max_steps steps and the leftover time is dropped, so a long frame costs at most max_steps steps. 0:
  // no limit.
  int max_steps = 0;
  // In/out: one state per jiggle, the caller's, carried from Run to Run.
  Span<JiggleState> states;
  // Outputs, one entry per jiggle, each optional (leave empty to skip):
  // corrections: 4 numbers (x, y, z, w), JiggleOutput::correction; multiply it onto the jiggling joint's
  // animated local rotation before the engine computes the joint's (and its children's) model matrices.
  Span<Real> corrections;
  // local_rotations: 4 numbers, the jiggled rotation relative to the parent: the rotation of
  // parent^-1 * joint (scale removed) times the correction.
  Span<Real> local_rotations;
  // model_matrices: 16 numbers, the jiggling joint's model matrix with the jiggle: parent * T * (R *
  // correction) * S for the joint's parent-relative T, R, S.
  Span<Real> model_matrices;
  // points: 3 numbers, the jiggle point after the cone clamp, model space.
  Span<Real> points;
  // cone_angles: 2 numbers, JiggleOutput::angle_deg and clamp_deg.
  Span<Real> cone_angles;

  bool Validate() const;
  bool Run() const;  // false (and nothing written) when Validate() fails
};

// A hit ("Combat Reaction"): adds magnitude * direction / |direction| (model space, units per second)
// to the velocity of jiggle `jiggle` at its next step (after that step's spring, before its limits:
// the kick then acts on the state at the step, as the bake's hits do). After a JiggleResetJob and
// before any step, the reset's state takes it instead (JiggleResetJob::Run adds impulses given before
// it). False when the index is outside `states` or the direction is zero or not finite.
// (Real is deduced from `direction` alone.)
template <typename T>
struct JiggleNonDeduced {
  using type = T;
};
template <typename Real>
bool applyJiggleImpulse(const Span<JiggleState>& states, std::size_t jiggle, const Real direction[3],
                        typename JiggleNonDeduced<Real>::type magnitude);
// The same for every jiggle whose bit is set in `mask` (bit i: jiggle i, i < 64); returns how many.
template <typename Real>
int applyJiggleImpulseMask(const Span<JiggleState>& states, std::uint64_t mask, const Real direction[3],
                           typename JiggleNonDeduced<Real>::type magnitude);

// The building blocks the jobs run, for the bake and for tests.

// The jiggle's look for `local_offset` (in the jiggling joint's frame) with the joint at `joint_matrix`
// and its root at `root_matrix` (nullptr: model space): the offset is clamped to the cone, turned into
// the aim transformation's rotation and its cone angle.
template <typename Real>
JiggleOutput<Real> evaluateJiggle(const JiggleSettings<Real>& settings, const Real local_offset[3], const Real* joint_matrix,
                                  const Real* root_matrix);

// out = a + fraction * (b - a), as (1 - fraction) a + fraction b; exactly a at 0 and b at 1. Offsets
// are blended in the joint's frame, where the cone is convex.
template <typename Real>
void blendJiggleOffset(const Real a[3], const Real b[3], Real fraction, Real out[3]);

// The talk's cone constraint on a point q in the jiggling joint's frame: when q is outside the cone, it
// is moved along the segment from the rest point to q onto the cone's surface (the smallest root of the
// talk's A t^2 + B t + C = 0, then bisected to the last bit so clamping again changes nothing). Points
// inside are returned unchanged, bit for bit. Returns whether q moved.
template <typename Real>
bool clampJiggleToCone(const JiggleSettings<Real>& settings, const Real q[3], Real out[3]);

// Angle of direction q (joint frame) from the aim axis, and the cone's half-angle in q's azimuth, degrees.
template <typename Real>
void jiggleConeAngle(const JiggleSettings<Real>& settings, const Real q[3], Real* angle_deg, Real* clamp_deg);

// The aim transformation for a jiggle point q and the root's up vector `up`, both in the joint's frame:
// the rotation taking the frame [aim, v, w] (w = aim x up, v = w x aim) to [u, v', w'] for u = q / |q|.
// Identity (exactly) when q is the rest point or zero; the shortest arc from the aim to u when u or the
// aim lies within 1e-6 (sine) of the up vector.
template <typename Real>
void jiggleAimRotation(const JiggleSettings<Real>& settings, const Real q[3], const Real up[3], Real out[4]);

// The rigid part of a joint matrix: its translation, and the rotation nearest its axes (columns
// normalized, X negated for a mirrored frame, then the polar factor) as a unit quaternion, as
// rigbake's decomposeTrs reads a TRS out of a matrix. `scale` (optional) gets the scale along each
// rotated axis (negative on X for a mirrored frame).
template <typename Real>
void jiggleRigidFrame(const Real* matrix, Real translation[3], Real rotation[4], Real* scale = nullptr);

extern template struct JiggleResetJob<float>;
extern template struct JiggleResetJob<double>;
extern template struct JiggleJob<float>;
extern template struct JiggleJob<double>;

}  // namespace rigbake::runtime
