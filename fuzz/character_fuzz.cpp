// Fuzz target: the character loader (glTF JSON, GLB and VRM bytes; the loader tells them apart by
// content) and the landmark resolution every command runs on a loaded character; a VRM 0.x is also
// converted to VRM 1.0 as `bake --vrm 1` does.
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
    // A VRM 0.x also goes through `bake --vrm 1`'s conversion (formats/vrm0_to_vrm1.cpp).
    if (loaded.character.vrm_version == "0.x") {
      rigbake::LoadOptions vrm1;
      vrm1.vrm = rigbake::VrmTarget::kVrm1;
      rigbake::resolveLandmarks(rigbake::loadCharacter(path, vrm1).character, inputs);
    }
  });
  return 0;
}
