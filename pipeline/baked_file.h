// What formats/baked_gltf.h decodes from a baked file beyond the Character (the influences as stored,
// the muscle joint nodes, the RIGBAKE_muscle_rig extension, the jiggles baked into the clips), and the
// Khronos glTF-Validator's verdict: the inputs of `rigbake validate`'s checks (pipeline/checks.h) that
// formats/ fills. Plain data; no tinygltf type.
#pragma once

#include <string>
#include <vector>

#include "anatomy/muscle_set.h"
#include "pipeline/jiggle.h"
#include "pipeline/pack_influences.h"
#include "runtime/muscle_rig.h"

namespace rigbake {

// A skinned primitive's influences exactly as the file stores them, with skin-local joint indices.
struct FileSkinAttributes {
  int mesh_part = -1;   // index into Character::meshes
  std::string pointer;  // "/meshes/M/primitives/P"
  int skin_joint_count = 0;
  int slots = 0;                // 4 per JOINTS_n/WEIGHTS_n pair
  std::vector<int> joints;      // every slot, zero-weight ones too: joints[v * slots + k]
  std::vector<double> weights;  // as decoded (normalized integers mapped to [0, 1])
  bool has_packed = false;      // the _RIGBAKE_PACKED_* carrier attributes were present and decodable
  bool carries_packed = false;  // some _RIGBAKE_PACKED_* attribute is present, decodable or not
  PackedInfluences packed;      // skin-local indices; joint_count = skin_joint_count
};

// A muscle joint node the bake added, from its extras {"rigbake": {...}}.
struct FileMuscleNode {
  int node = -1;
  std::string name;
  std::string muscle;  // e.g. LeftBicep
  std::string role;    // base, tip, driver, skinned
  std::string origin_joint;
  std::string insertion_joint;
  std::string carrier_joint;  // "" when the file does not say
  double compression = 0.0;
  double stretch = 0.0;
};

struct FileIssue {
  std::string pointer;
  std::string message;
};

// A node that is one of the bake's muscle joints by its name (pipeline/bake.h muscleJointName(): the
// suffixes _muscleSkinned, _muscleBase, _muscleTip, _muscleDriver) or by its extras.rigbake: what is left
// of the rig when a tool that does not know rigbake drops the extension (gltfpack drops extras too,
// and keeps names).
struct FileMuscleJoint {
  int node = -1;
  std::string name;
  int animations_moving_it = 0;  // animations with a channel that targets the node
};

// A baked jiggle's angle from its animated direction and its cone's half-angle in that direction,
// degrees, at each sample time, as the bake recorded them in the animation's extras (the animated
// direction itself is no longer in the file once the jiggle replaced the channels).
struct JiggleSeries {
  std::string joint;
  std::string host;  // "joint" or "muscle"
  std::vector<double> angle_deg;
  std::vector<double> clamp_deg;
};

struct ClipJiggles {
  std::string clip;
  std::string pointer;  // "/animations/A/extras/rigbake"
  std::vector<double> times;
  std::vector<JiggleSeries> jiggles;
};

// A jiggle the extension leaves to the runtime (a default bake with --jiggle), on the loaded skeleton:
// setup.joint is the jiggling node's joint, setup.root its rootNode's (-1: model space), setup.name its
// name; axes, length and parameters as stored (not checked: jiggleSetupProblem says what is wrong).
struct FileJiggle {
  JiggleSetup setup;
  int parent = -1;  // parentNode's joint, -1: model space
  int muscle = -1;  // the rig muscle whose skinned node jiggles, -1 for a skeleton joint
  std::string pointer;  // "/extensions/RIGBAKE_muscle_rig/jiggles/i"
};

// The RIGBAKE_muscle_rig extension as read (formats/muscle_rig_extension.h): the rig in terms of the
// loaded skeleton's joints, and which joint each muscle's skinned node is.
struct FileMuscleRig {
  bool present = false;
  runtime::MuscleRig<double> rig;
  std::vector<std::string> names;
  std::vector<int> skinned_joint;
  std::vector<PartKind> kinds;
  std::vector<FileJiggle> jiggles;
  std::vector<std::string> problems;
};

struct BakedFileData {
  std::vector<FileSkinAttributes> skins;
  FileMuscleRig rig;
  std::vector<ClipJiggles> jiggles;
  std::vector<FileMuscleNode> muscle_nodes;
  std::vector<FileMuscleJoint> muscle_joints;  // by name or extras, in node order
  int animations = 0;                          // the file's animations
  std::vector<FileIssue> structure;  // structural problems found while reading
};

// The Khronos glTF-Validator's verdict on the file, when it ran.
struct ExternalValidation {
  bool ran = false;
  std::string skip_reason;
  int errors = 0;
  int warnings = 0;
  std::vector<FileIssue> issues;  // "CODE: message" per issue, errors first
};

}  // namespace rigbake
