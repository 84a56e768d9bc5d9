// Skin weights for the muscles' skinned joints (the talk: "+26 skinned joints"). Each muscle takes a
// share of the weight of the joints it spans, around its origin-insertion segment, so the bind pose is
// unchanged; the share is smoothed over the welded mesh surface. docs/muscle-model.md, "Weights".
#pragma once

#include <vector>

#include "anatomy/muscle_set.h"
#include "formats/surface_graph.h"
#include "pipeline/influences.h"

namespace rigbake {

struct MuscleWeightOptions {
  double peak_share = 0.5;         // at the muscle's axis a muscle takes this share of its joints' weight
  double max_total_share = 0.6;    // all muscles together take at most this share at any vertex
  int smoothing_iterations = 4;    // Laplacian (umbrella) passes over the welded surface
  double smoothing_lambda = 0.5;   // step of each pass
  // Most influences a vertex may end with (the talk's God of War Ragnarök maximum): only the strongest
  // muscles at a vertex take weight there, so the bake's pruning to 10 loses nothing.
  int max_influences = 10;
};

// Radius of the weight falloff around the segment: the part's weight_radius when set, else
// 0.02 * body height + 0.15 * rest length (a thicker belly for a longer muscle), widened to reach the
// skin when the segment lies deeper than that (stocky or cartoon bodies): at least the segment's
// distance to the nearest skinned vertex plus half the base radius.
double muscleWeightRadius(const MusclePart& part, double body_height);
std::vector<double> muscleWeightRadii(const Character& character, const MuscleSet& muscles, double body_height);

// The joints a muscle spans: the skeleton path from its origin joint to its insertion joint.
std::vector<int> spannedJoints(const Skeleton& skeleton, const MusclePart& part);

// `base` are the part's influences; muscle m becomes skeleton joint muscle_joints[m]. Returns the
// influences with the muscles added (more slots per vertex), each vertex still summing to its old sum.
// `radii` from muscleWeightRadii().
InfluenceSet addMuscleInfluences(const MeshPart& part, const InfluenceSet& base, const SurfaceGraph& surface,
                                 const Skeleton& skeleton, const MuscleSet& muscles,
                                 const std::vector<int>& muscle_joints, const std::vector<double>& radii,
                                 const MuscleWeightOptions& options = {});

}  // namespace rigbake
