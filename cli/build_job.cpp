#include "cli/build_job.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy/placement.h"
#include "anatomy/retarget.h"
#include "cli/common.h"
#include "cli/validation_run.h"
#include "formats/atomic_file.h"
#include "formats/build_manifest.h"
#include "formats/gltf_bake.h"
#include "formats/json_text.h"
#include "formats/muscle_json.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"
#include "pipeline/bake.h"
#include "pipeline/rom.h"

namespace rigbake::cli {

const char* jobStatusName(JobStatus status) {
  switch (status) {
    case JobStatus::kBuilt: return "built";
    case JobStatus::kUpToDate: return "up-to-date";
    case JobStatus::kFailed: return "failed";
  }
  return "failed";
}

SharedPresets loadSharedPresets(const std::string& presets_dir) {
  SharedPresets shared;
  shared.directory = presets_dir;
  shared.maps = readNamingMaps(presets_dir + "/skeletons");
  shared.rules = readLandmarkRules(presets_dir + "/landmarks.json");
  shared.regions = presets_dir + "/regions/body.json";
  return shared;
}

JobOutcome failedJob(const BuildCharacter& character, const std::string& error) {
  JobOutcome outcome;
  outcome.name = character.name;
  outcome.status = JobStatus::kFailed;
  outcome.error = error;
  return outcome;
}

namespace {

struct Loaded {
  LoadedCharacter character;
  LandmarkSet landmarks;
};

// `vrm`: the character's "vrm" (-1 as the file is, 0 or 1 as bake --vrm).
Loaded loadResolved(const std::string& path, const SharedPresets& presets, int vrm) {
  LoadOptions options;
  if (vrm >= 0) options.vrm = vrm == 1 ? VrmTarget::kVrm1 : VrmTarget::kVrm0;
  Loaded loaded;
  loaded.character = loadCharacter(path, options);
  LandmarkInputs inputs;
  inputs.maps = &presets.maps;
  inputs.rules = &presets.rules;
  loaded.landmarks = resolveLandmarks(loaded.character.character, inputs);
  return loaded;
}

// Everything that decides a character's outputs, hashed: its files' bytes, the preset, the muscle
// source, the options and the rigbake version.
std::string inputsHash(const BuildManifest& manifest, const BuildCharacter& character) {
  std::vector<std::string> files = {character.input, character.preset};
  if (!character.muscles.empty()) files.push_back(character.muscles);
  if (!character.rom.empty()) files.push_back(character.rom);
  if (!character.muscles_from.empty()) {
    const BuildCharacter& source = manifest.characters[characterIndex(manifest, character.muscles_from)];
    files.push_back(source.input);
    files.push_back(characterOutputs(manifest, source).muscles);
  }
  return contentHash(files, std::string("rigbake ") + RIGBAKE_VERSION + " influences " +
                                std::to_string(character.influences) + " gltf_weights " +
                                gltfWeightsName(character.gltf_weights) + " muscles_from " + character.muscles_from +
                                (character.rom.empty() ? std::string() : " rom") + " muscle_motion " +
                                muscleMotionName(character.muscle_motion) + (character.helper_joints ? " helper_joints" : "") +
                                (character.vrm >= 0 ? " vrm " + std::to_string(character.vrm) : std::string()) +
                                " response " + responseModeName(character.response));
}

// Validates the written model against its muscle file and writes the three reports; returns how many
// error-severity checks failed.
int validateCharacter(const CharacterOutputs& out, const BuildCharacter& character, const SharedPresets& presets, int threads) {
  ValidationRequest request;
  request.threads = threads;  // the job's share of the cores, as its bake
  request.baked = out.model;
  request.muscles = out.muscles;
  request.preset = character.preset;
  request.presets.presets_dir = presets.directory;
  request.rom = character.rom;
  const Report report = validateBakedFile(request);
  writeReports(report, {out.report_json, out.report_junit, out.report_html}, threads);
  int failed = 0;
  for (const CheckResult& check : report.checks)
    failed += check.status == CheckStatus::kFail && check.severity == Severity::kError;
  return failed;
}

// The content hash of the character's five outputs as they are on disk, or "" when one is missing or
// unreadable. The stamp records it, so that outputs replaced after the stamp was written (by a run
// killed between its renames, another build into the same folder, a hand edit) are never up to date.
std::string outputsHash(const CharacterOutputs& out) {
  try {
    return contentHash({out.model, out.muscles, out.report_json, out.report_junit, out.report_html}, "outputs");
  } catch (const Error&) {
    return "";
  }
}

void writeStamp(const CharacterOutputs& out, const std::string& hash, const JobOutcome& outcome) {
  nlohmann::json stamp = {{"hash", hash},
                          {"outputs", outcome.status == JobStatus::kFailed ? std::string() : outputsHash(out)},
                          {"status", jobStatusName(outcome.status)},
                          {"error", outcome.error},
                          {"checks_failed", outcome.checks_failed}};
  writeFileAtomically(out.stamp, jsonText(stamp) + "\n");
}

// A rebuild first removes the stamp, so that a run killed after replacing any output leaves no stamp that
// calls the mix up to date.
void removeStamp(const CharacterOutputs& out) {
  std::error_code error;
  std::filesystem::remove(out.stamp, error);
  if (error) fail(errc::IO_WRITE_FAILED, out.stamp, "cannot remove the previous build stamp: " + error.message());
}

}  // namespace

namespace {

// The stamp a previous run left beside the character's outputs; discarded when missing or unreadable.
nlohmann::json readStamp(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nlohmann::json(nlohmann::json::value_t::discarded);
  return nlohmann::json::parse(in, nullptr, false);
}

JobOutcome outcomeFromStamp(const BuildCharacter& character, const std::string& path, const nlohmann::json& stamp) {
  if (stamp.is_discarded()) return failedJob(character, "not built (no readable " + path + ")");
  if (!stamp.is_object()) return failedJob(character, "unreadable build stamp " + path);
  JobOutcome outcome;
  outcome.name = character.name;
  std::string status = stamp.value("status", "failed");
  outcome.status = status == "built" ? JobStatus::kBuilt : status == "up-to-date" ? JobStatus::kUpToDate : JobStatus::kFailed;
  outcome.error = stamp.value("error", "");
  outcome.checks_failed = stamp.value("checks_failed", 0);
  return outcome;
}

}  // namespace

JobOutcome readJobOutcome(const BuildManifest& manifest, const BuildCharacter& character) {
  const std::string path = characterOutputs(manifest, character).stamp;
  return outcomeFromStamp(character, path, readStamp(path));
}

JobOutcome runCharacterJob(const BuildManifest& manifest, const BuildCharacter& character, const SharedPresets& presets,
                           bool force, int bake_threads) {
  const CharacterOutputs out = characterOutputs(manifest, character);
  std::string hash;
  try {
    hash = inputsHash(manifest, character);
    if (!force) {
      const nlohmann::json stamp = readStamp(out.stamp);
      JobOutcome previous = outcomeFromStamp(character, out.stamp, stamp);
      // Up to date only when the inputs are those stamped and so are the outputs, byte for byte.
      if (stamp.is_object() && stamp.value("hash", "") == hash && previous.status != JobStatus::kFailed) {
        const std::string outputs = outputsHash(out);
        if (!outputs.empty() && stamp.value("outputs", "") == outputs) {
          previous.status = JobStatus::kUpToDate;
          return previous;
        }
      }
    }
    createDirectories(out.directory);
    removeStamp(out);
    MusclePreset preset = readMusclePreset(character.preset);
    Loaded loaded = loadResolved(character.input, presets, character.vrm);
    const Character& body = loaded.character.character;
    MuscleSet muscles;
    if (!character.muscles.empty()) {
      muscles = readMuscleJson(character.muscles, body, loaded.landmarks, preset);
    } else if (!character.muscles_from.empty()) {
      const BuildCharacter& source = manifest.characters[characterIndex(manifest, character.muscles_from)];
      const std::string source_muscles_path = characterOutputs(manifest, source).muscles;
      Loaded from = loadResolved(source.input, presets, source.vrm);
      MuscleSet source_muscles =
          readMuscleJson(source_muscles_path, from.character.character, from.landmarks, preset);
      muscles = retargetMuscles(source_muscles, from.character.character, from.landmarks, body, loaded.landmarks, preset,
                                source_muscles_path);
    } else {
      muscles = placeMuscles(body, loaded.landmarks, preset, Sides::kBoth);
    }
    muscles.character = character.name + ".glb";
    // "rom": measured on, not written (docs/rom.md).
    if (!character.rom.empty())
      appendMeasureOnlyClips(&loaded.character.character, buildRom(body, loaded.landmarks, readRomPreset(character.rom)));
    BakeOptions options;
    options.influences = character.influences;
    options.gltf_weights = character.gltf_weights;
    options.threads = bake_threads;
    options.motion = character.muscle_motion;
    options.helper_joints = character.helper_joints;
    options.response = character.response;
    const RegionPreset region_preset = readRegionPreset(presets.regions);
    options.regions = resolveBodyRegions(body, loaded.landmarks, region_preset);
    options.creases = resolveCreases(body, loaded.landmarks, region_preset.creases);
    BakeResult bake = bakeCharacter(body, muscles, options);
    const BakedFile file = writeBakedFile(*loaded.character.document, body, bake, true, {});
    // The muscles as baked (carriers chosen, response fitted): what a retarget of this cast carries on.
    OutputBatch outputs;
    outputs.add(out.muscles, muscleJson(bake.muscles, body.skeleton, preset.name));
    outputs.add(out.model, file.bytes);
    outputs.commit();
    JobOutcome outcome;
    outcome.name = character.name;
    outcome.status = JobStatus::kBuilt;
    outcome.checks_failed = validateCharacter(out, character, presets, bake_threads);
    writeStamp(out, hash, outcome);
    return outcome;
  } catch (const Error& error) {
    JobOutcome outcome = failedJob(character, error.what());
    try {
      createDirectories(out.directory);
      writeStamp(out, hash, outcome);
    } catch (const std::exception&) {
      // The failure itself is what the summary reports; a missing stamp only means a rebuild next time.
    }
    return outcome;
  } catch (const std::exception& error) {
    return failedJob(character, printableLine(std::string("INTERNAL: ") + error.what()));
  }
}

}  // namespace rigbake::cli
