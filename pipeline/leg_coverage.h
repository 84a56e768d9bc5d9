// Whether the muscles cover the legs the clips move. The default preset (gow_biped, the talk's upper
// body) has no leg muscles, so on a character whose clips bend its hips and knees the bake leaves them
// to plain skinning and its figures show it (hip flexion -4.46 % on a modular character, issue 29):
// the bake says so in one line, naming a preset that covers them, rather than leaving the user to find
// out from the volume table.
#pragma once

#include <string>

#include "anatomy/character.h"
#include "anatomy/landmarks.h"
#include "anatomy/muscle_set.h"

namespace rigbake {

struct LegCoverage {
  bool legs = false;     // upper and lower leg landmarks ride joints of their own
  bool covered = false;  // some muscle part spans a hip or knee (its origin-insertion path holds a leg joint)
  double largest_turn_deg = 0.0;  // the most a hip or knee joint turns from rest, over every clip's samples
  std::string clip;               // where
  std::string joint;              // which joint
};

LegCoverage legCoverage(const Character& character, const LandmarkSet& landmarks, const MuscleSet& muscles);

// A bend of a hip or knee past this (degrees) is motion that plain skinning visibly deflates.
constexpr double kLegTurnWorthMuscles = 20.0;

}  // namespace rigbake
