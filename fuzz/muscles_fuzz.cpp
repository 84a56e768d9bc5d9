// Fuzz target: muscle JSON files (docs/muscle-json.md), read for the small sample mannequin of the seed
// corpus, as `rigbake bake --muscles` reads them (with the shipped preset for a positions-only file).
#include <cstddef>
#include <cstdint>

#include "anatomy/landmarks.h"
#include "formats/gltf_document.h"
#include "formats/muscle_json.h"
#include "formats/preset_json.h"
#include "fuzz/fuzz_support.h"

namespace {

struct Mannequin {
  rigbake::LoadedCharacter loaded = rigbake::loadCharacter(RIGBAKE_FUZZ_CHARACTER);
  rigbake::LandmarkSet landmarks;
  rigbake::MusclePreset preset = rigbake::readMusclePreset(RIGBAKE_PRESET_DIR "/muscles/gow_biped.json");
  Mannequin() {
    const std::vector<rigbake::NamingMap> maps = rigbake::readNamingMaps(RIGBAKE_PRESET_DIR "/skeletons");
    const rigbake::LandmarkRules rules = rigbake::readLandmarkRules(RIGBAKE_PRESET_DIR "/landmarks.json");
    rigbake::LandmarkInputs inputs;
    inputs.maps = &maps;
    inputs.rules = &rules;
    landmarks = rigbake::resolveLandmarks(loaded.character, inputs);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Mannequin mannequin;
  const std::string path = rigbake::fuzz::inputFile("muscles.json", data, size);
  rigbake::fuzz::expectCleanResult(
      [&] { rigbake::readMuscleJson(path, mannequin.loaded.character, mannequin.landmarks, mannequin.preset); });
  return 0;
}
