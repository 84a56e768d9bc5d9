// Fuzz target: the anatomy presets (docs/presets.md): each input is read as a muscle preset, a naming
// map, landmark rules and a region preset, as --preset, --map and presets/ give them.
#include <cstddef>
#include <cstdint>

#include "formats/preset_json.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rigbake::fuzz::inputFile("preset.json", data, size);
  rigbake::fuzz::expectCleanResult([&] { rigbake::readMusclePreset(path); });
  rigbake::fuzz::expectCleanResult([&] { rigbake::readNamingMap(path); });
  rigbake::fuzz::expectCleanResult([&] { rigbake::readLandmarkRules(path); });
  rigbake::fuzz::expectCleanResult([&] { rigbake::readRegionPreset(path); });
  return 0;
}
