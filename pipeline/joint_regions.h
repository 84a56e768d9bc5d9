// Volume per joint region, the way issue 29 measured the rig from outside: the skin whose strongest
// input joint is one joint (a triangle whose three corners all have that joint strongest), its volume
// taken about that joint's posed origin, uncapped. The body regions (anatomy/body_regions.h) are
// closed by caps that move with their boundary, and the response fit keeps them; this figure is not
// fitted, so a fit that moves volume between neighbouring pieces of one region, or across a region's
// cap, shows here ("measures that a fit cannot game"). Measured on the mannequin before it was added:
// at full ElbowFlexion the forearm's piece lost 3.5 points more than plain skinning.
// docs/deformation-quality.md ("Joint regions").
#pragma once

#include <vector>

#include "anatomy/character.h"
#include "pipeline/deformation_quality.h"

namespace rigbake {

// Fewer triangles than this and a joint gets no region (a twist helper's sliver of skin).
constexpr int kMinJointRegionTriangles = 20;

// Per clip of `clips` (quality->clips in the same order), per joint region: at the sample where the rig
// loses the most beyond plain skinning, max(0, min(plain, 0) - rig) of the two volume changes against
// the bind pose (the rig's largest change when it loses nothing beyond plain). Fills
// quality->joint_regions and each clip's joint_regions. Samples on `threads` threads; the same at any
// count.
void measureJointRegions(const Character& character, const std::vector<MeasuredPart>& parts,
                         const std::vector<MeasuredClip>& clips, int threads, DeformationQuality* quality);

}  // namespace rigbake
