#include "app/bake_job.h"
#include "core/file_name.h"

#include <chrono>

#include "anatomy/placement.h"
#include "anatomy/retarget.h"
#include "core/error.h"
#include "formats/gltf_write.h"
#include "formats/jiggle_json.h"
#include "formats/muscle_json.h"
#include "formats/packed_file.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"
#include "pipeline/rom.h"

namespace rigbake::app {
namespace {

class Stopwatch {
 public:
  // Seconds since the last lap (or the start).
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return seconds;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Placed on the character, read as the file gives them, or read against their own character and
// retargeted onto this one.
MuscleSet muscleSetOf(const BakeRequest& request, const Presets& presets, const ResolvedCharacter& target,
                      const MusclePreset& preset) {
  const Character& body = target.loaded.character;
  if (request.muscles.empty()) return placeMuscles(body, target.landmarks, preset, Sides::kBoth);
  if (request.muscles_from.path.empty()) return readMuscleJson(request.muscles, body, target.landmarks, preset);
  const ResolvedCharacter from = loadCharacter(request.muscles_from, presets);
  const MuscleSet source = readMuscleJson(request.muscles, from.loaded.character, from.landmarks, preset);
  return retargetMuscles(source, from.loaded.character, from.landmarks, body, target.landmarks, preset, request.muscles);
}

// The bake's regions, creases, jiggles and hits, from the request's presets.
BakeOptions bakeOptionsOf(const BakeRequest& request, const Presets& presets, const ResolvedCharacter& resolved,
                          const MuscleSet& muscles) {
  const Character& character = resolved.loaded.character;
  BakeOptions options = request.options;
  if (!request.regions.empty()) {
    const RegionPreset region_preset = readRegionPreset(presetFile(presets.directory, "regions", request.regions));
    options.regions = resolveBodyRegions(character, resolved.landmarks, region_preset);
    options.creases = resolveCreases(character, resolved.landmarks, region_preset.creases);
  }
  if (!request.jiggle.empty()) {
    options.jiggles = resolveJiggles(readJigglePreset(presetFile(presets.directory, "jiggle", request.jiggle)), character.skeleton,
                                     &resolved.landmarks, &muscles);
  } else if (!request.hits.empty()) {
    failOption("hits", "needs a jiggle preset: hits kick jiggle joints");
  }
  if (!request.hits.empty()) options.hits = readHits(request.hits);
  if (request.springs_only && request.jiggle.empty()) failOption("springs_only", "needs a jiggle preset");
  options.progress = request.progress;
  return options;
}

}  // namespace

BakeOutputs bakeJob(const BakeRequest& request, const Presets& presets) {
  BakeOutputs out;
  Stopwatch clock;
  reportProgress(request.progress, "loading the character");
  const MusclePreset preset = readMusclePreset(presetFile(presets.directory, "muscles", request.preset));
  out.character = loadCharacter(request.character, presets, request.notes);
  Character& character = out.character.loaded.character;
  const LandmarkSet& landmarks = out.character.landmarks;
  out.timings.load = clock.lap();
  // The range-of-motion clips join the character's own in memory only, so the weight rounding and the
  // deformation figures see them, but the written file does not hold them (docs/rom.md).
  RomPreset rom_preset;  // outlives `rom`, whose clips point at their specs in it
  RomResult rom;
  if (!request.rom.empty()) {
    rom_preset = readRomPreset(presetFile(presets.directory, "rom", request.rom));
    rom = buildRom(character, landmarks, rom_preset);
    appendMeasureOnlyClips(&character, rom);
  }
  reportProgress(request.progress, request.muscles.empty() ? "placing the muscles" : "reading the muscles");
  MuscleSet muscles = muscleSetOf(request, presets, out.character, preset);
  if (!request.muscles_character.empty()) muscles.character = request.muscles_character;
  const BakeOptions options = bakeOptionsOf(request, presets, out.character, muscles);
  out.jiggles = static_cast<int>(options.jiggles.size());
  out.hits = static_cast<int>(options.hits.size());
  out.timings.place = clock.lap();

  BakeOptions baked_motion = options;
  if (request.springs_only) baked_motion.jiggles.clear();
  out.bake = bakeCharacter(character, muscles, baked_motion, &out.timings.bake);
  clock.lap();

  reportProgress(request.progress, "writing the files");
  out.legs = legCoverage(character, landmarks, muscles);
  // Spring bones go where a VRM runtime simulates them; another file has nowhere to put them.
  out.vrm_springs = !options.jiggles.empty() && isVrmDocument(*out.character.loaded.document);
  if (request.springs_only && !out.vrm_springs)
    failOption("springs_only", request.character.path + " is not a VRM, so there is nowhere to put spring bones");
  BakedFile file = writeBakedFile(*out.character.loaded.document, character, out.bake, isBinaryGltfPath(request.output),
                                  out.vrm_springs ? options.jiggles : std::vector<JiggleSetup>{});
  out.animation_bytes = file.animation_bytes;
  out.input_animation_bytes = file.input_animation_bytes;
  out.vrm_constrained_muscles = file.vrm_constrained_muscles;
  BakeStatsInputs stats;
  stats.character_file = fileNameOf(request.character.path);
  stats.output_file = fileNameOf(request.output);
  stats.character = &character;
  stats.bake = &out.bake;
  stats.file = &file;
  stats.legs = &out.legs;
  stats.rom = request.rom.empty() ? nullptr : &rom;
  out.stats_json = bakeStatsJson(stats);
  std::vector<PackedInfluences> packed;
  for (const BakedPart& part : out.bake.parts) packed.push_back(part.packed);
  if (request.packed) out.packed = encodePackedFile(packed);
  out.muscles_json = muscleJson(out.bake.muscles, character.skeleton, preset.name);
  out.model = std::move(file.bytes);
  out.timings.write = clock.lap();
  return out;
}

}  // namespace rigbake::app
