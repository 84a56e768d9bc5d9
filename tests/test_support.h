// Shared test helpers: where the real characters are, and a loud failure when CI lacks them.
#pragma once

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

// The real characters the brief names. Under CI=true a missing file fails the test run.
inline const std::vector<std::string>& sharedAssetNames() {
  static const std::vector<std::string> kNames = {
      "CesiumMan.glb",
      "RobotExpressive.glb",
      "KayKit_Mannequin/manny_med_mod.gltf",
      "Quaternius_Cyberpunk_Character.glb",
      "Quaternius_ModularWomen_Soldier.glb",
  };
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
