// Fuzz target: the character loader (glTF JSON, GLB and VRM bytes; the loader tells them apart by
// content) and the landmark resolution every command runs on a loaded character.
#include <cstddef>
#include <cstdint>

#include "anatomy/landmarks.h"
#include "formats/gltf_document.h"
#include "formats/preset_json.h"
#include "fuzz/fuzz_support.h"

namespace {

struct ShippedPresets {
  std::vector<rigbake::NamingMap> maps = rigbake::readNamingMaps(RIGBAKE_PRESET_DIR "/skeletons");
  rigbake::LandmarkRules rules = rigbake::readLandmarkRules(RIGBAKE_PRESET_DIR "/landmarks.json");
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const ShippedPresets presets;
  const std::string path = rigbake::fuzz::inputFile("character.glb", data, size);
  rigbake::fuzz::expectCleanResult([&] {
    const rigbake::LoadedCharacter loaded = rigbake::loadCharacter(path);
    rigbake::LandmarkInputs inputs;
    inputs.maps = &presets.maps;
    inputs.rules = &presets.rules;
    rigbake::resolveLandmarks(loaded.character, inputs);
  });
  return 0;
}
