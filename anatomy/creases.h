// Creases: where a bending joint folds skin onto skin (inner elbow, armpit, back of the knee, groin).
// Plain skinning collapses there; a muscle rig that only keeps the body's volume can leave the fold as
// it was (issue 29: "collapse left as it was"). The crease contact figures
// (pipeline/crease_contact.h) measure, at each clip's peak bend, how close the opposing skin comes and
// how much of it passes through. Creases are data (presets/regions/*.json, "creases"): each names the
// landmarks whose skin lies on either side of the fold, the two landmarks whose joints' turn is the
// bend, and how far from the fold's joint the skin is measured.
#pragma once

#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/landmarks.h"

namespace rigbake {

struct CreaseRule {
  std::string name;  // e.g. "elbow"; sided creases become elbow_l and elbow_r
  bool sided = false;
  // Landmarks (side-relative when sided) owning the skin on each side of the fold: a vertex is on a
  // side when its strongest input joint is owned by one of them (anatomy/body_regions.h's ownership).
  std::vector<std::string> proximal, distal;
  // The bend: the turn of bend_distal's joint relative to bend_proximal's since the bind pose.
  std::string bend_proximal, bend_distal;
  // The skin measured lies within radius_fraction * |radius_to - radius_from| of `near` at bind.
  std::string near, radius_from, radius_to;
  double radius_fraction = 0.0;
  std::string pointer;  // JSON pointer in the preset, for messages
};

struct Crease {
  std::string name;  // with _l / _r for sided creases
  int proximal_joint = -1, distal_joint = -1;  // the bend's joints
  double radius = 0.0;  // scene units
  // Per mesh part (Character::meshes order, every part), the vertices on each side of the fold.
  std::vector<std::vector<int>> proximal, distal;
};

// Every crease whose landmarks the character resolves and that has skin on both sides, in preset order
// (left before right).
std::vector<Crease> resolveCreases(const Character& character, const LandmarkSet& landmarks,
                                   const std::vector<CreaseRule>& rules);

}  // namespace rigbake
