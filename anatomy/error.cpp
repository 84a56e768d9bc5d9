#include "anatomy/error.h"

namespace rigbake {

const std::vector<ErrorCodeInfo>& errorCodes() {
  static const std::vector<ErrorCodeInfo> kCodes = {
      {"USAGE", ExitCode::kUsage, "The command line is malformed or an option value is out of range."},
      {"IO_FILE_NOT_FOUND", ExitCode::kIo, "An input file does not exist or cannot be opened."},
      {"IO_WRITE_FAILED", ExitCode::kIo, "An output file could not be written or renamed into place."},
      {"GLTF_PARSE_FAILED", ExitCode::kInvalidInput, "The file is not a readable glTF, GLB or VRM (syntax, truncation, bad buffers)."},
      {"GLTF_NO_SKIN", ExitCode::kInvalidInput, "The glTF has no skin, so there is no skeleton to rig."},
      {"GLTF_ACCESSOR_INVALID", ExitCode::kInvalidInput, "An accessor the pipeline needs has the wrong type, component type or range."},
      {"GLTF_SKIN_INVALID", ExitCode::kInvalidInput, "A skin's joints or inverse bind matrices are inconsistent."},
      {"JSON_PARSE_FAILED", ExitCode::kInvalidInput, "A JSON input (preset, map, muscle file) is not valid JSON."},
      {"PRESET_INVALID", ExitCode::kInvalidInput, "A preset or naming map breaks its schema; the message gives the JSON pointer."},
      {"MAP_NOT_FOUND", ExitCode::kInvalidInput, "A naming map named on the command line does not exist among the shipped maps."},
      {"LANDMARK_UNRESOLVED", ExitCode::kInvalidInput, "A landmark the pipeline needs matches no joint and cannot be derived."},
      {"PRESET_LANDMARK_UNKNOWN", ExitCode::kInvalidInput, "A preset or naming map names a landmark that is not canonical."},
      {"MUSCLES_INVALID", ExitCode::kInvalidInput, "A muscle JSON file breaks the muscle schema."},
      {"MUSCLES_MISMATCH", ExitCode::kInvalidInput, "A muscle JSON file names joints that the character does not have."},
      {"JIGGLE_UNRESOLVED", ExitCode::kInvalidInput, "A jiggle preset names a joint, landmark or muscle the character does not have, or an unusable axis."},
      {"HITS_INVALID", ExitCode::kInvalidInput, "A hit file (--hits) breaks its schema or names a part that has no jiggle."},
      {"PACKED_FILE_INVALID", ExitCode::kInvalidInput, "A packed influence file (--packed-out) is damaged or not layout version 1."},
      {"MANIFEST_INVALID", ExitCode::kInvalidInput, "A build manifest breaks its schema or names an unknown muscles_from character."},
      {"BUILD_FAILED", ExitCode::kChecksFailed, "rigbake build finished, but at least one character failed; each is named in the summary."},
      {"VALIDATE_CONFIG_INVALID", ExitCode::kInvalidInput, "A `rigbake validate --config` file breaks its format; the message gives the JSON pointer."},
      {"RETARGET_LOCATOR_UNANCHORED", ExitCode::kInvalidInput, "A muscle locator rides on a joint with no canonical landmark on it or above it, so it cannot be retargeted."},
      {"RETARGET_SEGMENT_DEGENERATE", ExitCode::kInvalidInput, "Two landmarks that span a retarget frame coincide, so the segment has no direction."},
      {"GLTF_EXTENSION_UNSUPPORTED", ExitCode::kInvalidInput, "The glTF's extensionsRequired names an extension rigbake cannot honour, so it must not be loaded."},
      {"ROM_CLIP_UNKNOWN", ExitCode::kInvalidInput, "--clips names a clip the ROM preset does not have."},
      {"ROM_CLIP_UNAVAILABLE", ExitCode::kInvalidInput, "A ROM clip needs a landmark or joint the character lacks (no legs, no neck joint), or no ROM clip fits it at all."},
      {"ROM_CLIP_EXISTS", ExitCode::kInvalidInput, "The character already has an animation with a ROM clip's name (it is a ROM output already)."},
      {"VIEW_PLAYER_MISSING", ExitCode::kIo, "rigbake view cannot find the bundled player script (scripts/install-player.sh builds it)."},
      {"VIEW_NOT_BAKED", ExitCode::kInvalidInput, "rigbake view was given a file that is not a rigbake bake (no rig extension, muscle joints or packed influences)."},
      {"VIEW_BAKE_INVALID", ExitCode::kInvalidInput, "A baked file's RIGBAKE_muscle_rig extension or packed influence attributes are malformed, so the player cannot run it."},
      {"FBX_PARSE_FAILED", ExitCode::kInvalidInput, "The file is not a readable FBX (Assimp cannot import it: truncation, damage, not FBX) or uses a left-handed axis system."},
      {"VIEW_RIG_STRIPPED", ExitCode::kInvalidInput, "A baked file's muscle joints have neither the RIGBAKE_muscle_rig extension nor channels: a tool stripped the rig, so the player would show muscles that never move."},
      {"IO_OUTPUT_NOT_REGULAR", ExitCode::kIo, "An output path exists and is not a regular file (a device, FIFO, socket or directory), so it is not replaced."},
      {"BUILD_OUTPUT_LOCKED", ExitCode::kIo, "Another rigbake build is writing into the same output folder (it holds OUT/.rigbake-lock)."},
      {"BUILD_SOURCE_FAILED", ExitCode::kChecksFailed, "A build character's muscles_from source failed, so it could not be built (the run ends BUILD_FAILED)."},
      {"IO_INPUT_NOT_REGULAR", ExitCode::kInvalidInput, "An input path is a device, socket or directory, not a file to read (a FIFO or pipe is read)."},
      {"INPUT_TOO_LARGE", ExitCode::kInvalidInput, "An input file is larger than rigbake reads of its kind (2 GiB for a glTF, GLB or VRM, 64 MiB for JSON)."},
      {"VRM_CONVERSION_UNSUPPORTED", ExitCode::kInvalidInput, "bake --vrm asks for a VRM version the input cannot become: it is not a VRM, or it is a VRM 1.0 asked to be 0.x."},
      {"INTERNAL", ExitCode::kInternal, "A bug in rigbake: an invariant did not hold. Please report it with the input."},
  };
  return kCodes;
}

namespace {
std::string format(const std::string& code, const std::string& where, const std::string& message) {
  return where.empty() ? code + ": " + message : code + " " + where + ": " + message;
}
}  // namespace

size_t utf8SequenceAt(const std::string& text, size_t i) {
  const auto byte = [&](size_t k) { return k < text.size() ? static_cast<unsigned char>(text[k]) : 0u; };
  const unsigned lead = byte(i);
  auto continues = [&](size_t k, unsigned low, unsigned high) { return byte(k) >= low && byte(k) <= high; };
  if (lead < 0x80) return 1;
  if (lead >= 0xC2 && lead <= 0xDF) return continues(i + 1, 0x80, 0xBF) ? 2 : 0;
  if (lead >= 0xE0 && lead <= 0xEF) {
    const unsigned low = lead == 0xE0 ? 0xA0 : 0x80, high = lead == 0xED ? 0x9F : 0xBF;
    return continues(i + 1, low, high) && continues(i + 2, 0x80, 0xBF) ? 3 : 0;
  }
  if (lead >= 0xF0 && lead <= 0xF4) {
    const unsigned low = lead == 0xF0 ? 0x90 : 0x80, high = lead == 0xF4 ? 0x8F : 0xBF;
    return continues(i + 1, low, high) && continues(i + 2, 0x80, 0xBF) && continues(i + 3, 0x80, 0xBF) ? 4 : 0;
  }
  return 0;
}

std::string printableLine(const std::string& text) {
  static const char kHex[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const size_t length = utf8SequenceAt(text, i);
    if (length == 0 || c < 0x20 || c == 0x7F) {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
      ++i;
      continue;
    }
    out.append(text, i, length);
    i += length;
  }
  return out;
}

// The text of an error comes in part from the input (a parser's "last read: ..." quotes the file's
// bytes, a path is whatever bytes the file system holds): made one printable line of valid UTF-8, so
// that it is one line on a terminal and a JSON string in build summaries and --json output.
Error::Error(std::string code, std::string where, const std::string& message)
    : std::runtime_error(printableLine(format(code, where, message))), code_(std::move(code)), where_(printableLine(where)) {}

ExitCode Error::exitCode() const {
  for (const ErrorCodeInfo& info : errorCodes()) {
    if (code_ == info.code) return info.exit;
  }
  return ExitCode::kInternal;
}

void fail(const std::string& code, const std::string& where, const std::string& message) {
  throw Error(code, where, message);
}

}  // namespace rigbake
