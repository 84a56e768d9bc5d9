// Errors a user can cause, each with a stable code (docs/errors.md lists them all).
// A stage throws rigbake::Error once; cli/main.cpp catches it once, prints one line and exits
// with the code's exit status. Codes are never renamed or reused.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace rigbake {

// Documented exit statuses (docs/errors.md).
enum class ExitCode : int {
  kOk = 0,
  kUsage = 1,
  kIo = 2,
  kInvalidInput = 3,
  kChecksFailed = 1,  // validate: an error-severity check failed; build: a character failed (CI treats it as a failed test)
  kInternal = 5,
};

struct ErrorCodeInfo {
  const char* code;
  ExitCode exit;
  const char* meaning;
};

// Every user-facing error code, in the order they were introduced.
const std::vector<ErrorCodeInfo>& errorCodes();

class Error : public std::runtime_error {
 public:
  // `where` names the file and, when it helps, a JSON pointer or glTF path inside it.
  Error(std::string code, std::string where, const std::string& message);
  const std::string& code() const { return code_; }
  const std::string& where() const { return where_; }
  ExitCode exitCode() const;

 private:
  std::string code_;
  std::string where_;
};

[[noreturn]] void fail(const std::string& code, const std::string& where, const std::string& message);

// The length of the well-formed UTF-8 sequence (RFC 3629: no overlong forms, surrogates or code points
// past U+10FFFF) that starts at text[i], or 0. Text rigbake writes passes through it where the input
// may have put bytes that are not UTF-8 (error lines, JUnit XML).
size_t utf8SequenceAt(const std::string& text, size_t i);

// `text` as one line of valid UTF-8: every byte that is not part of a well-formed UTF-8 sequence, and
// every ASCII control character (newlines included), written as \xHH. Error messages pass through it.
std::string printableLine(const std::string& text);

}  // namespace rigbake
