// `rigbake view baked.glb -o DIR`: a page that plays a baked character in the browser with the rigbake
// player (player/, docs/view.md): the muscles and jiggles evaluated live by the runtime compiled to
// WebAssembly (the rigbake-three plugin), 4, 7 or 10 influences skinned from the packed attributes, the
// heatmap and the jiggles' hit button. Works from file:// with no server and no network.

#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "formats/atomic_file.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_write.h"
#include "formats/json_text.h"
#include "formats/view_page.h"

namespace rigbake::cli {
namespace {

struct ViewCommandOptions {
  std::string baked;
  std::string output;
  std::string player;
  bool json = false;
};

// The bundle scripts/install-player.sh builds, beside the source tree's presets (as the presets are
// found): RIGBAKE_DEFAULT_PRESET_DIR is <source>/presets.
std::string defaultPlayerBundle() {
  if (const char* env = std::getenv("RIGBAKE_PLAYER")) return env;
  return (std::filesystem::path(RIGBAKE_DEFAULT_PRESET_DIR).parent_path() / ".tools" / "player" / kViewPlayerFile).string();
}

// One of the files scripts/install-player.sh writes, or VIEW_PLAYER_MISSING: `missing` when it cannot be
// read, "is not the NAME (no MARKER in it)" when it lacks the marker the installer builds into it.
std::string readPlayerFile(const std::string& path, const std::string& marker, const std::string& name,
                           const std::string& missing) {
  std::string text;
  try {
    text = readFile(path);
  } catch (const Error&) {
    fail(errc::VIEW_PLAYER_MISSING, path, missing);
  }
  if (text.find(marker) == std::string::npos)
    fail(errc::VIEW_PLAYER_MISSING, path, "is not " + name + " (no " + marker + " in it): run scripts/install-player.sh");
  return text;
}

std::string readPlayerBundle(const std::string& path) {
  return readPlayerFile(path, "RigbakePlayer", "the rigbake player bundle",
                        "the bundled player is not there: run scripts/install-player.sh (it installs three.js and esbuild "
                        "from player/package-lock.json and builds the bundle), or pass --player FILE");
}

// Three's Draco decoder files as one script (scripts/install-player.sh writes it beside the bundle), for a
// Draco-compressed file's page.
std::string readDracoScript(const std::string& player_path) {
  return readPlayerFile((std::filesystem::path(player_path).parent_path() / kViewDracoFile).string(), "RIGBAKE_DRACO",
                        "the player's Draco decoder script",
                        "the Draco decoder script a KHR_draco_mesh_compression file's page needs is not beside the player "
                        "bundle: run scripts/install-player.sh");
}

// What would break the player: a malformed rig extension, packed attributes that do not decode.
void checkViewable(const std::string& path, const BakedFileData& file) {
  if (!file.rig.problems.empty()) {
    std::string list;
    for (size_t k = 0; k < file.rig.problems.size() && k < 3; ++k) list += (k ? "; " : "") + file.rig.problems[k];
    fail(errc::VIEW_BAKE_INVALID, path, "its RIGBAKE_muscle_rig extension cannot be evaluated: " + list);
  }
  for (const FileSkinAttributes& skin : file.skins) {
    if (skin.carries_packed && !skin.has_packed)
      fail(errc::VIEW_BAKE_INVALID, path + "#" + skin.pointer,
           "its _RIGBAKE_PACKED_* attributes do not decode as docs/packed-influences.md lays them out");
  }
  // Muscle joints that nothing moves: the extension is gone and the joints have no channels (issue 31).
  if (const int undriven = undrivenMuscleJoints(file); undriven > 0) {
    fail(errc::VIEW_RIG_STRIPPED, path,
         std::to_string(undriven) + " muscle joints without RIGBAKE_muscle_rig or channels: the rig was stripped "
         "(gltfpack and glTF-Transform without rigbake's config drop it); view the bake itself (docs/pipelines.md)");
  }
  bool baked = file.rig.present || !file.muscle_nodes.empty();
  for (const FileSkinAttributes& skin : file.skins) baked |= skin.has_packed;
  if (!baked)
    fail(errc::VIEW_NOT_BAKED, path,
         "has no RIGBAKE_muscle_rig extension, no muscle joints and no packed influences: it is not a rigbake bake. "
         "Bake it first (rigbake bake " + fileNameOf(path) + " -o baked.glb), then view baked.glb");
}

int run(const ViewCommandOptions& options) {
  const std::string player_path = options.player.empty() ? defaultPlayerBundle() : options.player;
  const std::string bundle = readPlayerBundle(player_path);
  LoadedCharacter loaded = loadCharacter(options.baked);
  const BakedFileData file = readBakedFileData(loaded);
  checkViewable(options.baked, file);
  // A GLB (or VRM) goes in byte for byte, compressed or not (the page decodes meshopt and Draco); a .gltf
  // with its buffers and images beside it becomes one GLB.
  const std::string glb = glbOf(options.baked, *loaded.document);
  const std::string draco = glbUsesExtension(glb, "KHR_draco_mesh_compression") ? readDracoScript(player_path) : std::string();
  const auto files = viewPageFiles(fileNameOf(options.baked), glb, bundle, draco);
  writeViewDirectory(options.output, files);

  long long page_bytes = 0;
  for (const auto& entry : files) page_bytes += static_cast<long long>(entry.second.size());
  int packed = 0;
  for (const FileSkinAttributes& skin : file.skins) packed = std::max(packed, skin.has_packed ? skin.packed.influences : 0);
  if (options.json) {
    nlohmann::json files_json = nlohmann::json::object();
    for (const auto& [name, bytes] : files) files_json[name] = bytes.size();
    std::cout << jsonText(nlohmann::json({{"input", fileNameOf(options.baked)},
                                          {"output", options.output},
                                          {"files", files_json},
                                          {"page_bytes", page_bytes},
                                          {"clips", loaded.character.clips.size()},
                                          {"muscles", file.rig.present ? file.rig.names.size() : 0},
                                          {"rig_extension", file.rig.present},
                                          {"packed_influences", packed}}))
              << "\n";
  }
  std::cerr << std::fixed << std::setprecision(1) << "wrote " << (std::filesystem::path(options.output) / kViewPageFile).string()
            << ": " << loaded.character.clips.size() << " clips, "
            << (file.rig.present ? std::to_string(file.rig.names.size()) + " muscles evaluated live" : std::string("no rig extension"))
            << ", " << (packed ? std::to_string(packed) + " packed influences" : std::string("no packed influences")) << ", "
            << page_bytes / 1.0e6 << " MB in all; open it in a browser (file:// works, no server needed)\n";
  return 0;
}

}  // namespace

void addViewCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<ViewCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "view",
      "Write a page that plays a baked character in the browser (three.js, WebGL 2), from file:// with no server and "
      "no network: every clip (a selector, opening on the one that moves the arms most; a time scrubber, frame steps with "
      "the , and . keys, an orbit camera that frames a chosen joint, F again, and a floor grid), the RIGBAKE_muscle_rig muscles and jiggles evaluated live from the skeleton "
      "by rigbake's runtime compiled to WebAssembly (runtime), played from the file's channels (sampled) or left at rest (off: the input's "
      "own skinning), 4 influences (three.js's own skinning of JOINTS_0/WEIGHTS_0) or 7 / 10 from the packed 0.001 "
      "weights in the player's shader, a heatmap of how far the muscles move the skin against plain skinning, and a "
      "Hit button that kicks the live jiggles. DIR gets index.html, rigbake-player.js (the player, the rigbake-three "
      "plugin, the WebAssembly runtime and three.js in one script, built by scripts/install-player.sh) and model.js "
      "(the GLB as base64; meshopt- and Draco-compressed files play, a Draco file's page gets rigbake-draco.js, the "
      "decoder); open DIR/index.html. The same "
      "input gives the same bytes. docs/view.md says what the page shows.\n\n"
      "Example:\n"
      "  rigbake bake hero.glb --influences 10 --muscle-motion both --jiggle biceps -o baked.glb\n"
      "  rigbake view baked.glb -o baked-view\n"
      "  chromium baked-view/index.html");
  command->add_option("baked", options->baked, "Baked glTF (.glb, .vrm or .gltf) from `rigbake bake`")->required();
  command->add_option("-o,--output", options->output,
                      "Directory to write the page into; created, or replaced when it holds a page rigbake view wrote "
                      "before (anything else in it is an error)")
      ->required();
  command->add_option("--player", options->player,
                      "The player bundle to copy (default: $RIGBAKE_PLAYER, else .tools/player/rigbake-player.js of the "
                      "source tree, which scripts/install-player.sh builds)");
  command->add_flag("--json", options->json, "Print what was written as JSON on stdout (files and bytes, clips, muscles)");
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
