// Errors a user can cause, each with a stable code (docs/errors.md lists them all).
// A stage throws rigbake::Error once; cli/main.cpp catches it once, prints one line and exits
// with the code's exit status. Codes are never renamed or reused.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace rigbake {

// Documented exit statuses (docs/errors.md). Each outcome has its own, so that a script tells a wrong
// command line from a character that failed its checks.
enum class ExitCode : int {
  kOk = 0,
  kUsage = 1,
  kIo = 2,
  kInvalidInput = 3,
  kChecksFailed = 4,  // validate: an error-severity check failed; build: a character failed (CI treats it as a failed test)
  kInternal = 5,
};

struct ErrorCode {
  const char* name;  // the stable code printed first on the error line, e.g. "GLTF_PARSE_FAILED"
  ExitCode exit;
  const char* meaning;  // one sentence for `rigbake errors` and docs/errors.md
};

// The one table of user-facing error codes, in the order they were introduced: X(NAME, EXIT, MEANING).
// Each row becomes the symbol errc::NAME that every fail() and Error names, so a mistyped code does not
// compile, and kErrorCodes, which `rigbake errors` prints and tests/cli_test.cpp checks docs/errors.md
// against. A meaning names no flag (scripts/check-flag-names.py): bake and build raise the same codes
// from options their users spell differently; docs/errors.md says which flag or key leads to each.
#define RIGBAKE_ERROR_CODES(X) \
  X(USAGE, kUsage, "The command line is malformed or an option value is out of range.") \
  X(IO_FILE_NOT_FOUND, kIo, "An input file does not exist or cannot be opened.") \
  X(IO_WRITE_FAILED, kIo, "An output file could not be written or renamed into place.") \
  X(GLTF_PARSE_FAILED, kInvalidInput, "The file is not a readable glTF, GLB or VRM (syntax, truncation, bad buffers).") \
  X(GLTF_NO_SKIN, kInvalidInput, "The glTF has no skin, so there is no skeleton to rig.") \
  X(GLTF_ACCESSOR_INVALID, kInvalidInput, "An accessor the pipeline needs has the wrong type, component type or range.") \
  X(GLTF_SKIN_INVALID, kInvalidInput, "A skin's joints or inverse bind matrices are inconsistent.") \
  X(JSON_PARSE_FAILED, kInvalidInput, "A JSON input (preset, map, muscle file) is not valid JSON.") \
  X(PRESET_INVALID, kInvalidInput, "A preset or naming map breaks its schema; the message gives the JSON pointer.") \
  X(MAP_NOT_FOUND, kInvalidInput, "A naming map named on the command line does not exist among the shipped maps.") \
  X(LANDMARK_UNRESOLVED, kInvalidInput, "A landmark the pipeline needs matches no joint and cannot be derived.") \
  X(PRESET_LANDMARK_UNKNOWN, kInvalidInput, "A preset or naming map names a landmark that is not canonical.") \
  X(MUSCLES_INVALID, kInvalidInput, "A muscle JSON file breaks the muscle schema.") \
  X(MUSCLES_MISMATCH, kInvalidInput, "A muscle JSON file names joints that the character does not have.") \
  X(JIGGLE_UNRESOLVED, kInvalidInput, "A jiggle preset names a joint, landmark or muscle the character does not have, or an unusable axis.") \
  X(HITS_INVALID, kInvalidInput, "A hit file breaks its schema or names a part that has no jiggle.") \
  X(PACKED_FILE_INVALID, kInvalidInput, "A packed influence file is damaged or not layout version 1.") \
  X(MANIFEST_INVALID, kInvalidInput, "A build manifest breaks its schema or names an unknown muscles_from character.") \
  X(BUILD_FAILED, kChecksFailed, "rigbake build finished, but at least one character failed; each is named in the summary.") \
  X(VALIDATE_CONFIG_INVALID, kInvalidInput, "A validation config file breaks its format; the message gives the JSON pointer.") \
  X(RETARGET_LOCATOR_UNANCHORED, kInvalidInput, "A muscle locator rides on a joint with no canonical landmark on it or above it, so it cannot be retargeted.") \
  X(RETARGET_SEGMENT_DEGENERATE, kInvalidInput, "Two landmarks that span a retarget frame coincide, so the segment has no direction.") \
  X(GLTF_EXTENSION_UNSUPPORTED, kInvalidInput, "The glTF's extensionsRequired names an extension rigbake cannot honour, so it must not be loaded.") \
  X(ROM_CLIP_UNKNOWN, kInvalidInput, "A clip asked for by name is not one the ROM preset has.") \
  X(ROM_CLIP_UNAVAILABLE, kInvalidInput, "A ROM clip needs a landmark or joint the character lacks (no legs, no neck joint), or no ROM clip fits it at all.") \
  X(ROM_CLIP_EXISTS, kInvalidInput, "The character already has an animation with a ROM clip's name (it is a ROM output already).") \
  X(VIEW_PLAYER_MISSING, kIo, "rigbake view cannot find the bundled player script (scripts/install-player.sh builds it).") \
  X(VIEW_NOT_BAKED, kInvalidInput, "rigbake view was given a file that is not a rigbake bake (no rig extension, muscle joints or packed influences).") \
  X(VIEW_BAKE_INVALID, kInvalidInput, "A baked file's RIGBAKE_muscle_rig extension or packed influence attributes are malformed, so the player cannot run it.") \
  X(FBX_PARSE_FAILED, kInvalidInput, "The file is not a readable FBX (Assimp cannot import it: truncation, damage, not FBX) or uses a left-handed axis system.") \
  X(VIEW_RIG_STRIPPED, kInvalidInput, "A baked file's muscle joints have neither the RIGBAKE_muscle_rig extension nor channels: a tool stripped the rig, so the player would show muscles that never move.") \
  X(IO_OUTPUT_NOT_REGULAR, kIo, "An output path exists and is not a regular file (a device, FIFO, socket or directory), so it is not replaced.") \
  X(BUILD_OUTPUT_LOCKED, kIo, "Another rigbake build is writing into the same output folder (it holds OUT/.rigbake-lock).") \
  X(BUILD_SOURCE_FAILED, kChecksFailed, "A build character's muscles_from source failed, so it could not be built (the run ends BUILD_FAILED).") \
  X(IO_INPUT_NOT_REGULAR, kInvalidInput, "An input path is a device, socket or directory, not a file to read (a FIFO or pipe is read).") \
  X(INPUT_TOO_LARGE, kInvalidInput, "An input file is larger than rigbake reads of its kind (2 GiB for a glTF, GLB or VRM, 64 MiB for JSON).") \
  X(VRM_CONVERSION_UNSUPPORTED, kInvalidInput, "A bake asks for a VRM version the input cannot become: it is not a VRM, or it is a VRM 1.0 asked to be 0.x.") \
  X(VALIDATE_INPUT_MISMATCH, kInvalidInput, "The character named as a baked file's input is not the one it was baked from: its skinned meshes, vertices or joints differ.") \
  X(INTERNAL, kInternal, "A bug in rigbake: an invariant did not hold. Please report it with the input.")

