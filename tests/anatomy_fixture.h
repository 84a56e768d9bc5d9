// Loads characters and the shipped presets the way the CLI does, for tests of the anatomy stages.
#pragma once

#include <string>

#include "anatomy/landmarks.h"
#include "anatomy/placement.h"
#include "formats/gltf_document.h"
#include "formats/preset_json.h"
#include "test_support.h"

namespace rigbake::test {

inline std::string presetsDir() { return sourceDir() + "/presets"; }

struct Resolved {
  Character character;
  LandmarkSet landmarks;
};

// Landmarks of `character` from the shipped naming maps and rules (or `forced`).
inline Resolved resolveWithShippedPresets(Character character, const NamingMap* forced = nullptr) {
  static const std::vector<NamingMap> maps = readNamingMaps(presetsDir() + "/skeletons");
  static const LandmarkRules rules = readLandmarkRules(presetsDir() + "/landmarks.json");
  Resolved resolved;
  resolved.character = std::move(character);
  LandmarkInputs inputs;
  inputs.maps = &maps;
  inputs.rules = &rules;
  inputs.forced_map = forced;
  resolved.landmarks = resolveLandmarks(resolved.character, inputs);
  return resolved;
}

inline Resolved resolveShipped(const std::string& path, const NamingMap* forced = nullptr) {
  return resolveWithShippedPresets(loadCharacter(path).character, forced);
}

// The sample's skeleton with every joint at or below a JO*UpLeg1 cut off (no meshes, no clips): a
// character without legs.
inline Character withoutLegs(const Character& character) {
  const Skeleton& skeleton = character.skeleton;
  std::vector<int> new_index(skeleton.size(), -1);
  Skeleton cut;
  for (int j = 0; j < skeleton.size(); ++j) {
    bool under_leg = false;
    for (int a = j; a >= 0; a = skeleton.parents[a]) under_leg |= skeleton.names[a].find("UpLeg") != std::string::npos;
    if (under_leg) continue;
    new_index[j] = cut.size();
    cut.names.push_back(skeleton.names[j]);
    cut.parents.push_back(skeleton.parents[j] < 0 ? -1 : new_index[skeleton.parents[j]]);
    cut.nodes.push_back(skeleton.nodes[j]);
    cut.bind_world.push_back(skeleton.bind_world[j]);
    cut.rest_local.push_back(skeleton.rest_local[j]);
    cut.root_parent_world.push_back(skeleton.root_parent_world[j]);
  }
  Character legless;
  legless.source = character.source;
  legless.skeleton = cut;
  return legless;
}

inline const MusclePreset& gowPreset() {
  static const MusclePreset preset = readMusclePreset(presetsDir() + "/muscles/gow_biped.json");
  return preset;
}

}  // namespace rigbake::test

#include <tiny_gltf.h>
#include <unistd.h>

#include <cstdio>

#include "formats/gltf_write.h"
#include "formats/sample_gltf.h"
#include "sample/sample_character.h"

namespace rigbake::test {

// A sample variant written once per test process to a temporary file, removed at exit.
struct SampleFileRemovedAtExit {
  std::string path;
  SampleFileRemovedAtExit(SampleVrm variant, bool upper_chest) {
    const char* suffix = variant == SampleVrm::kNone ? ".glb" : variant == SampleVrm::kVrm0 ? "-vrm0.vrm" : "-vrm1.vrm";
    path = "/tmp/rigbake-test-sample-" + std::to_string(getpid()) + (upper_chest ? "" : "-no-upper-chest") + suffix;
    SampleOptions options;
    options.vrm = variant;
    options.upper_chest = upper_chest;
    writeGltf(sampleToGltf(makeSampleCharacter(options)), path);
  }
  ~SampleFileRemovedAtExit() { std::remove(path.c_str()); }
};

// The built-in sample character written once per test process to a temporary GLB.
inline std::string sampleGlbPath(SampleVrm vrm = SampleVrm::kNone) {
  static const SampleFileRemovedAtExit plain(SampleVrm::kNone, true), vrm0(SampleVrm::kVrm0, true),
      vrm1(SampleVrm::kVrm1, true);
  return vrm == SampleVrm::kNone ? plain.path : vrm == SampleVrm::kVrm0 ? vrm0.path : vrm1.path;
}

// A VRM sample whose humanoid map has spine, chest and neck but no upperChest, as many VRM 0.x
// exports do (SampleOptions::upper_chest = false).
inline std::string sampleVrmWithoutUpperChestPath(SampleVrm vrm) {
  static const SampleFileRemovedAtExit vrm0(SampleVrm::kVrm0, false), vrm1(SampleVrm::kVrm1, false);
  return vrm == SampleVrm::kVrm1 ? vrm1.path : vrm0.path;
}

// The sample, then every shared asset (missing ones fail under CI=true, see requireAsset).
inline std::vector<std::string> sampleAndAssetPaths() {
  std::vector<std::string> paths = {sampleGlbPath()};
  for (const std::string& name : sharedAssetNames()) {
    std::string path = requireAsset(name);
    if (!path.empty()) paths.push_back(path);
  }
  return paths;
}

}  // namespace rigbake::test
