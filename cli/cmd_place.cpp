// `rigbake place CHAR -o muscles.json`: place the preset's muscles on the left side and mirror them.
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "anatomy/placement.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "formats/atomic_file.h"
#include "formats/json_text.h"
#include "formats/muscle_json.h"

namespace rigbake::cli {
namespace {

struct PlaceOptions {
  std::string character;
  std::string preset = "gow_biped";
  std::string side = "both";
  std::string output;
  PresetOptions presets;
  bool json = false;
};

int run(const PlaceOptions& options) {
  checkOutputOptions({{"-o", options.output, true, true}}, options.json);
  Sides sides = options.side == "left" ? Sides::kLeft : options.side == "right" ? Sides::kRight : Sides::kBoth;
  MusclePreset preset = loadMusclePreset(options.presets, options.preset);
  ResolvedCharacter resolved = loadAndResolve(options.character, options.presets);
  const Character& character = resolved.loaded.character;
  MuscleSet muscles = placeMuscles(character, resolved.landmarks, preset, sides);
  muscles.character = fileNameOf(options.character);
  writeFileAtomically(options.output, muscleJson(muscles, character.skeleton, preset.name));
  if (options.json) {
    std::cout << jsonText(nlohmann::json{{"character", muscles.character},
                                         {"preset", preset.name},
                                         {"muscle_parts", muscles.parts.size()},
                                         {"body_height", muscles.body_height},
                                         {"output", options.output}})
              << "\n";
  } else {
    std::cerr << "placed " << muscles.parts.size() << " muscle parts of " << preset.name << " on " << muscles.character
              << " (body height " << muscles.body_height << " m) -> " << options.output << "\n";
  }
  return 0;
}

}  // namespace

void addPlaceCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<PlaceOptions>();
  CLI::App* command = app.add_subcommand(
      "place",
      "Place the muscle locators of an anatomy preset (origin, insertion and driver of every muscle part) on the left "
      "side and mirror them to the right across the body's sagittal plane. Writes muscle JSON in the talk's export "
      "shape plus attach joints and factors (docs/muscle-json.md). Units: metres.");
  command->add_option("character", options->character, "Character file (.glb, .gltf, .vrm, .fbx)")->required();
  command->add_option("-o,--output", options->output, "Muscle JSON to write; - for standard output")->required();
  command->add_option("--preset", options->preset, "Muscle preset: a file, or a name under presets/muscles/")
      ->capture_default_str();
  command->add_option("--side", options->side, "Which sides to write")
      ->check(CLI::IsMember({"left", "right", "both"}))
      ->capture_default_str();
  addPresetOptions(command, &options->presets);
  command->add_flag("--json", options->json, "Print a JSON summary on stdout");
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
