// Body regions for measuring how skinning keeps volume (docs/deformation-quality.md): shoulder, upper
// arm, elbow, forearm, chest, back and, where the skeleton has legs, the lower body. Regions are data
// (presets/regions/*.json): each rule picks the triangles whose strongest skin joint belongs to one of
// its landmarks, optionally near a landmark or on one side of a body plane. Rules are tried in file
// order and the first that takes a triangle keeps it; rules with the same name form one region.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/creases.h"
#include "anatomy/landmarks.h"

namespace rigbake {

struct RegionRule {
  std::string name;  // the region, e.g. "elbow"; sided regions become elbow_l and elbow_r
  bool sided = false;
  // Landmarks (side-relative names when sided): a triangle qualifies when its strongest joint is one
  // of their joints, or lies below one with no other landmark in between (the landmark "owns" it).
  std::vector<std::string> owners;
  // Optional: the triangle's centroid lies within radius_fraction * |radius_to - radius_from| of the
  // `near` landmark.
  std::string near;
  std::string radius_from, radius_to;
  double radius_fraction = 0.0;
  // Optional: "forward" or "back": the centroid lies in front of / behind the body's coronal plane
  // through the `facing_landmark`.
  std::string facing;
  std::string facing_landmark;
  std::string pointer;  // JSON pointer in the preset, for messages
};

struct RegionPreset {
  std::string name;
  std::string file;
  std::vector<RegionRule> rules;
  std::vector<CreaseRule> creases;  // for the crease contact figures (anatomy/creases.h)
};

struct BodyRegion {
  std::string name;  // with _l / _r for sided regions
  // Per skinned mesh part with positions (in Character::meshes order), indices into its triangles.
  std::vector<std::vector<int>> triangles;
  int triangleCount() const;
};

// Every region that has at least one triangle, in the order the preset first names them (left before
// right). Rules whose landmarks the character does not resolve take nothing.
// Per joint, the landmarks that own it: those resolved to the joint itself, else its nearest ancestor's.
std::vector<std::set<std::string>> landmarkOwners(const Skeleton& skeleton, const LandmarkSet& landmarks);

std::vector<BodyRegion> resolveBodyRegions(const Character& character, const LandmarkSet& landmarks,
                                           const RegionPreset& preset);

}  // namespace rigbake
