// `rigbake rom CHAR -o CHAR_rom.glb`: the character with range-of-motion clips added as ordinary glTF
// animations, for looking at the skinning in any viewer (and for `bake --rom` / `validate --rom`,
// which measure on the same clips without writing them).
#include <iostream>
#include <set>

#include "core/error.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "formats/gltf_clips.h"
#include "formats/atomic_file.h"
#include "formats/gltf_write.h"
#include "formats/rom_json.h"
#include "formats/json_text.h"
#include "pipeline/rom.h"

namespace rigbake::cli {
namespace {

struct RomCommandOptions {
  std::string character;
  std::string output;
  std::string preset = "default";
  std::string clips;
  bool json = false;
  PresetOptions presets;
};

int run(const RomCommandOptions& options) {
  checkOutputOptions({{"-o", options.output, true}});
  const std::vector<std::string> only = splitClipNames(options.clips, "--clips");
  const RomPreset preset = loadRomPreset(options.presets, options.preset);
  ResolvedCharacter resolved = loadAndResolve(options.character, options.presets);
  const Character& character = resolved.loaded.character;
  const RomResult rom = buildRom(character, resolved.landmarks, preset, only);
  std::vector<Clip> clips;
  std::set<int> keyed;
  for (const RomClip& clip : rom.clips) {
    clips.push_back(clip.clip);
    for (const Track& track : clip.clip.tracks) keyed.insert(track.joint);
  }
  // Everything is computed before anything is written, so a failure leaves no output behind.
  writeFileAtomically(options.output, gltfWithClips(*resolved.loaded.document, character, clips, isBinaryGltfPath(options.output)));

  if (options.json) {
    nlohmann::json summary = {{"character", fileNameOf(options.character)},
                              {"output", fileNameOf(options.output)},
                              {"preset", preset.name},
                              {"own_clips", character.clips.size()},
                              {"joints_keyed", keyed.size()}};
    summary.update(romJson(rom, character.skeleton));
    std::cout << jsonText(summary) << "\n";
  }
  std::cerr << "wrote " << options.output << ": " << rom.clips.size() << " ROM clips of " << preset.name << " on "
            << keyed.size() << " joints, after the character's " << character.clips.size() << " own clips\n";
  for (const RomSkipped& skipped : rom.skipped)
    std::cerr << "skipped " << skipped.name << ": " << skipped.reason << "\n";
  return 0;
}

}  // namespace

void addRomCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<RomCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "rom",
      "Add range-of-motion clips to a character, the riggers' skin test: each major joint swept through its normal "
      "range, one motion per clip, both sides mirrored, rising from the start angle to the peak and back (or swinging "
      "both ways). The default preset (presets/rom/default.json, docs/rom.md) sweeps elbow flexion to 130 degrees, "
      "shoulder abduction 10-170 and flexion to 160 (the clavicle elevating with the arm), forearm twist +-80, spine "
      "flexion 80 and twist +-45, neck flexion +-45, and where the skeleton has legs hip flexion 120, knee flexion 135 "
      "and hip abduction 45. Clips are built from the landmarks and the body frame, so each means the same motion "
      "whatever the joint names, facing, units or rest pose; a clip the character cannot do (no legs) is skipped and "
      "named. They are written as ordinary LINEAR rotation animations named rom_*, after the character's own, which "
      "stay untouched. To measure skinning on them without writing them, use `rigbake bake --rom` or "
      "`rigbake validate --rom`.\n\nExample: rigbake rom hero.glb -o hero_rom.glb --clips elbow_flexion,knee_flexion");
  command->add_option("character", options->character, "Character file (.glb, .gltf, .vrm, .fbx)")->required();
  command->add_option("-o,--output", options->output,
                      "glTF to write: the character plus the ROM clips (.glb/.vrm binary, .gltf JSON)")
      ->required();
  command->add_option("--preset", options->preset,
                      "ROM preset: a file, or a name under presets/rom/ (ranges, curves, durations, key rate, joint "
                      "shares; docs/rom.md)")
      ->capture_default_str();
  command->add_option("--clips", options->clips,
                      "Only these preset clips, comma-separated (e.g. elbow_flexion,hip_flexion); a named clip the "
                      "character cannot do is an error (ROM_CLIP_UNAVAILABLE)");
  addPresetOptions(command, &options->presets);
  command->add_flag("--json", options->json,
                    "Print a JSON summary on stdout: every clip's animation name, duration, keys, range, peak time, "
                    "and per side its axis, rest angle and the joints keyed; the clips skipped and why");
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
