// Skin weights for the muscles' skinned joints (the talk: "+26 skinned joints"). Each muscle takes a
// share, around its origin-insertion segment and smoothed over the welded mesh surface, of the weight
// its carrier joint has there: the carrier is the joint the skinned joint rides, so at rest response a
// vertex moves exactly as the input skinning moves it, and the bind pose is unchanged.
// docs/muscle-weights.md.
#pragma once

#include <cstdint>
#include <vector>

#include "anatomy/muscle_set.h"
#include "pipeline/body_surface.h"
#include "pipeline/surface_graph.h"
#include "pipeline/influences.h"

namespace rigbake {

struct MuscleWeightOptions {
  double peak_share = 1.0;         // at the muscle's axis a muscle takes this share of its carrier's weight
  double max_total_share = 1.0;    // all muscles together take at most this share of a joint's weight
  // Only skin on the muscle's own side takes its share: from none where the vertex's direction from the
  // axis makes cosine facing_start with the muscle's up axis to all of it at facing_full.
  double facing_start = -0.2;
  double facing_full = 0.5;
  // A piece of the welded surface that the input moves rigidly (every vertex held by one and the same
  // joint alone: armour, props, a segmented body's segments) takes no muscle share: plain skinning keeps
  // its shape and volume exactly, so a muscle could only deform what the artist made rigid. Measured on
  // eight characters (docs/muscle-weights.md, "Rigid pieces"): Quaternius Cyberpunk's roughest clip
  // 2.76x -> 2.38x plain skinning's, the KayKit mannequin's 38x -> 3.2x, no count of issue 29 worse.
  bool rigid_pieces_stay_rigid = true;
  // Over this fraction of the origin-insertion segment at each end (its tendons) a muscle's share fades
  // to 0, and none reaches past either end: the skin there moves with the bone the tendon attaches to,
  // which the skinned joint, riding its carrier, does not follow. 0 (the default): the round-ended
  // falloff alone. Measured at 0.2 on eight characters (docs/muscle-weights.md, "Tendons", not the
  // default): the mannequin's forearm skin at full ElbowFlexion 3.54 -> 0.07 points beyond plain
  // skinning, 88 -> 101 of 128 clips within 1.2x plain skinning's roughness, 5 -> 7 characters with no
  // region beyond 1 point; but 11 -> 9 arm clips halved, and the mannequin's ElbowFlexion -0.13 % and
  // ArmRaise +0.56 % miss its targets (dual quaternions' -0.06 %, half of plain skinning's +0.78 %).
  double tendon_fraction = 0.0;
  int smoothing_iterations = 4;    // Laplacian (umbrella) passes over the welded surface
  double smoothing_lambda = 0.5;   // step of each pass
  // Most influences a vertex may end with (the talk's God of War Ragnarök maximum): only the strongest
  // muscles at a vertex take weight there, so the bake's pruning to 10 loses nothing.
  int max_influences = 10;
  // A corrective takes its share only where the skin blends the joints on either side of its span:
  // with x the vertex's weight on its insertion joint and the joints below it, the share is scaled by
  // min(1, corrective_blend_gain * 4 x (1 - x)), so all of it from x = 0.15 to 0.85 (gain 2), none
  // where one side holds the vertex alone. That is where plain skinning stretches a web.
  double corrective_blend_gain = 2.0;
};

// Radius of the weight falloff around the segment: the part's weight_radius when set, else
// 0.02 * body height + 0.15 * rest length (a thicker belly for a longer muscle), widened to reach the
// skin when the segment lies deeper than that (stocky or cartoon bodies): at least the segment's
// distance to the nearest skinned vertex plus half the base radius.
double muscleWeightRadius(const MusclePart& part, double body_height);
// One muscle per task on `threads` (each radius is a minimum over the vertices: the same at any count).
std::vector<double> muscleWeightRadii(const Character& character, const MuscleSet& muscles, double body_height,
                                      int threads = 1);

// The joints a muscle spans: the path from its origin joint to its insertion joint in the hierarchy
// `parents` (spannedHierarchy(): the body's, which need not be the rig's).
std::vector<int> spannedJoints(const std::vector<int>& parents, const MusclePart& part);

// How much of its carrier's weight each muscle may take at each welded vertex, before the influence
// budget: peak_share * (1 - x^2)^2 * side * tendon, x = distance to the segment / radius, side the
// smoothstep of facing, tendon the fade over each end (see MuscleWeightOptions), smoothed over the
// surface; none on a rigid piece
// (MuscleWeightOptions::rigid_pieces_stay_rigid, rigidPieces()). Only the shares above 0 are kept (a
// muscle reaches a small part of the body): welded vertex w's are muscle[k] with share[k] for k in
// [first[w], first[w + 1]), muscles ascending. A corrective's share has the blend factor
// (MuscleWeightOptions::corrective_blend_gain) in place of the side and the tendons: its offset moves
// all of the blended skin one way.
struct MuscleShares {
  std::vector<std::uint32_t> first;  // welded vertices + 1
  std::vector<int> muscle;
  std::vector<double> share;
  // Per welded vertex: 1 on a piece the input moves rigidly (rigidPieces()), which takes no share; all 0
  // without MuscleWeightOptions::rigid_pieces_stay_rigid.
  std::vector<char> rigid;
};
// Muscles on `threads` threads (pipeline/parallel.h); the same shares at any count.
MuscleShares muscleShares(const Skeleton& skeleton, const MeshPart& part, const SurfaceGraph& surface,
                          const MuscleSet& muscles, const std::vector<double>& radii, const MuscleWeightOptions& options = {},
                          int threads = 1);

// Per welded vertex of `surface` (over `part`'s vertices): 1 where its connected piece of the welded
// surface is moved rigidly by the input, every vertex of it held by one and the same joint alone (that
// joint's weight within 0.001 of the vertex's whole weight), else 0.
std::vector<char> rigidPieces(const MeshPart& part, const SurfaceGraph& surface);

// Each part's carrier: among the joints it spans, the one whose weight its share field covers most,
// summed over the whole skinned body (lowest joint index on a tie). A part whose carrier is already
// set (part.carrier >= 0) keeps it. `shares` are muscleShares() over body.skin(character).
void chooseCarrierJoints(const Character& character, const BodySurface& body, const MuscleShares& shares,
                         MuscleSet* muscles);

// `base` are the part's influences; muscle m becomes skeleton joint muscle_joints[m] and takes
// share * limit of the weight the vertex has on muscle m's carrier joint (limit keeps the muscles on
// one joint within max_total_share). Returns the influences with the muscles added (more slots per
// vertex), each vertex still summing to its old sum. Every part must have its carrier chosen. The same
// result on any number of threads.
InfluenceSet addMuscleInfluences(const InfluenceSet& base, const SurfaceGraph& surface, const MuscleShares& shares,
                                 const MuscleSet& muscles, const std::vector<int>& muscle_joints,
                                 const MuscleWeightOptions& options = {}, int threads = 1);

}  // namespace rigbake
