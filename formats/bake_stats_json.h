// The figures of one bake as JSON (`rigbake bake --stats` and --json; docs/output-contract.md): the
// deformation error of the rounded weights and where it peaks, the skin's bytes per vertex, the memory
// table of every layout, the volume figures, the leg coverage, the ROM clips measured on and the
// animation bytes.
#pragma once

#include <string>

#include "formats/gltf_bake.h"
#include "pipeline/bake.h"
#include "pipeline/leg_coverage.h"
#include "pipeline/rom.h"

namespace rigbake {

// Bytes per skinned vertex of the first baked part's skin: as the JOINTS_n/WEIGHTS_n written, and as
// the packed buffers (docs/packed-influences.md); 0 and 0 when nothing is skinned.
struct SkinBytesPerVertex {
  int gltf = 0;
  int packed = 0;
};
SkinBytesPerVertex skinBytesPerVertex(const BakeResult& bake);

// Nodes the file gains: each muscle's skinned joint, and its base, tip and driver with helper joints.
int jointsAdded(const BakeResult& bake);

struct BakeStatsInputs {
  std::string character_file;  // file names without directories, so the stats do not depend on where
  std::string output_file;     // the tool ran
  const Character* character = nullptr;  // as baked (the ROM clips appended)
  const BakeResult* bake = nullptr;
  const BakedFile* file = nullptr;
  const LegCoverage* legs = nullptr;
  const RomResult* rom = nullptr;  // the ROM clips measured on, or none
};

// The JSON text, indented by 2, ending in a newline.
std::string bakeStatsJson(const BakeStatsInputs& in);

}  // namespace rigbake
