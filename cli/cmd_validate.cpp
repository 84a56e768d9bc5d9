// `rigbake validate BAKED [--muscles M] [--config C] --report DIR [--khronos] [--json]`: runs every check
// of pipeline/checks.h on a baked character and writes DIR/report.json, DIR/report.junit.xml and
// DIR/report.html. Exit 0 when every error-severity check passes, 4 otherwise; a
// file rigbake cannot read at all is still exit 3, as for every command.
#include <iostream>

#include "core/error.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "app/validate_job.h"
#include "formats/report_json.h"
#include "formats/validate_config.h"
#include "pipeline/checks.h"

namespace rigbake::cli {
namespace {

struct ValidateCommandOptions {
  std::string baked;
  std::string muscles;
  std::string input;
  std::string preset = "gow_biped";
  std::string config;
  std::string report_dir;
  std::string rom;
  std::string regions = "body";
  bool pictures = true;
  bool khronos = false;
  bool json = false;
  std::string progress = "auto";
  int threads = 0;
  PresetOptions presets;
};

int run(const ValidateCommandOptions& options) {
  if (options.report_dir.empty()) fail(errc::USAGE, "--report", "names no directory (an empty path)");
  const app::ReportPaths paths = app::reportPathsIn(options.report_dir);
  checkOutputOptions({{"--report", paths.json, true}, {"--report", paths.junit, true}, {"--report", paths.html, true}});
  ProgressLine progress("rigbake validate", options.progress);
  app::ValidationRequest request;
  request.baked = options.baked;
  request.muscles = options.muscles;
  request.input.path = options.input;
  request.preset = options.preset;
  request.map = options.presets.map;
  if (!options.config.empty()) request.config = readValidationConfig(options.config);
  request.khronos = options.khronos;
  request.rom = options.rom;
  request.regions = options.regions;
  request.pictures = options.pictures;
  request.progress = progress.report();
  request.threads = options.threads;
  request.notes = printNotesOf(options.baked);
  const Report report = withFlagNames({{"map", "--map"}}, [&] {
    return app::validateJob(request, app::loadPresets(presetsDirectory(options.presets)));
  });
  progress.show("writing the reports");
  app::writeReports(report, paths, options.threads);
  progress.clear();
  const std::string character_name = fileNameOf(options.baked);

  if (options.json) std::cout << reportJson(report);
  int failed_errors = 0, failed_warnings = 0, skipped = 0;
  for (const CheckResult& check : report.checks) {
    const std::string where = check.location.empty() ? character_name : check.location;
    if (check.status == CheckStatus::kSkipped) ++skipped;
    // The reports say what happened; the flag that changes it is the command line's to name.
    if (check.status == CheckStatus::kSkipped) {
      const char* flag = check.code == "KHRONOS_VALIDATOR" && check.message == app::kKhronosNotRequested ? "--khronos"
                         : check.message == kNoMuscleFile                                               ? "--muscles"
                                                                                                        : nullptr;
      if (flag) std::cerr << check.code << " " << where << ": skipped: " << check.message << " (pass " << flag << ")\n";
    }
    if (check.status != CheckStatus::kFail) continue;
    ++(check.severity == Severity::kError ? failed_errors : failed_warnings);
    // Landmarks that match no joint are what a naming map is for.
    const char* hint = check.code == "LANDMARKS_RESOLVED" ? " (pass --map)" : "";
    std::cerr << check.code << " " << where << ": " << severityName(check.severity) << ": " << check.message << hint << "\n";
  }
  std::cerr << "validated " << character_name << ": " << report.checks.size() << " checks, " << failed_errors
            << " errors, " << failed_warnings << " warnings, " << skipped << " skipped; report in "
            << options.report_dir << "/report.html\n";
  return static_cast<int>(report.passed() ? ExitCode::kOk : ExitCode::kChecksFailed);
}

}  // namespace

void addValidateCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<ValidateCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "validate",
      "Check a baked character (landmarks, muscle locators, muscle length ratios over every clip, skin weights and "
      "indices, influence counts, packed-weight deformation error, volume kept per body region and bulge per muscle "
      "against the input skinning and dual quaternions (with pictures), glTF structure, optionally the Khronos "
      "glTF-Validator) and write report.json, report.junit.xml and report.html into --report DIR. Exit 0 when every "
      "error-severity check passes, 1 otherwise. docs/validate.md lists the checks.");
  command->add_option("baked", options->baked, "Baked character (.glb, .gltf, .vrm) from `rigbake bake`")->required();
  command->add_option("--report", options->report_dir, "Directory to write the reports into (created if missing)")
      ->required();
  command->add_option("--muscles", options->muscles,
                      "Muscle JSON the character was baked with; without it the muscle checks are skipped");
  command->add_option("--input", options->input,
                      "The character the file was baked from (bake's CHAR). Given, the volume, seam, surface and crease "
                      "figures compare the rig with that file's own skinning and cut the body regions from its weights, "
                      "as `bake --stats` does; without it, with the file's weights each muscle's handed back to its "
                      "carrier joint, which at 4 and 7 influences are close to the input's but not its own");
  command->add_option("--preset", options->preset, "Muscle preset for a positions-only --muscles file")
      ->capture_default_str();
  command->add_option("--config", options->config,
                      "JSON file overriding check thresholds and severities (docs/validate.md)");
  command->add_flag("--khronos", options->khronos,
                    "Also run the Khronos glTF-Validator (needs node and scripts/install-validator.sh)");
  command->add_option("--rom", options->rom,
                      "Also measure on range-of-motion clips (a ROM preset; alone: default): the muscle ratios and the "
                      "deformation figures per clip cover the rom_* clips too, so a character without clips gets "
                      "figures (docs/rom.md). The muscle joints ride their attach joints rigidly in these clips. Put it "
                      "after the file, or write --rom=PRESET")
      ->expected(0, 1)
      ->default_str("default");
  command->add_option("--regions", options->regions,
                      "Body regions for the volume figures (a file, or a name under presets/regions/)")
      ->capture_default_str();
  command->add_flag("!--no-pictures", options->pictures,
                    "Leave the deformation pictures out of report.html (the figures stay)");
  command->add_flag("--json", options->json, "Also print report.json on stdout");
  command->add_option("--threads", options->threads,
                      "Threads for the per-frame measures (0 = one per core); the reports are byte-identical at any count")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  addProgressOption(command, &options->progress);
  addPresetOptions(command, &options->presets);
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