namespace errc {
#define RIGBAKE_ERROR_CODE_SYMBOL(name, exit, meaning) inline constexpr ErrorCode name{#name, ExitCode::exit, meaning};
RIGBAKE_ERROR_CODES(RIGBAKE_ERROR_CODE_SYMBOL)
#undef RIGBAKE_ERROR_CODE_SYMBOL
}  // namespace errc

#define RIGBAKE_ERROR_CODE_ROW(name, exit, meaning) errc::name,
inline constexpr ErrorCode kErrorCodes[] = {RIGBAKE_ERROR_CODES(RIGBAKE_ERROR_CODE_ROW)};
#undef RIGBAKE_ERROR_CODE_ROW

class Error : public std::runtime_error {
 public:
  // `where` names the file and, when it helps, a JSON pointer or glTF path inside it.
  Error(const ErrorCode& code, std::string where, const std::string& message);
  const std::string& code() const { return name_; }
  const ErrorCode& errorCode() const { return *code_; }
  const std::string& where() const { return where_; }
  ExitCode exitCode() const { return code_->exit; }

 private:
  const ErrorCode* code_;  // a row of kErrorCodes (its symbols live as long as the program)
  std::string name_;
  std::string where_;
};

[[noreturn]] void fail(const ErrorCode& code, const std::string& where, const std::string& message);

// An option out of range, or at odds with another, named by its field in the options struct
// (BakeOptions::influences is "influences"). pipeline/ and app/ know no flags or manifest keys, so the
// caller names the option as its user spelled it (cli/: a flag; build: a manifest key) and rethrows;
// uncaught it is still a USAGE error, naming the field.
class InvalidOption : public Error {
 public:
  InvalidOption(const std::string& field, const std::string& problem);
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string field_;
  std::string problem_;
};

[[noreturn]] void failOption(const std::string& field, const std::string& problem);

// An error that one more option would fix, naming that option by its field, as InvalidOption names a
// bad one: anatomy/ asks for a naming map as "map" (the `map` of app::CharacterSource and
// app::ValidationRequest, the build manifest's "map"). The message says in words what to give ("give a
// JSON naming map") and names no flag; the caller that prints it adds how its user gives it (cli/: the
// flag; build: the manifest key). Uncaught, it is the plain error of its code.
class FixableByOption : public Error {
 public:
  FixableByOption(const ErrorCode& code, std::string where, const std::string& message, std::string field);
  const std::string& field() const { return field_; }
  const std::string& message() const { return message_; }  // without the code and where

 private:
  std::string field_;
  std::string message_;
};

// The length of the well-formed UTF-8 sequence (RFC 3629: no overlong forms, surrogates or code points
// past U+10FFFF) that starts at text[i], or 0. Text rigbake writes passes through it where the input
// may have put bytes that are not UTF-8 (error lines, JUnit XML).
size_t utf8SequenceAt(const std::string& text, size_t i);

// `text` as one line of valid UTF-8: every byte that is not part of a well-formed UTF-8 sequence, and
// every ASCII control character (newlines included), written as \xHH. Error messages pass through it.
std::string printableLine(const std::string& text);

}  // namespace rigbake
