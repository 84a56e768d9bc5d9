// Fitting the muscles' set-driven response to the character's own motion so that the skin keeps its
// volume (docs/muscle-model.md, "Fitted response"). The skin's displacement is linear in each muscle's
// response keys (offsets and across-fibre scale at full compression, the longest stretch and a quarter turn
// of twist either way), so Gauss-Newton on the linearized volumes is a small least-squares problem,
// in the spirit of Dem Bones (Le and Deng, "Smooth Skinning Decomposition with Rigid Bones", SIGGRAPH
// Asia 2012), which solves helper joints from example poses: here the joints are given and their
// set-driven keys are solved.
#pragma once

#include <string>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/fit_pose_choice.h"
#include "pipeline/pose.h"
#include "pipeline/progress.h"
#include "runtime/muscle_rig.h"

namespace rigbake {

struct ResponseFitOptions {
  // Poses fitted, chosen from every clip's sample times by chooseFitPoses(). Measured
  // (docs/muscle-model.md, "Poses"): 64 give the mannequin's figures of 160 within 0.01 points
  // (ArmRaise +0.28 -> +0.29 %) at 40 % of the fit's cost.
  int max_poses = 64;
  // How many of the clips' frames each fitted pose stands for (the bake sets it: the frames, up to
  // prior_poses, over the poses taken). The prior is weighed against the poses times this.
  double pose_weight = 1.0;
  int prior_poses = 160;
  // Levenberg-Marquardt steps (each re-linearizes the volumes). Measured on the mannequin: after five
  // the figures move by 0.02 points or less.
  int iterations = 6;
  // Told of each pass over the poses as it starts: the pass that measures the fixed pieces, then
  // iterations + 1 Levenberg-Marquardt passes (the last only measures).
  ProgressReport progress;
  // Marquardt's lambda (x the diagonal of the normal equations) before the first step, which is
  // taken at a third of it. Measured on the mannequin: from 0.3 the first three steps overshoot
  // (objective 3.1 -> 1,243, 1,131, 396: the volumes are cubic in the skin's positions and the step
  // thins stretched muscles to half at once) and are taken back; from 20 every step is kept.
  double initial_damping = 20.0;
  // Residual weights. Volumes are fractions of their bind volume; the prior is on amplitudes (1 = the
  // talk's response), scaled by how far the poses drive each key.
  double body_weight = 30.0;
  double region_weight = 30.0;
  double prior_weight = 0.05;
  // The body's row at each pose targets, instead of no change, the volume that the skin no fitted
  // muscle moves loses there (that piece closed by caps; 0 where it keeps or gains), but no more than
  // spared_input_share of the input skinning's whole-body loss there. The legs of a preset without leg
  // muscles lose volume in a run; a row that asked the arms and torso to make it up swelled them there,
  // so they swelled in every pose where their muscles shorten as in a run (Female Casual's elbow flexion
  // +1.23 % against plain skinning's -1.80 %, its shoulder abduction +1.61 % against -2.42 %). The share
  // keeps the goal in reach where nearly all the skin is out of reach (RobotExpressive, whose
  // body is rigid: sparing the whole loss left the rig 0.06 points behind plain skinning). Growth there
  // stays the row's to hold (targeting it too gives the mannequin's ArmRaise +0.48 % against +0.28 %,
  // plain +0.78 %). docs/deformation-quality.md, "The body's row spares the skin no muscle moves".
  bool spare_unreached_losses = true;
  double spared_input_share = 0.5;
  // A region is only pushed back when it leaves [min(input, 0) - margin, max(input, 0) + gain], the
  // input skinning's own change widened: muscles need not undo what the rig does not make worse, and
  // a flexed arm may swell where its muscles bulge. A region within region_band of an edge is in the
  // step's model (as a one-sided row) before it crosses it.
  double region_margin = 0.005;
  double region_gain = 0.3;
  double region_band = 0.01;
  // The skin a muscle drives (its mean move along the normal against the input skinning, as the
  // figures take it) may go in by at most compressed_in_share x body height while the muscle is
  // compressed by skin_min_compression or more, and by at most stretch_hollow_share x body height
  // while it is stretched: a compressed muscle does not deflate, a stretched one does not hollow the
  // skin, at every fitted pose. skin_weight: per metre beyond the floor on a body kReferenceBodyHeight
  // tall (per body height: the fit is the same in any unit); a muscle within
  // skin_band_share x body height of its floor is in the step's model.
  double skin_weight = 1000.0;
  double compressed_in_share = 0.0003;
  double skin_min_compression = 0.15;
  double stretch_hollow_share = 0.0008;
  double skin_band_share = 0.0005;
  // Smoothness (issue 29's "lumps"): per fitted pose, the root mean square over the fitted muscles'
  // vertices of L(d) . n, the umbrella Laplacian of the rig's move d against the input skinning along the
  // normal (the quantity the roughness figure takes, pipeline/surface_figures.h), times smoothness_weight
  // per metre of a body kReferenceBodyHeight tall, against the body's volume change at body_weight. 0 (the default): no such term. It trades
  // volume for smoothness on every character measured, differently per mesh (the Laplacian grows with
  // the square of the edge length): docs/deformation-quality.md, "The fit's smoothness term".
  double smoothness_weight = 0.0;
  // The roughness cap (issue 29's roughness goal as a constraint; `bake --fit-roughness-cap`): 0 (the
  // default) for none, else a ratio c >= 1. At each fitted pose, with p the input skinning's roughness
  // rise there (the figure, inputRoughnessRise()) and f the figures' floor (kRoughnessFloorPerHeight x
  // body height), each fitted vertex's |L x . n| may exceed the input skinning's there by at most
  // tau = c max(p, f) - p: a pair of hinges per vertex at roughness_cap_weight per metre of a body
  // kReferenceBodyHeight tall / sqrt(fitted vertices), in the step's model within roughness_cap_band x tau
  // of their bound. So over the fitted vertices the rig's rise stays within c times the input's; the
  // volume rows get what the cap leaves. docs/deformation-quality.md, "The roughness cap".
  double roughness_cap = 0.0;
  double roughness_cap_weight = 30000.0;
  double roughness_cap_band = 0.25;
  // Which volume the body's row keeps (issue 29's "measures a fit cannot game"): false, the signed volume,
  // in which skin pushed into a fold counts twice; true, the occupied one's gradient: at each fitted pose
  // the skin inside other skin under the starting (the talk's) response earns the row nothing, so
  // swelling into a fold does not pay (the row's value stays the signed volume). docs/deformation-quality.md,
  // "The fit on the occupied volume".
  bool occupied_volume = false;
  // Bounds on the amplitudes. Compression: [min_compression_fraction x the talk's, max_amplitude x
  // min(1, 4 x the talk's)] (nearer rest than a quarter of the talk's compression, the bound falls to 0
  // with the talk's amplitude: no spike of a bulge where the clips barely shorten a muscle);
  // stretch: [0, max_stretch_amplitude] and no thinner across the fibre than min_stretch_scale (a
  // stretched muscle thins, never swells); twist: [-min_twist_amplitude, max_twist_amplitude] (a twist
  // may ease a bulge a little).
  double max_amplitude = 4.0;
  double min_compression_fraction = 0.0;
  double max_stretch_amplitude = 20.0;
  double min_stretch_scale = 0.5;
  double max_twist_amplitude = 1.5;
  double min_twist_amplitude = 0.0;
  // A corrective's keys: [-max, max] x its offset (the preset's bulge vector), either way.
  double max_corrective_amplitude = 4.0;
  // The regions at every frame (`bake --fit-regions every-frame`; docs/deformation-quality.md, "Every
  // region at every frame"): the bake cuts the weights to the written influence count and rounds them
  // before the fit, so that the fit keeps the regions on the weights written, and after the fit the
  // checked poses (every clip frame the fit did not take) are measured: up to region_check_poses of them
  // where a region is furthest below its dead zone, by more than region_check_tolerance (a fraction of
  // its bind volume), join the fitted poses and the fit goes on from where it was, at most
  // region_check_rounds times; the regions' rows weigh every_frame_region_weight instead of
  // region_weight. Not with occupied_volume (its exposure is per vertex and pose: every frame's would
  // not fit in memory).
  bool every_frame_regions = false;
  int region_check_rounds = 2;
  int region_check_poses = 16;
  double region_check_tolerance = 0.0025;
  double every_frame_region_weight = 100.0;
};

struct ResponseFitReport {
  int poses = 0;
  int parameters = 0;
  int fitted_parts = 0;
  // Root mean square of the whole-body volume change over the fitted poses, before and after.
  double body_rms_before = 0.0;
  double body_rms_after = 0.0;
  int added_poses = 0;  // checked poses that joined the fit
};

// Fits the response of every part with fit[m] set (parts of the same name on both sides share one
// set of keys, mirrored); the others keep theirs and are evaluated as they are. `parts` holds each
// skinned part's input weights and its muscle-added full-precision weights (muscle m is joint
// skeleton.size() + m); every part's carrier must be chosen. `fit_poses` are the poses to fit over,
// `check_poses` those to check the regions at afterwards with every_frame_regions (else unused), on
// `threads` threads (pipeline/parallel.h; the result is the same at any count).
ResponseFitReport fitMuscleResponses(const Character& character, const std::vector<BodyRegion>& regions,
                                     const std::vector<MeasuredPart>& parts, const std::vector<Pose>& fit_poses,
                                     const std::vector<Pose>& check_poses, const std::vector<char>& fit, MuscleSet* muscles,
                                     const ResponseFitOptions& options = {}, int threads = 1);

// Where a pose puts the fitted parts' drivers (fit[m] set): each one's clamped length ratio and its
// twist in quarter turns, the quantities the response keys are read at. For chooseFitPoses().
std::vector<double> driverFeatures(const runtime::MuscleRig<double>& rig, const MuscleSet& muscles,
                                   const std::vector<char>& fit, const Pose& pose);

// True when `part` still has the response its preset gives it (defaultResponse()): what
// `bake --response auto` fits. Curves that were fitted before or edited by hand are kept.
bool hasPresetResponse(const MusclePart& part);

}  // namespace rigbake
