#include "app/validate_job.h"
#include "core/file_name.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/baked_gltf.h"
#include "formats/muscle_json.h"
#include "formats/report_html.h"
#include "formats/report_json.h"
#include "formats/report_junit.h"
#include "formats/preset_json.h"
#include "formats/rom_json.h"
#include "pipeline/baked_quality.h"
#include "pipeline/rom.h"

namespace rigbake::app {
namespace {

std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

bool onPath(const std::string& program) {
  return std::system(("command -v " + shellQuote(program) + " >/dev/null 2>&1").c_str()) == 0;
}

// The node runner ships in the source tree's scripts/, beside presets/; the validator package is
// where scripts/install-validator.sh puts it unless RIGBAKE_GLTF_VALIDATOR says otherwise.
ExternalValidation runKhronosValidator(const std::string& path) {
  ExternalValidation result;
  const std::filesystem::path source = std::filesystem::path(RIGBAKE_DEFAULT_PRESET_DIR).parent_path();
  const std::string runner = (source / "scripts" / "gltf-validate.js").string();
  const char* env = std::getenv("RIGBAKE_GLTF_VALIDATOR");
  const std::string package = env ? std::string(env) : (source / ".tools" / "node_modules" / "gltf-validator").string();
  if (!onPath("node")) {
    result.skip_reason = "node is not on PATH";
    return result;
  }
  if (!std::filesystem::exists(runner) || !std::filesystem::exists(package + "/package.json")) {
    result.skip_reason = "gltf-validator is not installed at " + package + " (run scripts/install-validator.sh)";
    return result;
  }
  std::string output;
  FILE* pipe = popen(("node " + shellQuote(runner) + " " + shellQuote(path) + " 2>&1").c_str(), "r");
  if (!pipe) {
    result.skip_reason = "could not start node";
    return result;
  }
  char chunk[4096];
  size_t n;
  while ((n = fread(chunk, 1, sizeof(chunk), pipe)) > 0) output.append(chunk, n);
  pclose(pipe);
  const nlohmann::json summary = nlohmann::json::parse(output, nullptr, false);
  if (summary.is_discarded() || !summary.is_object() || !summary.contains("numErrors")) {
    result.skip_reason = "gltf-validator gave no report: " + output.substr(0, output.find('\n'));
    return result;
  }
  result.ran = true;
  result.errors = summary.value("numErrors", 0);
  result.warnings = summary.value("numWarnings", 0);
  for (const std::string severity : {"error", "warning"}) {
    for (const auto& issue : summary.value("issues", nlohmann::json::array())) {
      if (issue.value("severity", "") != severity) continue;
      result.issues.push_back({issue.value("pointer", ""), severity + " " + issue.value("code", "") + ": " +
                                                               issue.value("message", "")});
    }
  }
  return result;
}

}  // namespace

Report validateJob(const ValidationRequest& request, const Presets& presets) {
  reportProgress(request.progress, "loading the character");
  // A misspelt map fails before the file is read, as loadCharacter() does.
  NamingMap forced;
  if (!request.map.empty()) forced = namingMapOf(presets, request.map);
  LoadedCharacter loaded = rigbake::loadCharacter(request.baked);
  if (request.notes)
    for (const std::string& note : loaded.notes) request.notes(note);
  LandmarkSet landmarks;
  bool landmarks_resolved = true;
  std::string landmark_problem;
  try {
    LandmarkInputs inputs;
    inputs.maps = &presets.maps;
    inputs.rules = &presets.rules;
    inputs.forced_map = request.map.empty() ? nullptr : &forced;
    landmarks = resolveLandmarks(loaded.character, inputs);
  } catch (const Error& e) {
    // An unresolvable landmark is a finding about this character, not a reason to write no report.
    if (e.code() != "LANDMARK_UNRESOLVED") throw;
    landmarks_resolved = false;
    landmark_problem = e.what();
  }
  // --rom: the range-of-motion clips are measured like the file's own (muscle ratios, deformation per
  // clip). Without landmarks there is no body frame to build them in; the landmark check says why.
  if (!request.rom.empty() && landmarks_resolved)
    appendMeasureOnlyClips(&loaded.character, buildRom(loaded.character, landmarks, readRomPreset(presetFile(presets.directory, "rom", request.rom))));
  const Character& character = loaded.character;
  MuscleSet muscles;
  if (!request.muscles.empty()) {
    MusclePreset preset = readMusclePreset(presetFile(presets.directory, "muscles", request.preset));
    muscles = readMuscleJson(request.muscles, character, landmarks, preset);
  }
  const BakedFileData file = readBakedFileData(loaded);

  ValidationInputs inputs;
  inputs.character_name = fileNameOf(request.baked);
  inputs.character = &character;
  inputs.landmarks = landmarks_resolved ? &landmarks : nullptr;
  inputs.landmark_problem = landmark_problem;
  inputs.muscles = request.muscles.empty() ? nullptr : &muscles;
  inputs.file = &file;
  inputs.threads = request.threads;
  BakedQuality quality;
  if (landmarks_resolved) {
    reportProgress(request.progress, request.pictures ? "measuring every frame and drawing the pictures" : "measuring every frame");
    BakedQualityOptions quality_options;
    quality_options.pictures = request.pictures;
    quality_options.threads = request.threads;
    LoadedCharacter input;
    if (!request.input.path.empty()) {
      reportProgress(request.progress, "loading the input character");
      input = rigbake::loadCharacter(request.input.path, request.input.load);
      quality_options.input = &input.character;
    }
    quality = measureBakedQuality(character, landmarks, readRegionPreset(presetFile(presets.directory, "regions", request.regions)),
                                  file, quality_options);
    inputs.quality = &quality;
  }
  if (request.khronos) {
    reportProgress(request.progress, "running the Khronos glTF-Validator");
    inputs.khronos = runKhronosValidator(request.baked);
  } else {
    inputs.khronos.skip_reason = kKhronosNotRequested;
  }
  reportProgress(request.progress, "checking");
  return validateBakedCharacter(inputs, request.config);
}

ReportPaths reportPathsIn(const std::string& directory) {
  return {directory + "/report.json", directory + "/report.junit.xml", directory + "/report.html"};
}

void writeReports(const Report& report, const ReportPaths& paths, int threads) {
  const std::string json = reportJson(report);
  const std::string junit = reportJunit({report});
  const std::string html = reportHtml(report, threads);
  // The folders this run creates, deepest first: a failed run takes them away again (it writes nothing).
  std::vector<std::filesystem::path> created;
  auto removeCreated = [&created]() {
    std::error_code ignored;
    for (const std::filesystem::path& folder : created) std::filesystem::remove(folder, ignored);  // only if empty
  };
  for (const std::string& path : {paths.json, paths.junit, paths.html}) {
    std::error_code error;
    std::filesystem::path parent = std::filesystem::path(path).parent_path();
    for (std::filesystem::path p = parent; !p.empty() && !std::filesystem::exists(p, error); p = p.parent_path())
      created.push_back(p);
    if (!parent.empty()) std::filesystem::create_directories(parent, error);
    if (error) {
      removeCreated();
      fail(errc::IO_WRITE_FAILED, parent.string(), "cannot create the report directory: " + error.message());
    }
  }
  // The three or none: a report.html that cannot be written must not leave a new report.json that says
  // the opposite of the old report.html.
  OutputBatch outputs;
  outputs.add(paths.json, json);
  outputs.add(paths.junit, junit);
  outputs.add(paths.html, html);
  try {
    outputs.commit();
  } catch (...) {
    removeCreated();
    throw;
  }
}

}  // namespace rigbake::app
