// Reads what `rigbake validate` checks in a baked glTF beyond the plain Character: every skinned
// primitive's JOINTS_n/WEIGHTS_n exactly as stored (skin-local indices, zero-weight slots kept), the
// packed carrier attributes of docs/packed-influences.md reassembled into PackedInfluences, the muscle
// joint nodes described by their extras {"rigbake": {...}} (pipeline/bake.h), and the structural
// problems found on the way (each with a glTF JSON pointer). It never throws for a problem it can
// report: a validator collects every issue instead of stopping at the first.
#pragma once

#include "formats/gltf_document.h"
#include "pipeline/baked_file.h"

namespace rigbake {

BakedFileData readBakedFileData(const LoadedCharacter& loaded);

}  // namespace rigbake
