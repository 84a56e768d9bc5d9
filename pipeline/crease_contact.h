// Crease contact (issue 29, "measures that a fit cannot game"): where a joint bends, plain skinning
// folds the skin on one side of the crease into the skin on the other (the inner elbow, the armpit, the
// back of the knee, the groin). At a clip's peak bend this measures, for one skinning, how close the
// opposing skin comes and how much of it passes through: a rig that keeps the body's volume by blowing
// up a muscle elsewhere leaves these as plain skinning has them; one that fixes the collapse moves them
// apart. docs/deformation-quality.md ("Creases").
#pragma once

#include <Eigen/Core>
#include <vector>

#include "pipeline/deformation_quality.h"

namespace rigbake {

// The bend below which a clip does not count as folding a crease (radians, 20 degrees).
constexpr double kMinCreaseBend = 0.349065850398865915;

// The skin on one side of a crease: bind and posed positions and the posed unit normals.
struct CreaseSide {
  std::vector<Eigen::Vector3d> bind, posed, normal;
};

// Opposing skin: a vertex of one side and the nearest posed vertex of the other among those at least
// `min_bind_apart` from it at bind (skin that only meets across the fold's line is not opposing), whose
// normals face each other (dot below -0.3). `closest` is the least distance of such pairs; a vertex is
// `through` when it lies behind its opposing vertex's tangent plane, and `deepest` is the largest such
// depth. Both sides are tested against each other. The same result whatever the order of calls.
CreaseMethodContact creaseContact(const CreaseSide& proximal, const CreaseSide& distal, double min_bind_apart);

// The turn (radians) of the joint with skinning matrix `distal` relative to the one with `proximal`:
// the angle of the rotation between their rigid parts (0 at bind).
double relativeTurn(const Eigen::Affine3d& proximal, const Eigen::Affine3d& distal);

}  // namespace rigbake
