// The batch build's plan as plain data: which characters to build, in which order (a character whose
// muscles are retargeted from another comes after it), which shard of a CI matrix each belongs to, and
// the Ninja graph that lets Ninja (or a distributed executor of Ninja graphs) schedule them.
#pragma once

#include <string>
#include <vector>

#include "pipeline/bake.h"
#include "pipeline/influences.h"

namespace rigbake {

struct BuildCharacter {
  std::string name;
  std::string input;         // path, already resolved against the manifest's directory
  std::string muscles_from;  // name of another character to retarget muscles from, or empty
  std::string muscles;       // a muscle JSON to use, or empty
  std::string preset;        // preset path for this character (manifest default when not given)
  int influences = 10;
  GltfWeights gltf_weights = GltfWeights::kMilli;
  std::string rom;           // ROM preset path to measure the bake and validation on too, or empty
  MuscleMotion muscle_motion = MuscleMotion::kRuntime;
  bool helper_joints = false;
  ResponseMode response = ResponseMode::kAuto;
  int vrm = -1;              // "vrm": VRM version to write (0 or 1, as rigbake bake --vrm), -1 as the input is
  // What `rigbake bake` does with --map, --regions, --jiggle, --hits, --vrm-springs-only, --fps,
  // --fit-poses, --fit-smoothness, --fit-volume, --stats and --packed-out (docs/build.md).
  std::string map;           // a naming map file (resolved) or a shipped map's name; empty: detected
  std::string regions;       // region preset file (resolved); empty: the shipped "body"
  std::string jiggle;        // jiggle preset file (resolved), or empty
  std::string hits;          // hit file (resolved), or empty; only with a jiggle
  bool vrm_springs_only = false;
  double fps = 0.0;
  int fit_poses = ResponseFitOptions{}.max_poses;
  double fit_smoothness = ResponseFitOptions{}.smoothness_weight;
  double fit_roughness_cap = ResponseFitOptions{}.roughness_cap;
  bool fit_occupied_volume = ResponseFitOptions{}.occupied_volume;  // "fit_volume": "occupied"
  bool fit_every_frame_regions = ResponseFitOptions{}.every_frame_regions;  // "fit_regions": "every-frame"
  bool stats = false;        // also write OUT/NAME/stats.json
  bool packed = false;       // also write OUT/NAME/NAME.rbpk
  std::string pointer;       // JSON pointer in the manifest, for messages
};

struct BuildManifest {
  std::string file;
  std::string directory;  // of the manifest; relative paths in it are resolved against this
  std::string preset;
  int influences = 10;
  GltfWeights gltf_weights = GltfWeights::kMilli;
  std::string rom;        // default ROM preset path, or empty
  MuscleMotion muscle_motion = MuscleMotion::kRuntime;
  bool helper_joints = false;
  ResponseMode response = ResponseMode::kAuto;
  int vrm = -1;
  std::string map, regions, jiggle, hits;  // the characters' defaults, as BuildCharacter's
  bool vrm_springs_only = false;
  double fps = 0.0;
  int fit_poses = ResponseFitOptions{}.max_poses;
  double fit_smoothness = ResponseFitOptions{}.smoothness_weight;
  double fit_roughness_cap = ResponseFitOptions{}.roughness_cap;
  bool fit_occupied_volume = ResponseFitOptions{}.occupied_volume;
  bool fit_every_frame_regions = ResponseFitOptions{}.every_frame_regions;
  bool stats = false, packed = false;
  std::string out;        // output root, resolved
  std::vector<BuildCharacter> characters;
};

// Index of the character named `name` in manifest.characters, or -1.
int characterIndex(const BuildManifest& manifest, const std::string& name);

// Characters in an order where every muscles_from source comes before its dependents (ties: manifest
// order). Throws Error MANIFEST_INVALID on an unknown or cyclic muscles_from, naming the pointer.
std::vector<int> buildOrder(const BuildManifest& manifest);

// The group of a character: the name of the character at the root of its muscles_from chain. A group
// is built on one shard so that a retarget always finds its source.
std::string buildGroup(const BuildManifest& manifest, int character);

// Whether a character belongs to shard `index` of `count` (0 <= index < count): groups are sorted by
// name and dealt round-robin, so the split is deterministic and every group lands on exactly one shard.
bool inShard(const BuildManifest& manifest, int character, int index, int count);

// Output paths of one character: OUT/NAME/NAME.glb, muscles.json, report.json, report.junit.xml,
// report.html, and the incremental-build stamp; with "stats" and "packed", stats.json and NAME.rbpk
// (empty paths otherwise).
struct CharacterOutputs {
  std::string directory, model, muscles, report_json, report_junit, report_html, stamp;
  std::string stats, packed;
  // Every output the character's run writes, the stamp aside, in a fixed order.
  std::vector<std::string> files() const;
};
CharacterOutputs characterOutputs(const BuildManifest& manifest, const BuildCharacter& character);

// The commands a Ninja file's rules run. They are command lines of the CLI, so cli/ writes them
// (pipeline/ knows no flags): each a shell command line, Ninja's `$name` standing for a character.
struct NinjaCommands {
  std::string written_by;  // the command that wrote the file, for its first comment line
  std::string character;   // builds the one character `$name`
  std::string summary;     // writes the build's summary from the characters' reports
};

// A Ninja file: one edge per character (commands.character), with its input, preset, muscle file,
// source character's muscles.json and the manifest (`manifest_path`) as inputs, and one edge for the
// summary (commands.summary).
std::string ninjaFile(const BuildManifest& manifest, const std::string& manifest_path, const NinjaCommands& commands);

// `text` as one single-quoted word of a POSIX shell command line (for NinjaCommands).
std::string shellWord(const std::string& text);

}  // namespace rigbake
