// What every fuzz target shares. rigbake's readers take paths (they check that an input is a regular
// file and bound its size first), so each input is written to a file in a private folder and read from
// there: the fuzzer then runs the same code a user's file reaches, size checks included.
//
// A run may end in a rigbake::Error (one line, a documented code): that is the expected answer to a bad
// input. Anything else is a finding: any other exception escapes and libFuzzer reports it as a crash
// (the CLI would have printed INTERNAL, exit 5), and so do the sanitizers' reports, an Error whose code
// docs/errors.md does not list, and an error line that is not one line.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/error.h"

namespace rigbake::fuzz {

// A folder of this process's own, removed at exit.
inline const std::string& workDirectory() {
  static const std::string directory = [] {
    char pattern[] = "/tmp/rigbake-fuzz-XXXXXX";
    if (::mkdtemp(pattern) == nullptr) {
      std::perror("rigbake fuzz: mkdtemp");
      std::abort();
    }
    static std::string made;
    made = pattern;
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(made, ignored);
    });
    return made;
  }();
  return directory;
}

// Writes `data` to NAME in the work folder and returns its path.
inline std::string inputFile(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = workDirectory() + "/" + name;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr || (size > 0 && std::fwrite(data, 1, size, file) != size) || std::fclose(file) != 0) {
    std::perror(("rigbake fuzz: writing " + path).c_str());
    std::abort();
  }
  return path;
}

// Aborts (a finding) unless `error` is what a user may see: a documented code and one printable line.
inline void checkError(const Error& error) {
  bool known = false;
  for (const ErrorCode& info : kErrorCodes) known = known || error.code() == info.name;
  const std::string line = printableLine(std::string(error.what()));
  if (!known || error.exitCode() == ExitCode::kInternal || line.find('\n') != std::string::npos) {
    std::fprintf(stderr, "rigbake fuzz: an error users must not see: code %s: %s\n", error.code().c_str(), line.c_str());
    std::abort();
  }
}

// Runs `read` and accepts only success or a rigbake::Error that checkError passes.
template <typename Read>
void expectCleanResult(Read read) {
  try {
    read();
  } catch (const Error& error) {
    checkError(error);
  }
}

}  // namespace rigbake::fuzz
