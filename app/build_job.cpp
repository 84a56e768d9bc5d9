#include "app/build_job.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/bake_job.h"
#include "app/validate_job.h"
#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/build_manifest.h"
#include "formats/json_text.h"

namespace rigbake::app {

const char* jobStatusName(JobStatus status) {
  switch (status) {
    case JobStatus::kBuilt: return "built";
    case JobStatus::kUpToDate: return "up-to-date";
    case JobStatus::kFailed: return "failed";
  }
  return "failed";
}

JobOutcome failedJob(const BuildCharacter& character, const std::string& error) {
  JobOutcome outcome;
  outcome.name = character.name;
  outcome.status = JobStatus::kFailed;
  outcome.error = error;
  return outcome;
}

namespace {

// The options `build` took over from `bake` later, named only when set, so that the stamps of
// characters that use none of them stay valid.
std::string bakeOnlyOptions(const BuildCharacter& character) {
  std::string text;
  if (!character.map.empty()) text += " map " + character.map;
  if (!character.regions.empty()) text += " regions";
  if (!character.jiggle.empty()) text += " jiggle";
  if (!character.hits.empty()) text += " hits";
  if (character.vrm_springs_only) text += " vrm_springs_only";
  if (character.fps != 0.0) text += " fps " + std::to_string(character.fps);
  if (character.fit_poses != ResponseFitOptions{}.max_poses) text += " fit_poses " + std::to_string(character.fit_poses);
  if (character.fit_smoothness != ResponseFitOptions{}.smoothness_weight)
    text += " fit_smoothness " + std::to_string(character.fit_smoothness);
  if (character.fit_roughness_cap != ResponseFitOptions{}.roughness_cap)
    text += " fit_roughness_cap " + std::to_string(character.fit_roughness_cap);
  if (character.fit_occupied_volume) text += " fit_volume occupied";
  if (character.fit_every_frame_regions) text += " fit_regions every-frame";
  if (character.stats) text += " stats";
  if (character.packed) text += " packed";
  return text;
}

// Everything that decides a character's outputs, hashed: its files' bytes, the preset, the muscle
// source, the options and the rigbake version.
std::string inputsHash(const BuildManifest& manifest, const BuildCharacter& character) {
  std::vector<std::string> files = {character.input, character.preset};
  if (!character.muscles.empty()) files.push_back(character.muscles);
  if (!character.rom.empty()) files.push_back(character.rom);
  for (const std::string* file : {&character.regions, &character.jiggle, &character.hits})
    if (!file->empty()) files.push_back(*file);
  if (character.map.find('/') != std::string::npos) files.push_back(character.map);  // a file, not a shipped name
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
                                " response " + responseModeName(character.response) + bakeOnlyOptions(character));
}

// Validates the written model against its muscle file and writes the three reports; returns how many
// error-severity checks failed.
int validateCharacter(const CharacterOutputs& out, const BuildCharacter& character, const Presets& presets, int threads) {
  ValidationRequest request;
  request.threads = threads;  // the job's share of the cores, as its bake
  request.baked = out.model;
  request.muscles = out.muscles;
  // The input the bake read, as it read it: validate measures the bake's own regions and plain skinning.
  request.input.path = character.input;
  if (character.vrm >= 0) request.input.load.vrm = character.vrm == 1 ? VrmTarget::kVrm1 : VrmTarget::kVrm0;
  request.preset = character.preset;
  request.map = character.map;
  request.rom = character.rom;
  if (!character.regions.empty()) request.regions = character.regions;
  const Report report = validateJob(request, presets);
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
    return contentHash(out.files(), "outputs");
  } catch (const Error&) {
    return "";
  }
}

// The character's bake as `rigbake bake` would be asked for it.
BakeRequest bakeRequestOf(const BuildManifest& manifest, const BuildCharacter& character, const CharacterOutputs& out,
                          int bake_threads) {
  auto sourceOf = [&](const BuildCharacter& c) {
    CharacterSource source;
    source.path = c.input;
    if (c.vrm >= 0) source.load.vrm = c.vrm == 1 ? VrmTarget::kVrm1 : VrmTarget::kVrm0;
    source.map = c.map;
    return source;
  };
  BakeRequest request;
  request.character = sourceOf(character);
  request.output = out.model;
  request.preset = character.preset;
  request.muscles = character.muscles;
  if (!character.muscles_from.empty()) {
    const BuildCharacter& source = manifest.characters[characterIndex(manifest, character.muscles_from)];
    request.muscles = characterOutputs(manifest, source).muscles;
    request.muscles_from = sourceOf(source);
  }
  request.muscles_character = character.name + ".glb";
  request.rom = character.rom;  // measured on, not written (docs/rom.md)
  if (!character.regions.empty()) request.regions = character.regions;
  request.jiggle = character.jiggle;
  request.hits = character.hits;
  request.springs_only = character.vrm_springs_only;
  request.packed = character.packed;
  BakeOptions& options = request.options;
  options.influences = character.influences;
  options.gltf_weights = character.gltf_weights;
  options.fps = character.fps;
  options.threads = bake_threads;
  options.response = character.response;
  options.fit.max_poses = character.fit_poses;
  options.fit.smoothness_weight = character.fit_smoothness;
  options.fit.roughness_cap = character.fit_roughness_cap;
  options.fit.occupied_volume = character.fit_occupied_volume;
  options.fit.every_frame_regions = character.fit_every_frame_regions;
  options.motion = character.muscle_motion;
  options.helper_joints = character.helper_joints;
  options.measure_skin = character.stats;  // only the stats show them (pipeline/bake.h)
  return request;
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

JobOutcome runCharacterJob(const BuildManifest& manifest, const BuildCharacter& character, const Presets& presets,
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
    BakeOutputs baked = bakeJob(bakeRequestOf(manifest, character, out, bake_threads), presets);
    // The muscles as baked (carriers chosen, response fitted): what a retarget of this cast carries on.
    OutputBatch outputs;
    outputs.add(out.muscles, std::move(baked.muscles_json));
    outputs.add(out.model, std::move(baked.model));
    if (character.stats) outputs.add(out.stats, std::move(baked.stats_json));
    if (character.packed) outputs.add(out.packed, std::move(baked.packed));
    outputs.commit();
    JobOutcome outcome;
    outcome.name = character.name;
    outcome.status = JobStatus::kBuilt;
    outcome.checks_failed = validateCharacter(out, character, presets, bake_threads);
    writeStamp(out, hash, outcome);
    return outcome;
  } catch (const Error& thrown) {
    // An option the bake refuses is named as the manifest spells it (bake's --vrm-springs-only is the
    // manifest's vrm_springs_only), and an error that an option would fix (a naming map) says which key
    // gives it.
    const InvalidOption* option = dynamic_cast<const InvalidOption*>(&thrown);
    const FixableByOption* fixable = dynamic_cast<const FixableByOption*>(&thrown);
    const std::string key = option && option->field() == "springs_only" ? "vrm_springs_only" : option ? option->field() : "";
    const Error error = option    ? Error(errc::MANIFEST_INVALID, manifest.file + "#" + character.pointer + "/" + key, option->problem())
                        : fixable ? Error(fixable->errorCode(), fixable->where(),
                                          fixable->message() + " (as " + manifest.file + "#" + character.pointer + "/" + fixable->field() + ")")
                                  : thrown;
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

}  // namespace rigbake::app
