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
// `stats` is a first bake that also measures the skin's surface figures (seams, joint regions,
// roughness, centres of rotation, creases: BakeOptions::measure_skin), as `bake --stats` or `--json`
// does; a plain `rigbake bake`, and the other modes, leave them to `rigbake validate`.
//
// The bake is app::bakeJob's, as `rigbake bake` runs it; the stages are its BakeJobTimings: load (the file
// and its landmarks), place (muscle preset, muscles, body regions), the bake's own stages, and write (the
// bytes of every output bake makes: model, stats, packed influences, muscle JSON; not the disk write).
#include <sys/resource.h>

#include <iostream>
#include <nlohmann/json.hpp>

#include "app/bake_job.h"
#include "formats/atomic_file.h"

using namespace rigbake;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: rigbake_bench INPUT OUTPUT.glb PRESETS_DIR [influences [threads [stats | fit|fitted|error-only MUSCLES.json]]]\n";
    return 1;
  }
  const std::string input = argv[1], output = argv[2], presets = argv[3];
  const int influences = argc > 4 ? std::stoi(argv[4]) : 10;
  const int threads = argc > 5 ? std::stoi(argv[5]) : 0;  // 0: one per core, as bake --threads
  const std::string mode = argc > 6 ? argv[6] : "";
  if (!mode.empty() && mode != "stats" && (argc < 8 || (mode != "fit" && mode != "fitted" && mode != "error-only"))) {
    std::cerr << "rigbake_bench: the sixth argument is 'stats', or 'fit', 'fitted' or 'error-only' followed by a muscle JSON path\n";
    return 1;
  }
  const std::string muscles_path = mode != "stats" && argc > 7 ? argv[7] : "";
  const bool error_only = mode == "error-only";
  const bool fitted = mode == "fitted" || error_only;
  try {
    // As `rigbake bake INPUT --influences N --threads T -o OUTPUT` bakes it (gow_biped, the body regions),
    // with the muscles of `fitted` read as --muscles reads them.
    app::BakeRequest request;
    request.character.path = input;
    request.output = output;
    request.muscles = fitted ? muscles_path : "";
    request.options.influences = influences;
    request.options.threads = threads;
    request.options.measure_quality = !error_only;
    request.options.measure_skin = mode == "stats";
    const app::Presets presets_read = app::loadPresets(presets);
    const app::BakeOutputs out = app::bakeJob(request, presets_read);
    if (mode == "fit") {
      writeFileAtomically(muscles_path, out.muscles_json);
      return 0;
    }
    writeFileAtomically(output, out.model);
    const BakeResult& bake = out.bake;
    const app::BakeJobTimings& timings = out.timings;
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
                                {"skin_figures", mode == "stats"},
                                {"load", timings.load},
                                {"place", timings.place},
                                {"evaluate", timings.bake.evaluate},
                                {"weights", timings.bake.weights},
                                {"fit", timings.bake.fit},
                                {"pack", timings.bake.pack},
                                {"error", timings.bake.error},
                                {"quality", timings.bake.quality},
                                {"write", timings.write},
                                {"peak_mb", usage.ru_maxrss / 1024.0}}
                     .dump()
              << "\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 3;
  }
  return 0;
}
