// Where a body region's loss beyond plain skinning comes from. SKIN_REGION_VOLUME_LOSS says that a
// region lost more under the rig than under the input skinning; on a coarse character one place can
// carry most of it (Female Casual's abdomen at 4 influences in Female_Run: 2.85 of its 3.42 points at
// one vertex of the region's border, whose row keeps 13 % of the right latissimus and drops a 5 %
// joint), and reverting rows by hand to find it misleads: a neighbour's rows can buy the volume back
// without being where it went. At the sample where the rig's change of the region peaks, each
// welded vertex's share of the difference between the two skinnings' volumes is, to first order,
//
//     c_v = 100 · ∇_v V(x̄) · (x_rig,v − x_plain,v) / V_bind   (points),  x̄ = (x_rig + x_plain) / 2,
//
// with V the region's closed piece (caps included: a border vertex moves its cap's centre too), so the
// c_v sum to the difference up to third-order terms (the volume is cubic in the positions; about the
// midpoint the second-order terms of each vertex's own move cancel). The place with the most negative
// c_v is reported. docs/deformation-quality.md, "Regions".
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "pipeline/influences.h"
#include "pipeline/skin_place.h"
#include "pipeline/skin_volume.h"

namespace rigbake {

// The place that takes the most of a region's volume under the rig against plain skinning at one
// sample. `at.found` is false when no vertex takes any (the rig loses nothing there at first order).
struct RegionLossPlace {
  SkinPlace at;
  double points = 0.0;              // -c_v of that place: points of the region's bind volume it takes (> 0)
  double first_order_points = 0.0;  // sum of c_v over the region: the rig's change minus plain's, to first order
  double difference_points = 0.0;   // the same difference measured exactly (both closed pieces' volumes)
  double time = 0.0;                // the sample, seconds into the clip
  // Where the pieces carry the weights as the bake made them before writing them (RegionPiece::full):
  // the rig's volume with the written weights minus with those, exactly (points; negative where the cut
  // to the written influence count and the 0.001 rounding lose volume). By default the fit keeps the
  // regions with the weights before the cut, so this is the part of the loss it could not see
  // (docs/deformation-quality.md, "Where a region loses it"). validate has only the written weights:
  // cut_measured stays false.
  bool cut_measured = false;
  double cut_points = 0.0;
};

// One part's closed piece of a region: the part's welded surface, the piece over it and both weight
// sets (the bind positions are the part's own, Character::meshes[mesh_part]).
struct RegionPiece {
  int mesh_part = -1;  // index into Character::meshes
  const VolumeSurface* surface = nullptr;
  const ClosedPatch* patch = nullptr;
  const InfluenceSet* input = nullptr;  // the input's weights (plain skinning)
  const InfluenceSet* rig = nullptr;    // the weights written
  const InfluenceSet* full = nullptr;   // the bake's weights before the cut and the rounding; null when unknown
};

// What regionLossPlace() reuses from call to call (one per thread): positions indexed by welded vertex,
// of which each call writes and reads only its region's.
struct RegionLossScratch {
  std::vector<Eigen::Vector3d> plain, rig, middle, gradient, full, plain_listed, rig_listed, full_listed;
  std::vector<int> needed;
};

// The place above for a region made of `pieces` (one per measured part of `character`) at one sample
// (`frame`, every joint's skin matrix), with the region's bind volume summed over the parts.
RegionLossPlace regionLossPlace(const Character& character, const std::vector<RegionPiece>& pieces,
                                const std::vector<Eigen::Affine3d>& frame, double bind_volume, double time,
                                RegionLossScratch* scratch);

// One phrase naming the place for bake's region line and validate's check, e.g. "2.85 points of it at
// vertex 449 of mesh 'Cylinder.005' (glTF mesh 0, primitive 0; bind position -0.313 2.695 0.032)";
// empty when nothing was found.
std::string regionLossPlaceText(const RegionLossPlace& place);

}  // namespace rigbake
