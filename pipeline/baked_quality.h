// Deformation quality of a baked file, for `rigbake validate` (docs/deformation-quality.md): the same
// figures `bake --stats` gives, measured from the file alone. The baked rig skins with the file's own
// weights and the muscle joints as an engine evaluates them (the RIGBAKE_muscle_rig extension, or the
// sampled channels); the input skinning is the same weights with every muscle joint's weight handed
// back to its carrier joint: the plain skinning the bake started from, after its pruning and rounding
// (which `bake --stats` measures separately, in mm). Also renders the report's pictures.
#pragma once

#include <string>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy/character.h"
#include "anatomy/landmarks.h"
#include "pipeline/checks.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/render.h"

namespace rigbake {

struct BakedQualityOptions {
  int picture_size = 200;  // pixels, each of the three panels (square)
  bool pictures = true;
  int threads = 1;  // frames measured on this many threads (0: one per core); the same figures at any count
  // The character the file was baked from, or nullptr. Given, the input skinning is its own weights
  // (its skinned mesh parts in order, joints matched by name), so the regions and plain skinning are
  // the bake's; else the file's weights with each muscle's handed back to its carrier, which at 4 and
  // 7 influences are close to the input's but not its own. VALIDATE_INPUT_MISMATCH when the parts,
  // vertices or joints are not the file's.
  const Character* input = nullptr;
};

// Needs the file's muscle nodes (skinned ones with a carrier joint) and the landmarks; without them
// the result says why it did not measure.
BakedQuality measureBakedQuality(const Character& character, const LandmarkSet& landmarks, const RegionPreset& regions,
                                 const BakedFileData& file, const BakedQualityOptions& options = {});

}  // namespace rigbake
