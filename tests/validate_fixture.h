// Bakes characters in-process the way `rigbake place` + `rigbake bake` do, writes the GLB and reads it
// back the way `rigbake validate` does, for the check and report tests. Also runs headless Chromium on
// a report page.
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>

#include "anatomy_fixture.h"
#include "app/bake_job.h"
#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/muscle_json.h"
#include "pipeline/bake.h"
#include "pipeline/checks.h"

namespace rigbake::test {

// A baked file loaded back for validation, with everything validateBakedCharacter() needs.
struct ValidatedBake {
  std::string source;  // the character that was baked
  std::string name;    // file name of the baked GLB
  std::string glb;     // its path
  std::string muscles_path;
  LoadedCharacter loaded;
  LandmarkSet landmarks;
  MuscleSet muscles;  // read back against the baked skeleton, as --muscles does
  BakedFileData file;
  int clip_count = 0;

  ValidationInputs inputs() const {
    ValidationInputs in;
    in.character_name = name;
    in.character = &loaded.character;
    in.landmarks = &landmarks;
    in.muscles = &muscles;
    in.file = &file;
    in.khronos.skip_reason = "not requested";
    return in;
  }
};

inline std::string validateScratchDir() {
  static const std::string dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "rigbake-validate-XXXXXX").string();
    return std::string(mkdtemp(pattern.data()));
  }();
  return dir;
}

// Writes the baked GLB and its muscle JSON (as baked, as `bake --muscles-out` writes it) into `dir`;
// returns the GLB path.
inline std::string bakeToFiles(const std::string& path, int influences, const std::string& dir,
                               std::string* muscles_path) {
  static const app::Presets presets = app::loadPresets(presetsDir());
  const std::string stem = std::filesystem::path(path).stem().string() + "-" + std::to_string(influences);
  const std::string glb = dir + "/" + stem + ".glb";
  *muscles_path = dir + "/" + stem + "-muscles.json";
  app::BakeRequest request;
  request.character.path = path;
  request.output = glb;
  request.regions = "";  // the checks measure the regions themselves, from the file
  request.options.influences = influences;
  // Both the rig extension and the skinned joints' channels: the checks read either.
  request.options.motion = MuscleMotion::kBoth;
  const app::BakeOutputs out = app::bakeJob(request, presets);
  std::ofstream(glb, std::ios::binary) << out.model;
  std::ofstream(*muscles_path, std::ios::binary) << out.muscles_json;
  return glb;
}

inline std::shared_ptr<ValidatedBake> loadValidatedBake(const std::string& glb, const std::string& muscles_path,
                                                        const std::string& source) {
  auto baked = std::make_shared<ValidatedBake>();
  baked->source = source;
  baked->name = std::filesystem::path(glb).filename().string();
  baked->glb = glb;
  baked->muscles_path = muscles_path;
  Resolved resolved = resolveShipped(glb);
  baked->loaded = loadCharacter(glb);
  baked->landmarks = resolved.landmarks;
  baked->muscles = readMuscleJson(muscles_path, baked->loaded.character, baked->landmarks, gowPreset());
  baked->file = readBakedFileData(baked->loaded);
  baked->clip_count = static_cast<int>(baked->loaded.character.clips.size());
  return baked;
}

inline std::vector<std::string> validateCharacterPaths() {
  std::vector<std::string> paths = sampleAndAssetPaths();
  return paths;
}

// One character baked at 10 influences and loaded back, once per test process (ctest runs each test
// case in its own process, so a test that needs only the sample must not bake every asset).
inline std::shared_ptr<ValidatedBake> validatedBakeOf(const std::string& path) {
  static std::map<std::string, std::shared_ptr<ValidatedBake>> cache;
  auto found = cache.find(path);
  if (found != cache.end()) return found->second;
  std::string muscles;
  std::string glb = bakeToFiles(path, 10, validateScratchDir(), &muscles);
  return cache[path] = loadValidatedBake(glb, muscles, path);
}

// The sample and every shared asset.
inline std::vector<std::shared_ptr<ValidatedBake>> validatedBakes() {
  std::vector<std::shared_ptr<ValidatedBake>> all;
  for (const std::string& path : validateCharacterPaths()) all.push_back(validatedBakeOf(path));
  return all;
}

inline const ValidatedBake& validatedSample() { return *validatedBakeOf(sampleGlbPath()); }

inline const CheckResult& checkOf(const Report& report, const std::string& code) {
  for (const CheckResult& check : report.checks) {
    if (check.code == code) return check;
  }
  FAIL("no check " << code << " in the report");
  return report.checks.front();
}

// ---- Headless Chromium ----

inline std::string chromiumBinary() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    if (external::onPath(name)) return name;
  }
  return "";
}

struct ChromiumRun {
  int exit_code = -1;
  std::string dom;  // --dump-dom output
  std::string log;  // stderr with --enable-logging=stderr
};

// Renders `html_path` headless with a fresh profile and no network services; dumps the DOM (and a
// screenshot when `screenshot` is not empty).
inline ChromiumRun renderInChromium(const std::string& html_path, const std::string& screenshot = "") {
  external::ScratchDir profile;
  const std::string flags =
      " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking"
      " --disable-component-update --disable-sync --disable-dev-shm-usage --enable-logging=stderr --v=0"
      " --user-data-dir=" + external::shellQuote(profile.path());
  const std::string url = external::shellQuote("file://" + std::filesystem::absolute(html_path).string());
  ChromiumRun run;
  const std::string log_file = profile.file("stderr.log");
  external::CommandResult dump =
      external::runCommand(chromiumBinary() + flags + " --dump-dom " + url + " 2>" + external::shellQuote(log_file));
  run.exit_code = dump.exit_code;
  run.dom = dump.output;
  run.log = slurp(log_file);
  if (!screenshot.empty()) {
    external::ScratchDir profile2;
    external::runCommand(chromiumBinary() + " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                         " --disable-background-networking --disable-component-update --disable-sync"
                         " --disable-dev-shm-usage --hide-scrollbars --window-size=1320,2600 --user-data-dir=" +
                         external::shellQuote(profile2.path()) + " --screenshot=" + external::shellQuote(screenshot) +
                         " " + url + " 2>&1");
  }
  return run;
}

inline int countOccurrences(const std::string& text, const std::string& needle) {
  int count = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++count;
  return count;
}

}  // namespace rigbake::test
