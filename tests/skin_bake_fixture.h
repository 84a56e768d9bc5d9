// The bake the skin tests measure variants with: the character placed with the God of War preset on both
// sides and baked with the shipped body regions, every figure measured (as `bake --stats` does): with
// `options` as given, or at 10 influences with `response` and the fit's smoothness term at `smoothness`
// (`--fit-smoothness`).
#pragma once

#include "anatomy/body_regions.h"
#include "anatomy_fixture.h"
#include "formats/preset_json.h"
#include "pipeline/bake.h"

namespace rigbake::test {

inline BakeResult bakeWithBodyRegions(const Resolved& r, BakeOptions options) {
  static const RegionPreset regions = readRegionPreset(presetsDir() + "/regions/body.json");
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, gowPreset(), Sides::kBoth);
  options.regions = resolveBodyRegions(r.character, r.landmarks, regions);
  return bakeCharacter(r.character, muscles, options);
}

inline BakeResult bakeWithBodyRegions(const Resolved& r, ResponseMode response = ResponseMode::kAuto, double smoothness = 0.0) {
  BakeOptions options;
  options.influences = 10;
  options.response = response;
  options.fit.smoothness_weight = smoothness;
  return bakeWithBodyRegions(r, options);
}

}  // namespace rigbake::test
