// `rigbake retarget muscles.json --from SRC --to DST -o out.json`: move muscle data made for one
// character onto another (the talk's "Import/Export Muscle Data"). Method: anatomy/retarget.cpp.
#include <iostream>
#include <nlohmann/json.hpp>

#include "anatomy/retarget.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "formats/atomic_file.h"
#include "formats/json_text.h"
#include "formats/muscle_json.h"

namespace rigbake::cli {
namespace {

struct RetargetOptions {
  std::string muscles;
  std::string from;
  std::string to;
  std::string output;
  std::string preset = "gow_biped";
  std::string presets_dir;
  std::string map_from;
  std::string map_to;
  bool json = false;
};

int run(const RetargetOptions& options) {
  checkOutputOptions({{"-o", options.output, true, true}}, options.json);
  PresetOptions src_presets{options.presets_dir, options.map_from, "--map-from"};
  PresetOptions dst_presets{options.presets_dir, options.map_to, "--map-to"};
  MusclePreset preset = loadMusclePreset(src_presets, options.preset);
  ResolvedCharacter src = loadAndResolve(options.from, src_presets);
  // Read against the source: a file naming joints SRC lacks fails here with MUSCLES_MISMATCH.
  MuscleSet source = readMuscleJson(options.muscles, src.loaded.character, src.landmarks, preset);
  ResolvedCharacter dst = loadAndResolve(options.to, dst_presets);

  std::vector<CarriedLocator> carried;
  MuscleSet moved = retargetMuscles(source, src.loaded.character, src.landmarks, dst.loaded.character, dst.landmarks,
                                    preset, options.muscles, &carried);
  moved.character = fileNameOf(options.to);
  writeFileAtomically(options.output, muscleJson(moved, dst.loaded.character.skeleton, preset.name));

  if (options.json) {
    nlohmann::json locators = nlohmann::json::array();
    for (const CarriedLocator& entry : carried) {
      locators.push_back({{"part", entry.part},
                          {"locator", entry.locator},
                          {"frame", entry.frame},
                          {"from_joint", entry.src_joint},
                          {"to_joint", entry.dst_joint}});
    }
    std::cout << jsonText(nlohmann::json{{"from", fileNameOf(options.from)},
                                         {"to", moved.character},
                                         {"preset", preset.name},
                                         {"muscle_parts", moved.parts.size()},
                                         {"from_body_height", src.landmarks.body.height},
                                         {"to_body_height", dst.landmarks.body.height},
                                         {"locators", locators},
                                         {"output", options.output}})
              << "\n";
  } else {
    std::cerr << "retargeted " << moved.parts.size() << " muscle parts from " << fileNameOf(options.from)
              << " (body height " << src.landmarks.body.height << " m) to " << moved.character << " (body height "
              << dst.landmarks.body.height << " m) -> " << options.output << "\n";
  }
  return 0;
}

}  // namespace

void addRetargetCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<RetargetOptions>();
  CLI::App* command = app.add_subcommand(
      "retarget",
      "Move muscle data (placed or hand-tuned) from the character it was made for onto another one whose skeleton "
      "has other joint names, proportions, scale, units or facing. Each origin and insertion is carried in a frame "
      "between canonical landmarks (its attach joint's body segment, or for a preset part the segment its placement "
      "rule starts from), along the bone as a fraction of its length and across it as a fraction of body height, "
      "and rebuilt on the same landmarks of DST; each driver keeps its place between its muscle's ends. Accepts rigbake muscle JSON and the talk's positions-only export "
      "(whose attach joints then come from --preset). Writes muscle JSON for DST (docs/muscle-json.md); method and "
      "measured accuracy in docs/retarget.md.");
  command->add_option("muscles", options->muscles, "Muscle JSON made for --from")->required();
  command->add_option("--from", options->from, "Character the muscle file was made for (.glb, .gltf, .vrm, .fbx)")
      ->required();
  command->add_option("--to", options->to, "Character to move the muscles onto (.glb, .gltf, .vrm, .fbx)")->required();
  command->add_option("-o,--output", options->output, "Muscle JSON to write for --to; - for standard output")->required();
  command->add_option("--preset", options->preset,
                      "Muscle preset giving each part's attach landmarks and placement rule: a file, or a name under presets/muscles/")
      ->capture_default_str();
  command->add_option("--presets", options->presets_dir,
                      "Directory of presets (skeletons/, muscles/, landmarks.json); default: $RIGBAKE_PRESETS or the "
                      "presets/ shipped with rigbake");
  command->add_option("--map-from", options->map_from,
                      "Skeleton naming map for --from: a JSON file or a shipped map name. Default: auto-detect");
  command->add_option("--map-to", options->map_to,
                      "Skeleton naming map for --to: a JSON file or a shipped map name. Default: auto-detect");
  command->add_flag("--json", options->json,
                    "Print a JSON summary on stdout, with the frame and joints each locator was carried by");
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
