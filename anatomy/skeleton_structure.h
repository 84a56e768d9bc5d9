// The structural fallback: when no naming map fits, find the spine chain from the pelvis to the head
// and the two arm and leg chains from the hierarchy and the rest-pose geometry alone.
#pragma once

#include <map>
#include <string>

#include "anatomy/character.h"

namespace rigbake {

// Canonical landmark name -> joint index, for the landmarks structure can tell (pelvis, spine_l5,
// spine_t12, chest, neck, head, and per side clavicle, upper_arm, forearm, hand, and when both legs are
// found upper_leg, lower_leg, foot and toe). Missing entries
// are left for derivation. Returns an empty map when the skeleton has no recognisable humanoid shape.
std::map<std::string, int> landmarksFromStructure(const Skeleton& skeleton);

// "l", "r" or "" from side tokens in a joint name (Left, _L, .l, L__4_, ...).
std::string sideFromName(const std::string& name);

}  // namespace rigbake
