// Rounding the pruned weights to the talk's 0.001 precision so that the skin moves as little as
// possible away from the full-precision skin over the character's own animation.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "pipeline/influences.h"

namespace rigbake {

// Skin matrices (joint world * inverse bind) of every joint at one sampled frame.
using SkinFrame = std::vector<Eigen::Affine3d>;

// Like quantizeInfluences(set, 1000): every weight is rounded down or up to a multiple of 0.001 and
// each vertex sums to exactly 1000. Of the roundings that do so, each vertex takes the one whose
// linear-blend skinning error, summed in squares over `frames`, is smallest (largest-remainder rounding
// wins ties, and is what an empty `frames` gives); vertices whose error then comes within half of the
// worst vertex's take the one with the smallest worst frame instead, so that the worst vertex is as
// good as such roundings allow. Canonical slot order as in influences.h.
QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames);
// The same on `threads` threads (pipeline/parallel.h): the result does not depend on the count.
QuantizedInfluences quantizeForMotion(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                      const std::vector<SkinFrame>& frames, int threads);

// quantizeForMotion() of several mesh parts skinned by the same frames, in `parts` order, with the
// moments of the joints the parts share summed once. Pass 2 refines by the worst vertex of all the
// parts (the character's), so a body cut into other meshes rounds the same; one part alone rounds as
// the single-set call does.
struct MotionPart {
  const InfluenceSet* set = nullptr;
  const std::vector<Eigen::Vector3d>* bind_positions = nullptr;
};
std::vector<QuantizedInfluences> quantizeForMotion(const std::vector<MotionPart>& parts, const std::vector<SkinFrame>& frames,
                                                   int threads);

// The same roundings computed the direct way, frame by frame for every vertex (slow: O(frames n^2) per
// vertex). quantizeForMotion() must give exactly these; the tests compare the two.
QuantizedInfluences quantizeForMotionReference(const InfluenceSet& set, const std::vector<Eigen::Vector3d>& bind_positions,
                                               const std::vector<SkinFrame>& frames);

}  // namespace rigbake
