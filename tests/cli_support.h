// Runs the rigbake binary the way a user or CI would and captures what it says.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_support.h"

namespace rigbake::test {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A fresh directory per test case, removed at the end.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "rigbake-test-XXXXXX").string();
    path = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// `args` is a shell-quoted argument string; `environment`, when given, is "NAME=value ..." set for
// this run alone.
inline CliResult runCli(const std::string& args, const std::string& environment = "") {
  TempDir capture;
  std::string out = capture / "out", err = capture / "err";
  std::string command = (environment.empty() ? "" : "env " + environment + " ") + std::string(rigbake::test::kRigbakeCli) + " " + args + " >" +
                        out + " 2>" + err + " </dev/null";
  int status = std::system(command.c_str());
  CliResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = slurp(out);
  result.err = slurp(err);
  return result;
}

inline int lineCount(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

// The sample character, written once per test process by the CLI itself.
inline std::string sampleGlbPathForCli() {
  struct RemovedAtExit {
    std::string path = (std::filesystem::temp_directory_path() / ("rigbake-cli-sample-" + std::to_string(getpid()) + ".glb")).string();
    RemovedAtExit() { runCli("sample -o " + path); }
    ~RemovedAtExit() { std::remove(path.c_str()); }
  };
  static const RemovedAtExit sample;
  return sample.path;
}

}  // namespace rigbake::test
