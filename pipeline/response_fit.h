// Fitting the muscles' set-driven response to the character's own motion so that the skin keeps its
// volume (docs/muscle-model.md, "Fitted response"). The skin's displacement is linear in each muscle's
// response keys (offsets and across-fibre scale at full compression, full stretch and a quarter turn
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
#include "pipeline/pose.h"

namespace rigbake {

struct ResponseFitOptions {
  int max_poses = 160;      // poses sampled evenly from every clip's sample times
  int iterations = 6;       // Levenberg-Marquardt steps (each re-linearizes the volumes)
  // Residual weights. Volumes are fractions of their bind volume; the prior is on amplitudes (1 = the
  // talk's response), scaled by how far the poses drive each key.
  double body_weight = 30.0;
  double region_weight = 30.0;
  double prior_weight = 0.05;
  // A region is only pushed back when it leaves [min(input, 0) - margin, max(input, 0) + gain], the
  // input skinning's own change widened: muscles need not undo what the rig does not make worse, and
  // a flexed arm may swell where its muscles bulge.
  double region_margin = 0.005;
  double region_gain = 0.3;
  // Bounds on the amplitudes. Compression: [min_compression_fraction x the talk's, max_amplitude] (a
  // compressed muscle never pulls the skin in); stretch: [0, max_stretch_amplitude] (a stretched muscle thins, never swells);
  // twist: [-min_twist_amplitude, max_twist_amplitude] (a twist may ease a bulge a little).
  double max_amplitude = 4.0;
  // A compression key keeps at least this fraction of the talk's response at its ratio, so that a
  // compressed muscle bulges out even where the body's volume alone would rather it did not. Measured
  // on the mannequin (ArmRaise whole body / the compressed rear deltoid's mean skin move): 0 gives
  // +0.63 % / -1.3 mm (its neighbours' thinning pulls its skin in), 0.2 gives +0.76 % / -0.7 mm,
  // 0.5 gives +0.94 % / > 0 (the input skinning: +0.78 %).
  double min_compression_fraction = 0.2;
  double max_stretch_amplitude = 4.0;
  double max_twist_amplitude = 1.5;
  double min_twist_amplitude = 0.0;
};

struct ResponseFitReport {
  int poses = 0;
  int parameters = 0;
  int fitted_parts = 0;
  // Root mean square of the whole-body volume change over the fitted poses, before and after.
  double body_rms_before = 0.0;
  double body_rms_after = 0.0;
};

// Fits the response of every part with fit[m] set (parts of the same name on both sides share one
// set of keys, mirrored); the others keep theirs and are evaluated as they are. `parts` holds each
// skinned part's input weights and its muscle-added full-precision weights (muscle m is joint
// skeleton.size() + m); every part's carrier must be chosen. `poses` are the poses to fit over, on
// `threads` threads (pipeline/parallel.h; the result is the same at any count).
ResponseFitReport fitMuscleResponses(const Character& character, const std::vector<BodyRegion>& regions,
                                     const std::vector<MeasuredPart>& parts, const std::vector<Pose>& poses,
                                     const std::vector<char>& fit, MuscleSet* muscles,
                                     const ResponseFitOptions& options = {}, int threads = 1);

// True when `part` still has the response its preset gives it (defaultMuscleResponse()): what
// `bake --response auto` fits. Curves that were fitted before or edited by hand are kept.
bool hasPresetResponse(const MusclePart& part);

}  // namespace rigbake
