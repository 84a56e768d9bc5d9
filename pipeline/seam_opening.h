// Seam opening: how far apart skin vertices that share a bind position (mesh borders between glTF
// meshes, UV and material seams, hard edges) move when posed. Plain skinning of identical weights
// keeps them together exactly; a rig whose muscle weights differ on the two sides of a border opens a
// slit there when a muscle moves (issue 29: 5.4 mm on the Quaternius Soldier before the body was welded
// across its meshes, pipeline/body_surface.h). docs/deformation-quality.md.
#pragma once

#include <vector>

#include "anatomy/character.h"
#include "pipeline/deformation_quality.h"

namespace rigbake {

// The places where two or more skinned vertices (of any part) sit within `weld_tolerance` of each
// other at the bind pose (pipeline/weld.h), each as its (part index into `parts`, vertex) members.
struct SeamPlaces {
  std::vector<std::vector<std::pair<int, int>>> members;
};
SeamPlaces findSeamPlaces(const Character& character, const std::vector<MeasuredPart>& parts, double weld_tolerance);

// Per clip, the largest amount by which two vertices of one place move further apart than they are at
// the bind pose, over the clip's samples, skinned
// (linear blend, double precision) with the parts' input weights and with their rig weights; the rig's
// figure is measured with the muscles' skinned joints of the clip's frames. A place whose vertices carry
// the same weights, joint for joint, in a set opens by nothing in it and is not skinned. The same at
// any thread count.
std::vector<SeamOpening> measureSeamOpening(const std::vector<MeasuredPart>& parts, const Character& character,
                                            const SeamPlaces& places, const std::vector<MeasuredClip>& clips, int threads);

// Both of the above into `quality`, whose clips are `clips` in order: seam_places and each clip's seams.
void measureSeams(const Character& character, const std::vector<MeasuredPart>& parts, const std::vector<MeasuredClip>& clips,
                  double weld_tolerance, int threads, DeformationQuality* quality);

}  // namespace rigbake
