// Fuzz target: build manifests (docs/build.md), read as `rigbake build` reads them. Relative paths in
// a manifest resolve against the fuzzer's private folder, where nothing but the manifest exists.
#include <cstddef>
#include <cstdint>

#include "formats/build_manifest.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rigbake::fuzz::inputFile("manifest.json", data, size);
  rigbake::fuzz::expectCleanResult([&] { rigbake::readBuildManifest(path, RIGBAKE_PRESET_DIR); });
  return 0;
}
