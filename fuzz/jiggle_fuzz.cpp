// Fuzz target: jiggle presets and hit files (docs/jiggle.md): each input is read as both, as --jiggle
// and --hits read them.
#include <cstddef>
#include <cstdint>

#include "formats/jiggle_json.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rigbake::fuzz::inputFile("jiggle.json", data, size);
  rigbake::fuzz::expectCleanResult([&] { rigbake::readJigglePreset(path); });
  rigbake::fuzz::expectCleanResult([&] { rigbake::readHits(path); });
  return 0;
}
