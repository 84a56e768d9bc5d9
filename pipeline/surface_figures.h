// The skin's smoothness under four skinnings, and the centre-of-rotation yardstick's volume (issue 29:
// "lumps where the fit pushed volume"). Volume is the one figure the response fit optimises; a fit can
// keep it by pushing skin out in one place and in at another, which shows as roughness. So for each
// clip, at its most deformed samples (surfaceSamples()), the skin is posed by plain skinning (the input's
// weights), dual quaternions, centres of rotation (pipeline/centre_of_rotation.h) and the rig, and
// each welded vertex's roughness, |L(v) . n(v)| with L the umbrella Laplacian (mean of the one-ring
// minus the vertex; Taubin 1995) and n the area-weighted normal, is compared with its bind value. The
// figure is the 95th percentile of that rise over the skin that moves: vertices that blend two joints
// (each at least 0.05) or carry at least 0.05 of a muscle. Beside it, the same skin's strain: the 95th
// percentiles of |posed / bind - 1| of its triangles' areas and their edges' lengths, which roughness
// does not see (skin stretched within its plane). docs/deformation-quality.md.
#pragma once

#include <vector>

#include "anatomy/character.h"
#include "anatomy/creases.h"
#include "pipeline/deformation_quality.h"

namespace rigbake {

// A clip's samples the figures are taken at, ascending: where the rig's, the input skinning's and dual
// quaternions' whole-body volume change peak (`figures`, measured on every sample), and the last. Every
// sample would cost four skinnings each: on Quaternius Cyberpunk (22 clips, 559 samples) that was five
// times the rest of the bake.
std::vector<size_t> surfaceSamples(const MeasuredClip& clip, const ClipQuality& figures);

// The input skinning's roughness rise at each of `frames` (skinning matrices of the skeleton's joints):
// the figure above, its 95th percentile over the skin that moves, unfloored. The response fit's
// roughness cap (pipeline/response_fit.h) bounds the rig by it at the fitted poses, so both read one
// definition of the figure.
std::vector<double> inputRoughnessRise(const Character& character, const std::vector<MeasuredPart>& parts, int skeleton_joints,
                                       double body_height, int threads, const std::vector<SkinFrame>& frames);

// Fills each clip's `surface` and `creases` in `quality` (clips in the same order). Muscle joints are
// those at or above `skeleton_joints` in the parts' rig weights. `body_height` (scene units) sets the
// weld tolerance (bodyWeldTolerance()) and the roughness floor (kRoughnessFloorPerHeight). Each crease (anatomy/creases.h) is
// measured at the sample of each clip where its bend peaks, when that is at least kMinCreaseBend
// (pipeline/crease_contact.h). The same figures at any thread count.
void measureSurfaceFigures(const Character& character, const std::vector<MeasuredPart>& parts,
                           const std::vector<MeasuredClip>& clips, int skeleton_joints, double body_height, int threads,
                           DeformationQuality* quality, const std::vector<Crease>& creases = {});

}  // namespace rigbake
