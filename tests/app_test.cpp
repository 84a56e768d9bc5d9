// app/: the jobs that `rigbake bake`, `validate`, `build`, bench/ and these tests all run. A bad option
// is named by its field (the CLI and the manifest name it their own way); validate reads its file once.
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "anatomy_fixture.h"
#include "app/bake_job.h"
#include "cli_support.h"
#include "core/error.h"
#include "external_tools.h"
#include "formats/packed_file.h"
#include "test_support.h"

#include <catch2/catch.hpp>

using namespace rigbake;

namespace {

const app::Presets& appPresets() {
  static const app::Presets presets = app::loadPresets(test::presetsDir());
  return presets;
}

// The sample, placed from gow_biped, 4 influences, the preset's response kept (no fit: a quick bake).
app::BakeRequest quickSampleBake() {
  app::BakeRequest request;
  request.character.path = test::sampleGlbPath();
  request.output = "sample_baked.glb";
  request.options.response = ResponseMode::kKeep;
  return request;
}

// "field: problem" of the InvalidOption the job throws, or "none".
std::string invalidOption(const app::BakeRequest& request) {
  try {
    app::bakeJob(request, appPresets());
  } catch (const InvalidOption& option) {
    CHECK(option.code() == "USAGE");
    return option.field() + ": " + option.problem();
  }
  return "none";
}

}  // namespace

TEST_CASE("app: bakeJob names a bad option by its field, never by a command-line flag") {
  app::BakeRequest request = quickSampleBake();
  request.options.influences = 5;
  CHECK(invalidOption(request) == "influences: must be 4, 7 or 10 (got 5)");
  request = quickSampleBake();
  request.options.fps = -1.0;
  CHECK(invalidOption(request) == "fps: must be positive, or 0 for the clips' own key times");
  request = quickSampleBake();
  request.options.fit.max_poses = 0;
  CHECK(invalidOption(request) == "fit_poses: must be from 1 to 100000 (got 0)");
  request = quickSampleBake();
  request.options.fit.smoothness_weight = -1.0;
  CHECK(invalidOption(request) == "fit_smoothness: must be from 0 to 1000000 per metre of a 1.8 m body");
  request.options.fit.smoothness_weight = std::numeric_limits<double>::quiet_NaN();
  CHECK(invalidOption(request) == "fit_smoothness: must be from 0 to 1000000 per metre of a 1.8 m body");
  request = quickSampleBake();
  request.options.fit.roughness_cap = 0.5;  // a cap below plain skinning's own roughness: nothing could meet it
  CHECK(invalidOption(request) == "fit_roughness_cap: must be 0 (no cap) or from 1 to 100 times plain skinning's roughness rise");
  request.options.fit.roughness_cap = std::numeric_limits<double>::quiet_NaN();
  CHECK(invalidOption(request) == "fit_roughness_cap: must be 0 (no cap) or from 1 to 100 times plain skinning's roughness rise");
  request = quickSampleBake();
  request.options.fit.every_frame_regions = true;
  request.options.fit.occupied_volume = true;
  CHECK(invalidOption(request) == "fit_regions: every-frame cannot be combined with the occupied-volume fit");
  request = quickSampleBake();
  request.hits = test::presetsDir() + "/jiggle/biceps.json";  // never read: the check comes first
  CHECK(invalidOption(request) == "hits: needs a jiggle preset: hits kick jiggle joints");
  request = quickSampleBake();
  request.springs_only = true;
  CHECK(invalidOption(request) == "springs_only: needs a jiggle preset");
  request.jiggle = "biceps";
  CHECK(invalidOption(request) == "springs_only: " + test::sampleGlbPath() + " is not a VRM, so there is nowhere to put spring bones");
}

TEST_CASE("app: bakeJob makes every output's bytes and says what it baked") {
  app::BakeRequest request = quickSampleBake();
  request.jiggle = "biceps";
  request.packed = true;
  const app::BakeOutputs out = app::bakeJob(request, appPresets());
  // A GLB, whose stats name the files without their folders and count what was baked.
  REQUIRE(out.model.size() > 12);
  CHECK(out.model.compare(0, 4, "glTF") == 0);
  const nlohmann::json stats = nlohmann::json::parse(out.stats_json);
  CHECK(stats["character"] == std::filesystem::path(test::sampleGlbPath()).filename().string());
  CHECK(stats["output"] == "sample_baked.glb");
  CHECK(stats["influences"] == 4);
  CHECK(stats["muscle_joints"] == out.bake.muscles.parts.size());
  CHECK(stats["vertices"] == out.bake.vertex_count);
  CHECK(out.bake.vertex_count > 1000);
  CHECK(out.jiggles == 2);  // biceps: left and right
  CHECK(out.hits == 0);
  CHECK(!out.vrm_springs);
  // The muscle JSON names the preset by its name, and holds every baked part.
  const nlohmann::json muscles = nlohmann::json::parse(out.muscles_json);
  CHECK(muscles["rigbake"]["preset"] == "gow_biped");
  CHECK(muscles["rigbake"]["muscles"].size() == out.bake.muscles.parts.size());
  // The packed file: one part per skinned mesh part, each as baked.
  const std::vector<PackedInfluences> packed = decodePackedFile(out.packed, "packed");
  REQUIRE(packed.size() == out.bake.parts.size());
  for (size_t p = 0; p < packed.size(); ++p) CHECK(packed[p].vertex_count == out.bake.parts[p].packed.vertex_count);
  CHECK(out.character.loaded.notes.empty());
}

TEST_CASE("cli validate: a file whose landmarks do not resolve is read once, so a pipe works, and the report says why") {
  test::TempDir dir;
  const std::string fifo = dir / "piped.glb";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  // One writer, once: a second open of the pipe (a second parse) would wait for a writer that never
  // comes, which `timeout` turns into a failure (and the writer is timed out too should rigbake never
  // open the pipe).
  int written = -1;
  std::thread writer([&] {
    const std::string copy = "cat " + test::external::shellQuote(test::sampleGlbPath()) + " > " + test::external::shellQuote(fifo);
    written = std::system(("timeout 120 sh -c " + test::external::shellQuote(copy)).c_str());
  });
  const test::CliResult r =
      test::runCli("validate " + fifo + " --map mixamo --no-pictures --report " + (dir / "report"), "RIGBAKE_TEST=1 timeout 120");
  writer.join();
  CHECK(written == 0);
  CHECK(r.exit_code == 4);
  const nlohmann::json report = nlohmann::json::parse(test::slurp(dir / "report/report.json"));
  bool landmark_check = false;
  for (const auto& check : report["checks"]) {
    if (check["code"] != "LANDMARKS_RESOLVED") continue;
    landmark_check = true;
    CHECK(check["status"] == "fail");
    const std::string message = check["message"].get<std::string>();
    CHECK(message.rfind("LANDMARK_UNRESOLVED ", 0) == 0);
    // The report names no flag (build writes the same report); the command line's failing line does.
    CHECK(message.find("cannot be derived; give a JSON naming map") != std::string::npos);
    CHECK(message.find("--map") == std::string::npos);
  }
  CHECK(landmark_check);
  CHECK(r.err.find("LANDMARKS_RESOLVED piped.glb: error: LANDMARK_UNRESOLVED ") != std::string::npos);
  CHECK(r.err.find(" (pass --map)\n") != std::string::npos);
}
