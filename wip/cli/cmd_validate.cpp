// `rigbake validate BAKED [--muscles M] [--config C] --report DIR [--khronos] [--json]`: runs every check
// of pipeline/checks.h on a baked character and writes DIR/report.json, DIR/report.junit.xml and
// DIR/report.html. Exit 0 when every error-severity check passes, 4 (validation failed) otherwise; a
// file rigbake cannot read at all is still exit 3, as for every command.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "anatomy/error.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "formats/atomic_file.h"
#include "formats/baked_gltf.h"
#include "formats/muscle_json.h"
#include "formats/report_html.h"
#include "formats/report_json.h"
#include "formats/report_junit.h"
#include "formats/validate_config.h"
#include "pipeline/checks.h"

namespace rigbake::cli {
namespace {

struct ValidateCommandOptions {
  std::string baked;
  std::string muscles;
  std::string preset = "gow_biped";
  std::string config;
  std::string report_dir;
  bool khronos = false;
  bool json = false;
  PresetOptions presets;
};

std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

bool onPath(const std::string& program) {
  return std::system(("command -v " + shellQuote(program) + " >/dev/null 2>&1").c_str()) == 0;
}

bool exists(const std::string& path) { return std::filesystem::exists(path); }

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
  if (!exists(runner) || !exists(package + "/package.json")) {
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

int run(const ValidateCommandOptions& options) {
  const ValidationConfig config = options.config.empty() ? ValidationConfig{} : readValidationConfig(options.config);
  LoadedCharacter loaded;
  LandmarkSet landmarks;
  bool landmarks_resolved = true;
  std::string landmark_problem;
  try {
    ResolvedCharacter resolved = loadAndResolve(options.baked, options.presets);
    loaded = std::move(resolved.loaded);
    landmarks = std::move(resolved.landmarks);
  } catch (const Error& e) {
    // An unresolvable landmark is a finding about this character, not a reason to write no report.
    if (e.code() != "LANDMARK_UNRESOLVED") throw;
    loaded = loadCharacter(options.baked);
    landmarks_resolved = false;
    landmark_problem = e.what();
  }
  const Character& character = loaded.character;
  MuscleSet muscles;
  if (!options.muscles.empty()) {
    MusclePreset preset = loadMusclePreset(options.presets, options.preset);
    muscles = readMuscleJson(options.muscles, character, landmarks, preset);
  }
  const BakedFileData file = readBakedFileData(loaded);

  ValidationInputs inputs;
  inputs.character_name = fileNameOf(options.baked);
  inputs.character = &character;
  inputs.landmarks = landmarks_resolved ? &landmarks : nullptr;
  inputs.landmark_problem = landmark_problem;
  inputs.muscles = options.muscles.empty() ? nullptr : &muscles;
  inputs.file = &file;
  if (options.khronos) inputs.khronos = runKhronosValidator(options.baked);
  else inputs.khronos.skip_reason = "not requested (pass --khronos)";
  const Report report = validateBakedCharacter(inputs, config);

  // Every output is rendered before any is written.
  const std::string json = reportJson(report);
  const std::string junit = reportJunit({report});
  const std::string html = reportHtml(report);
  std::error_code error;
  std::filesystem::create_directories(options.report_dir, error);
  if (error) fail("IO_WRITE_FAILED", options.report_dir, "cannot create the report directory: " + error.message());
  writeFileAtomically(options.report_dir + "/report.json", json);
  writeFileAtomically(options.report_dir + "/report.junit.xml", junit);
  writeFileAtomically(options.report_dir + "/report.html", html);

  if (options.json) std::cout << json;
  int failed_errors = 0, failed_warnings = 0, skipped = 0;
  for (const CheckResult& check : report.checks) {
    if (check.status == CheckStatus::kSkipped) ++skipped;
    if (check.status != CheckStatus::kFail) continue;
    ++(check.severity == Severity::kError ? failed_errors : failed_warnings);
    std::cerr << check.code << " " << (check.location.empty() ? inputs.character_name : check.location) << ": "
              << severityName(check.severity) << ": " << check.message << "\n";
  }
  std::cerr << "validated " << inputs.character_name << ": " << report.checks.size() << " checks, " << failed_errors
            << " errors, " << failed_warnings << " warnings, " << skipped << " skipped; report in "
            << options.report_dir << "/report.html\n";
  return static_cast<int>(report.passed() ? ExitCode::kOk : ExitCode::kValidationFailed);
}

}  // namespace

void addValidateCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<ValidateCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "validate",
      "Check a baked character (landmarks, muscle locators, muscle length ratios over every clip, skin weights and "
      "indices, influence counts, packed-weight deformation error, glTF structure, optionally the Khronos "
      "glTF-Validator) and write report.json, report.junit.xml and report.html into --report DIR. Exit 0 when every "
      "error-severity check passes, 4 otherwise. docs/validate.md lists the checks.");
  command->add_option("baked", options->baked, "Baked character (.glb, .gltf, .vrm) from `rigbake bake`")->required();
  command->add_option("--report", options->report_dir, "Directory to write the reports into (created if missing)")
      ->required();
  command->add_option("--muscles", options->muscles,
                      "Muscle JSON the character was baked with; without it the muscle checks are skipped");
  command->add_option("--preset", options->preset, "Muscle preset for a positions-only --muscles file")
      ->capture_default_str();
  command->add_option("--config", options->config,
                      "JSON file overriding check thresholds and severities (docs/validate.md)");
  command->add_flag("--khronos", options->khronos,
                    "Also run the Khronos glTF-Validator (needs node and scripts/install-validator.sh)");
  command->add_flag("--json", options->json, "Also print report.json on stdout");
  addPresetOptions(command, &options->presets);
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
