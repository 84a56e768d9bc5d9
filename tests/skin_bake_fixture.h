// The bake the skin tests measure variants with: the character placed with the God of War preset on both
// sides and baked at 10 influences with the shipped body regions, every figure measured (as
// `bake --influences 10 --stats` does), with the fit's smoothness term at `smoothness` (`--fit-smoothness`).
#pragma once

#include "anatomy/body_regions.h"
#include "anatomy_fixture.h"
#include "formats/preset_json.h"
#include "pipeline/bake.h"

namespace rigbake::test {

inline BakeResult bakeWithBodyRegions(const Resolved& r, ResponseMode response = ResponseMode::kAuto, double smoothness = 0.0) {
  static const RegionPreset regions = readRegionPreset(presetsDir() + "/regions/body.json");
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, gowPreset(), Sides::kBoth);
  BakeOptions options;
  options.influences = 10;
  options.response = response;
  options.fit.smoothness_weight = smoothness;
  options.regions = resolveBodyRegions(r.character, r.landmarks, regions);
  return bakeCharacter(r.character, muscles, options);
}

}  // namespace rigbake::test
