// The RIGBAKE_muscle_rig glTF extension (docs/extensions/RIGBAKE_muscle_rig.md, JSON Schema in
// presets/schemas/RIGBAKE_muscle_rig.schema.json): the muscle rig as data, so that an engine or a
// player evaluates the muscle joints from the skeleton at run time (runtime/muscle_rig.h) instead of
// playing sampled channels. Written by the bake, read back by validate and the tests.
#pragma once

#include <string>
#include <vector>

#include "anatomy/character.h"
#include "anatomy/muscle_set.h"
#include "pipeline/baked_file.h"
#include "pipeline/jiggle.h"
#include "runtime/muscle_rig.h"

namespace tinygltf {
class Model;
}

namespace rigbake {

inline constexpr const char* kMuscleRigExtension = "RIGBAKE_muscle_rig";
inline constexpr int kMuscleRigExtensionVersion = 1;

// One jiggle as the extension stores it (node indices in the written file).
struct RigJiggle {
  std::string name;
  int node = -1;       // the jiggling joint's node
  int parent_node = -1;
  int root_node = -1;  // whose frame gives the up vector
  JiggleSetup setup;   // settings; joint/muscle/root indices are not written
};

// What the bake writes: for every muscle its skinned joint's node and, when written, its helper
// nodes (base, tip, driver); the rig's joints as nodes of the file's skeleton.
struct MuscleRigNodes {
  std::vector<int> skinned;                  // per muscle
  std::vector<std::vector<int>> helpers;     // per muscle: empty, or base, tip, driver
};

// Adds the extension to the model (root extensions, extensionsUsed; not required: a viewer that does
// not know it plays the file as plain glTF, the skinned joints resting where the input skin puts them).
void addMuscleRigExtension(tinygltf::Model* model, const Skeleton& skeleton, const MuscleSet& muscles,
                           const runtime::MuscleRig<double>& rig, const MuscleRigNodes& nodes,
                           const std::vector<RigJiggle>& jiggles);

// The extension of a loaded file, on that file's skeleton: the rig with joint indices of
// character.skeleton, each muscle's name and skinned joint. `present` is false when the file has none;
// `problems` lists what is malformed (each "pointer: message"), and then the rig is not usable.
using LoadedMuscleRig = FileMuscleRig;  // pipeline/baked_file.h
LoadedMuscleRig readMuscleRigExtension(const tinygltf::Model& model, const Character& character);

}  // namespace rigbake
