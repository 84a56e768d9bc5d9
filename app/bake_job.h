// One bake as a job: load the character and resolve its landmarks, place (or read, or retarget) the
// muscles, build the ROM clips to measure on, resolve the body regions and jiggles, bake, and make the
// bytes of every output. `rigbake bake`, each character of `rigbake build`, the benches and the tests
// all bake through bakeJob, so they cannot drift apart. Nothing is written or printed here: the caller
// writes the bytes (all or none, formats/atomic_file.h) and says what it likes about the figures.
#pragma once

#include <string>
#include <vector>

#include "app/character.h"
#include "formats/bake_stats_json.h"
#include "formats/gltf_bake.h"
#include "pipeline/bake.h"
#include "pipeline/leg_coverage.h"
#include "pipeline/progress.h"

namespace rigbake::app {

struct BakeRequest {
  CharacterSource character;
  // Where the model will be written: .glb/.vrm make it GLB, anything else glTF JSON; its file name is
  // the stats' "output".
  std::string output;
  std::string preset = "gow_biped";  // muscle preset: a file, or a name under presets/muscles/
  std::string muscles;               // a muscle JSON to bake; empty: place the preset on the character
  // When given, `muscles` belongs to this character and is retargeted onto `character`
  // (anatomy/retarget.h), as build's muscles_from does.
  CharacterSource muscles_from;
  std::string muscles_character;  // MuscleSet::character of the muscles baked; empty: the file's name
  std::string rom;                // ROM preset (a file or a name) to measure on too, not written; empty: none
  std::string regions = "body";   // body regions for the volume figures (a file or a name); empty: none
  std::string jiggle;             // jiggle preset (a file or a name); empty: no jiggle
  std::string hits;               // hit file kicking the jiggles; needs `jiggle`
  bool springs_only = false;      // VRM: the jiggles as spring bones only, not baked into the clips
  // Also make the packed influences file. Only when asked: a character whose mesh parts pack with
  // different index sizes has no single file (encodePackedFile() throws INTERNAL), yet bakes.
  bool packed = false;
  // influences, gltf_weights, fps, threads, response, fit, motion, helper_joints, measure_quality;
  // its regions, creases, jiggles, hits and progress are filled in from the fields above.
  BakeOptions options;
  ProgressReport progress;  // told of each stage as it starts; may be empty
  NoteReport notes;         // told of the character's notes as it is loaded; may be empty
};

// Wall-clock seconds of the job's stages, for bench/ (never in an output).
struct BakeJobTimings {
  double load = 0.0;   // reading the file and resolving its landmarks
  double place = 0.0;  // presets, muscles, ROM clips, regions and jiggles
  BakeTimings bake;
  double write = 0.0;  // the model's bytes and the other outputs
};

struct BakeOutputs {
  // The bytes of every output.
  std::string model;         // GLB, VRM or glTF JSON, as BakeRequest::output names it
  std::string packed;        // the packed influences file (formats/packed_file.h) when BakeRequest::packed
  std::string stats_json;    // the figures (formats/bake_stats_json.h)
  std::string muscles_json;  // the muscles as baked (carriers chosen, response fitted)
  // What was baked, for a caller to report on.
  ResolvedCharacter character;  // as baked: ROM clips appended (measure-only); its notes too
  BakeResult bake;
  long long animation_bytes = 0;        // the written model's animation buffers
  long long input_animation_bytes = 0;  // the same in the input
  int vrm_constrained_muscles = 0;      // VRM 1.0: muscles whose base and tip carry VRMC_node_constraint
  bool vrm_springs = false;             // the jiggles were also written as VRM spring bones
  int jiggles = 0;                      // jiggle joints resolved (baked unless springs_only)
  int hits = 0;
  LegCoverage legs;
  BakeJobTimings timings;
};

// Throws the stages' Errors (a missing file, an unresolved landmark, ...) and InvalidOption naming a
// BakeRequest or BakeOptions field: "hits" and "springs_only" without a jiggle, "springs_only" on a
// file that is not a VRM, "influences" and "fps" out of range.
BakeOutputs bakeJob(const BakeRequest& request, const Presets& presets);

}  // namespace rigbake::app
