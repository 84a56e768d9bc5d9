// Test helpers for checks that run outside tools on written files: the Khronos glTF-Validator (through
// scripts/gltf-validate.js and node) and Blender's glTF importer. Under CI=true a missing tool fails
// the test; elsewhere it is a warning and the check is skipped.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace rigbake::test::external {

inline bool underCi() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}

// Returns `available`; when false, FAILs under CI and WARNs otherwise.
inline bool requireTool(bool available, const std::string& what) {
  if (available) return true;
  if (underCi()) FAIL(what << " is missing under CI");
  WARN(what << " is missing, check skipped outside CI");
  return false;
}

inline std::string shellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout, and stderr when the command redirects it
};

inline CommandResult runCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> chunk{};
  size_t n;
  while ((n = fread(chunk.data(), 1, chunk.size(), pipe)) > 0) result.output.append(chunk.data(), n);
  int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline bool onPath(const std::string& program) {
  return std::system(("command -v " + shellQuote(program) + " >/dev/null 2>&1").c_str()) == 0;
}

// A fresh directory under the system temp dir, removed with everything in it at scope exit.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "rigbake-test-XXXXXX").string();
    if (mkdtemp(pattern.data())) path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// glTF-Transform's CLI as scripts/install-gltf-transform.sh installs it ($RIGBAKE_GLTF_TRANSFORM overrides).
inline std::string gltfTransformCli() {
  const char* override_path = std::getenv("RIGBAKE_GLTF_TRANSFORM");
  return override_path ? override_path : sourceDir() + "/.tools/gltf-transform/node_modules/.bin/gltf-transform";
}

inline std::string validatorRunner() { return sourceDir() + "/scripts/gltf-validate.js"; }

inline bool validatorAvailable() {
  const char* package = std::getenv("RIGBAKE_GLTF_VALIDATOR");
  std::string package_json = (package ? std::string(package) : sourceDir() + "/.tools/node_modules/gltf-validator") +
                             "/package.json";
  return onPath("node") && fileExists(validatorRunner()) && fileExists(package_json);
}

inline std::string validatorHint() {
  return "gltf-validator (node on PATH and scripts/install-validator.sh run, for " + validatorRunner() + ")";
}

struct ValidationSummary {
  int exit_code = -1;
  int errors = -1;
  int warnings = -1;
  std::vector<std::string> warning_codes;
  std::string raw;
};

// Runs the node runner on one file and reads its one-line JSON summary.
inline ValidationSummary validateWithKhronos(const std::string& path) {
  ValidationSummary summary;
  CommandResult run = runCommand("node " + shellQuote(validatorRunner()) + " " + shellQuote(path) + " 2>&1");
  summary.exit_code = run.exit_code;
  summary.raw = run.output;
  nlohmann::json report = nlohmann::json::parse(run.output, nullptr, false);
  if (report.is_discarded() || !report.is_object()) return summary;
  summary.errors = report.value("numErrors", -1);
  summary.warnings = report.value("numWarnings", -1);
  for (const auto& issue : report.value("issues", nlohmann::json::array())) {
    if (issue.value("severity", "") == "warning") summary.warning_codes.push_back(issue.value("code", ""));
  }
  return summary;
}

}  // namespace rigbake::test::external
