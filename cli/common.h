// What several subcommands share: finding the presets, loading a character and resolving its
// landmarks from flags.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/file_name.h"  // fileNameOf(): outputs name inputs without directories
#include "anatomy/landmarks.h"
#include "core/error.h"
#include "app/character.h"
#include "anatomy/presets.h"
#include "formats/gltf_document.h"
#include "pipeline/rom.h"

namespace rigbake::cli {

struct PresetOptions {
  std::string presets_dir;  // --presets; default: $RIGBAKE_PRESETS or the source tree's presets/
  std::string map;          // --map: a naming map file, or the name of a shipped map
  const char* map_flag = "--map";  // how this command spells the flag that gives `map` (retarget: --map-from, --map-to)
};

void addPresetOptions(CLI::App* command, PresetOptions* options);
std::string presetsDirectory(const PresetOptions& options);

// A preset file by path, or by name under presets/KIND/ (muscles, jiggle); IO_FILE_NOT_FOUND otherwise.
std::string presetFile(const PresetOptions& options, const std::string& kind, const std::string& name_or_path);

// A muscle preset by file path, or by name under presets/muscles/.
MusclePreset loadMusclePreset(const PresetOptions& options, const std::string& name_or_path);

// A ROM preset by file path, or by name under presets/rom/ (docs/rom.md).
RomPreset loadRomPreset(const PresetOptions& options, const std::string& name_or_path);

// "a,b" -> {"a", "b"} for --clips; USAGE for an empty name.
std::vector<std::string> splitClipNames(const std::string& list, const std::string& option);

// An output named on the command line, checked before any work: a required one may not be empty (USAGE),
// and none may be an existing device, FIFO, socket or directory (IO_OUTPUT_NOT_REGULAR). "-" is standard
// output where `to_stdout` allows it (JSON outputs, docs/output-contract.md) and USAGE elsewhere; at most
// one output may be "-", and none when `json_on_stdout` (--json already prints there).
struct OutputOption {
  const char* option;
  const std::string& path;
  bool required;
  bool to_stdout = false;
};
void checkOutputOptions(std::initializer_list<OutputOption> outputs, bool json_on_stdout = false);

using ResolvedCharacter = app::ResolvedCharacter;

// app::loadCharacter() with the flags' presets directory and --map, its notes printed on stderr (what an
// FBX or a VRM 0.x -> 1.0 conversion did and left out; a glTF input loaded as it is has none).
ResolvedCharacter loadAndResolve(const std::string& path, const PresetOptions& options, const LoadOptions& load = {});
// Prints each note of the file at `path` on stderr as it comes ("note PATH: ...").
app::NoteReport printNotesOf(const std::string& path);

// Where an options struct's field comes from on the command line: app/ and pipeline/ name a bad option
// by its field (InvalidOption, core/error.h), the user knows the flag.
struct FlagName {
  const char* field;  // e.g. "influences" (BakeOptions::influences)
  const char* flag;   // e.g. "--influences"
};

// Runs `call`; an InvalidOption it throws becomes the USAGE error of the field's flag, in the same words,
// and an error that an option would fix (FixableByOption) keeps its code and gets "(pass FLAG)".
template <typename Call>
auto withFlagNames(const std::vector<FlagName>& flags, Call&& call) -> decltype(call()) {
  try {
    return call();
  } catch (const InvalidOption& option) {
    for (const FlagName& name : flags)
      if (option.field() == name.field) fail(errc::USAGE, name.flag, option.problem());
    throw;
  } catch (const FixableByOption& fixable) {
    for (const FlagName& name : flags)
      if (fixable.field() == name.field)
        fail(fixable.errorCode(), fixable.where(), fixable.message() + " (pass " + name.flag + ")");
    throw;
  }
}

}  // namespace rigbake::cli
