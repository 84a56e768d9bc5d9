// Times the stages of one bake in this process and prints one JSON line: seconds per stage and the
// peak resident memory. bench/run calls it once per input (a fresh process, so the peak is the
// input's own) and prints the table.
//
// A re-bake takes two processes, as a user's two commands: `fit MUSCLES.json` bakes once (untimed) and
// writes the muscles with their fitted curves, as `bake --muscles-out` does; `fitted MUSCLES.json`
// times a bake with them, read as `bake --muscles` reads them (`--response auto` keeps fitted curves: no
// fit stage). In one process the re-bake's peak memory was the first bake's, and its heap was warm.
// `error-only MUSCLES.json` is that re-bake without the volume figures (BakeOptions::measure_quality
// off): the work issue 14 was filed against, before issue 11 added the response fit and the per-frame
// volumes of three skinnings; every frame of every clip still gets the deformation error.
#include <sys/resource.h>

#include <chrono>
#include <iostream>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "anatomy/body_regions.h"
#include "anatomy/placement.h"
#include "formats/gltf_bake.h"
#include "formats/gltf_document.h"
#include "formats/gltf_write.h"
#include "formats/muscle_json.h"
#include "formats/atomic_file.h"
#include "formats/preset_json.h"
#include "pipeline/bake.h"

using namespace rigbake;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: rigbake_bench INPUT OUTPUT.glb PRESETS_DIR [influences [threads [fit|fitted|error-only MUSCLES.json]]]\n";
    return 1;
  }
  const std::string input = argv[1], output = argv[2], presets = argv[3];
  const int influences = argc > 4 ? std::stoi(argv[4]) : 10;
  const int threads = argc > 5 ? std::stoi(argv[5]) : 0;  // 0: one per core, as bake --threads
  const std::string mode = argc > 6 ? argv[6] : "";
  if (!mode.empty() && (argc < 8 || (mode != "fit" && mode != "fitted" && mode != "error-only"))) {
    std::cerr << "rigbake_bench: the sixth argument is 'fit', 'fitted' or 'error-only', followed by a muscle JSON path\n";
    return 1;
  }
  const std::string muscles_path = argc > 7 ? argv[7] : "";
  const bool error_only = mode == "error-only";
  const bool fitted = mode == "fitted" || error_only;
  auto clock = std::chrono::steady_clock::now();
  auto lap = [&clock]() {
    auto now = std::chrono::steady_clock::now();
    double seconds = std::chrono::duration<double>(now - clock).count();
    clock = now;
    return seconds;
  };
  try {
    LoadedCharacter loaded = loadCharacter(input);
    const double load = lap();
    std::vector<NamingMap> maps = readNamingMaps(presets + "/skeletons");
    LandmarkRules rules = readLandmarkRules(presets + "/landmarks.json");
    MusclePreset preset = readMusclePreset(presets + "/muscles/gow_biped.json");
    LandmarkInputs inputs;
    inputs.maps = &maps;
    inputs.rules = &rules;
    LandmarkSet landmarks = resolveLandmarks(loaded.character, inputs);
    MuscleSet muscles = fitted ? readMuscleJson(muscles_path, loaded.character, landmarks, preset)
                               : placeMuscles(loaded.character, landmarks, preset, Sides::kBoth);
    BakeOptions options;
    options.influences = influences;
    options.threads = threads;
    options.measure_quality = !error_only;
    // The body regions `bake` measures and fits by default (--regions body): without them the bench
    // timed a lighter fit and lighter figures than the CLI runs.
    const RegionPreset region_preset = readRegionPreset(presets + "/regions/body.json");
    options.regions = resolveBodyRegions(loaded.character, landmarks, region_preset);
    options.creases = resolveCreases(loaded.character, landmarks, region_preset.creases);
    const double place = lap();
    if (mode == "fit") {
      const MuscleSet fitted_muscles = bakeCharacter(loaded.character, muscles, options).muscles;
      writeFileAtomically(muscles_path, muscleJson(fitted_muscles, loaded.character.skeleton, preset.name));
      return 0;
    }
    BakeTimings timings;
    BakeResult bake = bakeCharacter(loaded.character, muscles, options, &timings);
    lap();
    writeGltf(bakedModel(*loaded.document, loaded.character, bake), output);
    const double write = lap();
    // Frames sampled over every clip: with the vertices and influences, the bench's unit of work.
    size_t frames = 0;
    for (const BakedClip& clip : bake.clips) frames += clip.times.size();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::cout << nlohmann::json{{"input", input},
                                {"vertices", bake.vertex_count},
                                {"clips", bake.clips.size()},
                                {"frames", frames},
                                {"influences", influences},
                                {"threads", threads},
                                {"fitted", fitted},
                                {"volumes", !error_only},
                                {"load", load},
                                {"place", place},
                                {"evaluate", timings.evaluate},
                                {"weights", timings.weights},
                                {"fit", timings.fit},
                                {"pack", timings.pack},
                                {"error", timings.error},
                                {"quality", timings.quality},
                                {"write", write},
                                {"peak_mb", usage.ru_maxrss / 1024.0}}
                     .dump()
              << "\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 3;
  }
  return 0;
}
