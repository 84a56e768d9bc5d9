// Shared test helpers: where the real characters are, and a loud failure when CI lacks them.
#pragma once

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace rigbake::test {

inline std::string sharedAssetsDir() {
  const char* env = std::getenv("RIGBAKE_SHARED_ASSETS");
  return env ? env : RIGBAKE_SHARED_ASSETS;
}

inline std::string sourceDir() { return RIGBAKE_SOURCE_DIR; }

// This build tree's programs. The cases are compiled once, in the release tree, and the sanitizer tree
// links that same archive (tests/CMakeLists.txt): main.cpp, which each tree compiles itself, defines them.
extern const char* const kRigbakeCli;     // the CLI the cases run
extern const char* const kRuntimeLibrary;  // the runtime's shared library
extern const char* const kRuntimeCCheck;   // tests/c_api/runtime_c_check, a C program on that library

// The real characters the brief names. Under CI=true a missing file fails the test run.
// RIGBAKE_TEST_ASSETS=name,name,... narrows the list for a pass that only needs each code path once
// (scripts/test.sh's sanitizer pass); an unknown name fails, so a typo cannot empty the list.
inline const std::vector<std::string>& sharedAssetNames() {
  static const std::vector<std::string> kNames = [] {
    const std::vector<std::string> all = {
        "CesiumMan.glb",
        "RobotExpressive.glb",
        "KayKit_Mannequin/manny_med_mod.gltf",
        "Quaternius_Cyberpunk_Character.glb",
        "Quaternius_ModularWomen_Soldier.glb",
    };
    const char* subset = std::getenv("RIGBAKE_TEST_ASSETS");
    if (!subset || !*subset) return all;
    std::vector<std::string> chosen;
    std::string list = std::string(subset) + ",";
    for (size_t start = 0, comma; (comma = list.find(',', start)) != std::string::npos; start = comma + 1) {
      const std::string name = list.substr(start, comma - start);
      if (name.empty()) continue;
      if (std::find(all.begin(), all.end(), name) == all.end()) FAIL("RIGBAKE_TEST_ASSETS names an unknown asset: " << name);
      chosen.push_back(name);
    }
    return chosen;
  }();
  return kNames;
}

inline bool fileExists(const std::string& path) { return std::ifstream(path).good(); }

// Returns the full path, or "" (after WARN) outside CI when the asset is missing.
inline std::string requireAsset(const std::string& name) {
  std::string path = sharedAssetsDir() + "/" + name;
  if (fileExists(path)) return path;
  const char* ci = std::getenv("CI");
  if (ci && std::string(ci) == "true") FAIL("shared asset missing under CI: " << path);
  WARN("shared asset missing, check skipped outside CI: " << path);
  return "";
}

}  // namespace rigbake::test
