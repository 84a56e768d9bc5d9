// `rigbake view` and the three.js player (player/, docs/view.md) on the rigbake-three plugin
// (player/plugin/). The CLI cases check the errors, the help, the atomic output and the deterministic
// bytes with a stand-in player bundle; the Chromium cases build real pages with the installed bundle
// (scripts/install-player.sh; $RIGBAKE_PLAYER when set) and open them in headless Chromium through
// player/test/run_page.mjs, which waits (in real time) for the page's self-test (index.html?test=1,
// player/src/self_test.js) and returns what it wrote into the DOM and every console message. The
// agreement cases hand the page a reference computed here: rigbake's C++ runtime
// (runtime::MuscleRigJob<double> on the file's RIGBAKE_muscle_rig extension) and skinning (skinLinearBlend
// with the packed 0.001 weights) at sampled clip times, and the native C API's muscles and jiggles frame by
// frame; the plugin (the WebAssembly runtime) and the GPU-skinned positions (read back by transform
// feedback) must match them.
#include <tiny_gltf.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cli_support.h"
#include "external_tools.h"
#include "glb_support.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "formats/base64.h"
#include "formats/view_page.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pack_influences.h"
#include "pipeline/pose.h"
#include "pipeline/skinning.h"
#include "runtime/muscle_rig.h"
#include "runtime/rigbake_runtime.h"

namespace rigbake::view_test {

namespace ext = rigbake::test::external;
using test::TempDir;

constexpr double kAgreement = 1e-5;  // metres and radians, the bound
// The muscle matrices' rotation/scale terms (relative to the matrix's size) between the float runtime the
// browser runs and the double C++ reference: float's rounding of the length ratio (1e-6) times the slope
// of the scale curve (up to about 10) gives up to 1.2e-5 (CesiumMan); what that moves a vertex is what
// the GPU skinning comparison measures, in metres, under kAgreement.
constexpr double kFloatTerms = 5e-5;

std::string viewArg(const std::string& text) { return ext::shellQuote(text); }

// The bundle `rigbake view` copies: $RIGBAKE_PLAYER when set (as the command reads it), else the installed one.
std::string installedPlayer() {
  if (const char* env = std::getenv("RIGBAKE_PLAYER")) return env;
  return test::sourceDir() + "/.tools/player/" + kViewPlayerFile;
}
std::string pageRunner() { return test::sourceDir() + "/player/test/run_page.mjs"; }

std::string viewChromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    if (ext::onPath(name)) return name;
  }
  return "";
}

// Chromium, node and the installed player bundle; under CI=true a missing one fails the test.
bool browserToolsPresent() {
  return ext::requireTool(!viewChromium().empty(), "chromium (apt-get install chromium)") &&
         ext::requireTool(ext::onPath("node"), "node (scripts/install-deps.sh)") &&
         ext::requireTool(test::fileExists(installedPlayer()), "the rigbake player bundle " + installedPlayer() +
                                                                   " (run scripts/install-player.sh)");
}

// A stand-in bundle for the CLI cases: rigbake view only checks that it is the player.
std::string fakePlayer(const TempDir& dir) {
  const std::string path = dir / "fake-player.js";
  std::ofstream(path, std::ios::binary) << "window.RigbakePlayer = {startPage() {}};\n";
  return path;
}

std::string bakeForView(const std::string& character, const std::string& flags, const std::string& out) {
  const test::CliResult bake = test::runCli("bake " + viewArg(character) + " " + flags + " -o " + viewArg(out));
  INFO(bake.err);
  REQUIRE(bake.exit_code == 0);
  return out;
}

// ---- the C++ reference ----

struct ReferenceCounts {
  int capi_frames = 0;
  int jiggles = 0;
  int matrix_frames = 0;
  int skin_frames = 0;
  int skin_vertices = 0;
  int muscles = 0;
  int clips = 0;
};

std::string doublesBase64(const std::vector<Eigen::Vector3d>& points) {
  std::string bytes(points.size() * 3 * sizeof(double), '\0');
  for (size_t v = 0; v < points.size(); ++v) {
    for (int c = 0; c < 3; ++c) {
      const double value = points[v][c];
      std::memcpy(&bytes[(3 * v + c) * sizeof(double)], &value, sizeof(double));  // little endian, as the page reads it
    }
  }
  return base64Encode(bytes);
}

// The muscle matrices, drivers and helpers of the C++ runtime at `fractions` of every clip's
// duration, and the skinned positions at `skin_fractions`, as the page's window.RIGBAKE_REFERENCE.
nlohmann::json cppReference(const std::string& glb, const std::vector<double>& fractions,
                            const std::vector<double>& skin_fractions, bool with_helpers, ReferenceCounts* counts) {
  const LoadedCharacter loaded = loadCharacter(glb);
  const BakedFileData file = readBakedFileData(loaded);
  REQUIRE(file.rig.present);
  REQUIRE(file.rig.problems.empty());
  const Character& character = loaded.character;
  const Skeleton& skeleton = character.skeleton;
  const runtime::MuscleRig<double>& rig = file.rig.rig;
  const size_t muscles = rig.muscles.size();
  counts->muscles = static_cast<int>(muscles);

  // Per skinned primitive its packed 0.001 weights on skeleton joints.
  struct SkinPart {
    const MeshPart* mesh;
    InfluenceSet influences;
  };
  std::vector<SkinPart> parts;
  for (const FileSkinAttributes& skin : file.skins) {
    REQUIRE(skin.has_packed);
    const MeshPart& mesh = character.meshes[skin.mesh_part];
    const QuantizedInfluences quantized = unpackInfluences(skin.packed);
    SkinPart part{&mesh, {}};
    part.influences.slots_per_vertex = quantized.slots_per_vertex;
    for (size_t i = 0; i < quantized.joints.size(); ++i) {
      part.influences.joints.push_back(mesh.skin_joints[quantized.joints[i]]);
      part.influences.weights.push_back(quantized.weights[i] / 1000.0);
    }
    parts.push_back(std::move(part));
  }

  auto evaluate = [&](const Pose& pose, std::vector<double>* skinned, std::vector<double>* helpers,
                      std::vector<runtime::MuscleDrivers<double>>* drivers) {
    const std::vector<double> joints = jointMatrices(pose);
    skinned->assign(16 * muscles, 0.0);
    helpers->assign(48 * muscles, 0.0);
    drivers->assign(muscles, {});
    runtime::MuscleRigJob<double> job;
    job.rig = &rig;
    job.joint_matrices = runtime::Span<const double>(joints.data(), joints.size());
    job.skinned_matrices = *skinned;
    job.helper_matrices = *helpers;
    job.drivers = *drivers;
    REQUIRE(job.Run());
  };

  nlohmann::json clips = nlohmann::json::array();
  nlohmann::json skin_frames = nlohmann::json::array();
  for (const Clip& clip : character.clips) {
    if (clip.gltf_animation < 0 || clip.measure_only) continue;
    ++counts->clips;
    nlohmann::json entry = {{"animation", clip.gltf_animation}, {"name", clip.name}};
    nlohmann::json times = nlohmann::json::array(), skinned_json = nlohmann::json::array(),
                   drivers_json = nlohmann::json::array(), helpers_json = nlohmann::json::array();
    for (double fraction : fractions) {
      const double time = fraction * clip.duration;
      const Pose pose = sampleClip(skeleton, clip, time);
      std::vector<double> skinned, helpers;
      std::vector<runtime::MuscleDrivers<double>> drivers;
      evaluate(pose, &skinned, &helpers, &drivers);
      nlohmann::json driver_values = nlohmann::json::array();
      for (const auto& d : drivers) {
        driver_values.push_back(d.ratio);
        driver_values.push_back(d.twist);
      }
      times.push_back(time);
      skinned_json.push_back(skinned);
      drivers_json.push_back(driver_values);
      helpers_json.push_back(helpers);
      ++counts->matrix_frames;
    }
    entry["times"] = times;
    entry["skinned"] = skinned_json;
    entry["drivers"] = drivers_json;
    if (with_helpers) entry["helpers"] = helpers_json;
    clips.push_back(entry);

    for (double fraction : skin_fractions) {
      const double time = fraction * clip.duration;
      Pose pose = sampleClip(skeleton, clip, time);
      std::vector<double> skinned, helpers;
      std::vector<runtime::MuscleDrivers<double>> drivers;
      evaluate(pose, &skinned, &helpers, &drivers);
      // The muscle joints where the runtime puts them (a runtime bake has no channels for them).
      for (size_t m = 0; m < muscles; ++m) pose.world[file.rig.skinned_joint[m]] = matrixAt(skinned, m);
      std::vector<Eigen::Affine3d> frame;
      for (int j = 0; j < skeleton.size(); ++j) frame.push_back(skinMatrix(pose, skeleton, j));
      nlohmann::json parts_json = nlohmann::json::array();
      for (const SkinPart& part : parts) {
        const std::vector<Eigen::Vector3d> positions = skinLinearBlend(part.mesh->positions, part.influences, frame);
        parts_json.push_back({{"node", part.mesh->gltf_node},
                              {"mesh", part.mesh->gltf_mesh},
                              {"primitive", part.mesh->gltf_primitive},
                              {"positions", doublesBase64(positions)}});
        counts->skin_vertices += static_cast<int>(positions.size());
      }
      skin_frames.push_back({{"animation", clip.gltf_animation}, {"time", time}, {"parts", parts_json}});
      ++counts->skin_frames;
    }
  }
  return {{"clips", clips}, {"skin", skin_frames}};
}

std::string floatsBase64(const std::vector<float>& values) {
  std::string bytes(values.size() * sizeof(float), '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());  // little endian, as the page reads it
  return base64Encode(bytes);
}

constexpr float kFrameSeconds = 1.0f / 30.0f;
constexpr int kHitFrame = 5;

// The frames tests/runtime_c_api_test.cpp runs through the C API, here for the page: every clip's poses
// at 30 fps in one sequence (at most max_frames), each frame's node world matrices (the skeleton's
// nodes; the others identity) and what the native float C API computes from them: the muscles' skinned
// matrices, and after a hit of 2 m/s along +z at frame 5, the jiggles stepped by 1/30 s, their
// corrections and jiggled world matrices. The page sets its scene to each pose, runs the plugin's
// update and compares.
nlohmann::json capiFrames(const std::string& glb, int max_frames, ReferenceCounts* counts) {
  const LoadedCharacter loaded = loadCharacter(glb);
  const Skeleton& skeleton = loaded.character.skeleton;
  const nlohmann::json json = test::glbJson(test::slurp(glb));
  const int node_count = static_cast<int>(json["nodes"].size());
  const std::string text = json["extensions"]["RIGBAKE_muscle_rig"].dump();
  rigbake_rig* rig = rigbake_rig_create(text.data(), text.size(), node_count);
  INFO(rigbake_last_error());
  REQUIRE(rig);
  const size_t muscles = static_cast<size_t>(rigbake_rig_muscle_count(rig));
  const size_t jiggles = static_cast<size_t>(rigbake_rig_jiggle_count(rig));
  counts->jiggles = static_cast<int>(jiggles);
  std::vector<float> poses, expected, pose, skinned(16 * muscles), corrections(4 * jiggles), jiggled(16 * jiggles);
  const float hit[3] = {0.0f, 0.0f, 1.0f};
  int frames = 0;
  for (const Clip& clip : loaded.character.clips) {
    for (double t : sampleTimes(clip, 30.0)) {
      if (frames == max_frames) break;
      const Pose sampled = sampleClip(skeleton, clip, t);
      pose.assign(16 * static_cast<size_t>(node_count), 0.0f);
      for (int n = 0; n < node_count; ++n)
        for (int k = 0; k < 4; ++k) pose[16 * n + 5 * k] = 1.0f;
      for (int j = 0; j < skeleton.size(); ++j)
        for (int k = 0; k < 16; ++k) pose[16 * static_cast<size_t>(skeleton.nodes[j]) + k] = static_cast<float>(sampled.world[j].matrix().data()[k]);
      poses.insert(poses.end(), pose.begin(), pose.end());
      REQUIRE(rigbake_rig_evaluate(rig, pose.data(), skinned.data(), nullptr, nullptr) == RIGBAKE_OK);
      REQUIRE(rigbake_rig_store_skinned(rig, skinned.data(), pose.data()) == RIGBAKE_OK);
      if (frames == kHitFrame && jiggles > 0) REQUIRE(rigbake_jiggle_impulse(rig, -1, hit, 2.0f) == RIGBAKE_OK);
      REQUIRE(rigbake_jiggle_step(rig, pose.data(), frames == 0 ? 0.0f : kFrameSeconds, 0, corrections.data(), nullptr, jiggled.data(),
                                  nullptr) == RIGBAKE_OK);
      expected.insert(expected.end(), skinned.begin(), skinned.end());
      expected.insert(expected.end(), corrections.begin(), corrections.end());
      expected.insert(expected.end(), jiggled.begin(), jiggled.end());
      ++frames;
    }
  }
  rigbake_rig_destroy(rig);
  counts->capi_frames = frames;
  std::vector<int> nodes(skeleton.nodes.begin(), skeleton.nodes.end());
  return {{"nodeCount", node_count}, {"nodes", nodes},       {"muscles", muscles},     {"jiggles", jiggles},
          {"dt", kFrameSeconds},    {"hitFrame", kHitFrame}, {"poses", floatsBase64(poses)}, {"expected", floatsBase64(expected)}};
}

// ---- the browser ----

struct PageResult {
  nlohmann::json run;     // what run_page.mjs printed
  nlohmann::json result;  // the page's own result
  std::string raw;
};

PageResult openPage(const std::string& html, const std::string& query, int timeout_seconds) {
  const std::string url = "file://" + std::filesystem::absolute(html).string() + query;
  const ext::CommandResult run = ext::runCommand("node " + viewArg(pageRunner()) + " " + viewArg(viewChromium()) + " " +
                                                 viewArg(url) + " " + std::to_string(timeout_seconds) + " 2>&1");
  PageResult page;
  page.raw = run.output;
  // The runner's JSON is its last line (anything before it is the browser's own chatter).
  std::string last;
  std::istringstream lines(run.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("{", 0) == 0) last = line;
  }
  page.run = nlohmann::json::parse(last, nullptr, false);
  if (page.run.is_object() && page.run.contains("result") && page.run["result"].is_object()) page.result = page.run["result"];
  return page;
}

// No console error, no uncaught exception, no failed load, and the self-test finished.
void checkCleanRun(const PageResult& page) {
  INFO(page.raw.substr(0, 4000));
  REQUIRE(page.run.is_object());
  CHECK_FALSE(page.run.value("timedOut", true));
  REQUIRE(page.result.is_object());
  CHECK(page.result.value("done", false));
  CHECK(page.result.value("loaded", false));
  CHECK(page.result["errors"].empty());
  CHECK(page.run["console"].empty());
  CHECK(page.run["exceptions"].empty());
  for (const auto& entry : page.run["log"]) {
    const std::string text = entry.get<std::string>();
    // Chromium's own performance note about the test's readPixels is not an error of the page.
    if (text.find("GPU stall due to ReadPixels") != std::string::npos) continue;
    CHECK(text.rfind("error", 0) != 0);
  }
}

// Every clip was played from its start to its end and rendered.
void checkClipsPlayed(const PageResult& page, int clip_count) {
  INFO(page.raw.substr(0, 4000));
  REQUIRE(page.result["clips"].size() == static_cast<size_t>(clip_count));
  for (const auto& clip : page.result["clips"]) {
    INFO(clip.dump());
    CHECK(clip["maxTime"].get<double>() >= 0.8 * clip["duration"].get<double>());
    CHECK(clip["visible"].get<int>() > 500);  // of 320 x 240 pixels: the character is on screen
    CHECK(clip["glError"].get<int>() == 0);
  }
}

struct ViewPage {
  TempDir dir;
  std::string glb;
  std::string page_dir;
};

// Bakes `character`, writes its page with the CLI, and the test variant beside it.
void writeAgreementPage(ViewPage* page, const std::string& character, const std::string& bake_flags,
                        const std::vector<double>& fractions, const std::vector<double>& skin_fractions,
                        int capi_max_frames, ReferenceCounts* counts) {
  page->glb = bakeForView(character, bake_flags, page->dir / "baked.glb");
  page->page_dir = page->dir / "view";
  const test::CliResult view = test::runCli("view " + viewArg(page->glb) + " -o " + viewArg(page->page_dir));
  INFO(view.err);
  REQUIRE(view.exit_code == 0);
  const bool with_helpers = bake_flags.find("--helper-joints") != std::string::npos;
  nlohmann::json reference = cppReference(page->glb, fractions, skin_fractions, with_helpers, counts);
  reference["capi"] = capiFrames(page->glb, capi_max_frames, counts);
  std::ofstream(page->page_dir + "/reference.js", std::ios::binary)
      << "window.RIGBAKE_REFERENCE = " << reference.dump() << ";\n";
  // The test variant: the page as written plus the reference script.
  std::string html = test::slurp(page->page_dir + "/" + kViewPageFile);
  const std::string model_tag = std::string("<script src=\"") + kViewModelFile + "\"></script>";
  REQUIRE(html.find(model_tag) != std::string::npos);
  html.replace(html.find(model_tag), 0, "<script src=\"reference.js\"></script>\n");
  std::ofstream(page->page_dir + "/test.html", std::ios::binary) << html;
}

// The page's rigger controls (self_test.js riggerTools, docs/view.md "On the page") on its default clip:
// the scrubber pauses and poses (the same time, the same pose; another time, another), one frame step is
// the clip's key spacing by the buttons and the keys and gives the scrubber's pose there, the orbit
// camera's target is at the selected joint (and at its new place after F), the floor grid lies at the
// skin's lowest point, and the panel with its heatmap group is no wider than its box at 1280 x 720 and
// 800 x 600. Returns the stage's result.
nlohmann::json checkRiggerTools(const PageResult& run, double frame_step) {
  const nlohmann::json& rigger = run.result["rigger"];
  INFO(rigger.dump());
  REQUIRE(rigger.is_object());
  CHECK(rigger["paused_by_scrub"] == true);
  CHECK(rigger["scrub_time_error"].get<double>() < 1e-12);
  CHECK(rigger["moved_m"].get<double>() > 0.01);  // time 0.41 x duration is another pose than time 0
  CHECK(rigger["repeat_m"].get<double>() == 0.0);  // and scrubbing back to it gives the same one
  CHECK(std::abs(rigger["frame_step"].get<double>() - frame_step) < 1e-6);
  CHECK(std::abs(rigger["next_dt"].get<double>() - frame_step) < 1e-9);
  CHECK(std::abs(rigger["prev_dt"].get<double>()) < 1e-9);
  CHECK(std::abs(rigger["key_dt"].get<double>() - 2 * frame_step) < 1e-9);
  CHECK(std::abs(rigger["key_back_dt"].get<double>() - frame_step) < 1e-9);
  CHECK(rigger["step_pose_m"].get<double>() < 1e-9);
  CHECK(rigger["paused_by_step"] == true);
  CHECK(rigger["camera_target_m"].get<double>() < 1e-3);
  REQUIRE(rigger["framed"].size() == 2);
  CHECK(rigger["framed"][1]["reframe_moved_m"].get<double>() > 0.01);  // F followed a joint that moved
  CHECK(rigger["grid"] == true);
  CHECK(std::abs(rigger["grid_y"].get<double>() - rigger["bind_min_y"].get<double>()) < 0.02);
  CHECK(std::abs(rigger["grid_size"].get<double>() - 2 * rigger["character_height"].get<double>()) < 1e-3 * rigger["character_height"].get<double>());
  REQUIRE(rigger["panel"].size() == 2);
  for (const auto& size : rigger["panel"]) CHECK(size["fits"] == true);
  return rigger;
}

// skin_bound: the GPU's packed skinning against rigbake's (issue 31: 1e-6 m for 10 influences);
// capi_max_frames: how many 30 fps frames of the clips, in their order, the C API comparison runs.
void checkAgreement(const std::string& label, const std::string& character, const std::string& bake_flags,
                    const std::vector<double>& fractions, const std::vector<double>& skin_fractions, double skin_bound,
                    int capi_max_frames = 240) {
  ViewPage page;
  ReferenceCounts counts;
  writeAgreementPage(&page, character, bake_flags, fractions, skin_fractions, capi_max_frames, &counts);
  const PageResult run = openPage(page.page_dir + "/test.html", "?test=1", 240);
  checkCleanRun(run);
  checkClipsPlayed(run, counts.clips);
  INFO(run.raw.substr(0, 6000));
  const nlohmann::json& matrices = run.result["matrices"];
  const nlohmann::json& skinning = run.result["skinning"];
  REQUIRE(matrices.is_object());
  REQUIRE(skinning.is_object());
  CHECK(matrices["frames"].get<int>() == counts.matrix_frames);
  CHECK(matrices["muscles"].get<int>() == counts.muscles);
  CHECK(matrices["translation_m"].get<double>() < kAgreement);
  CHECK(matrices["linear"].get<double>() < kFloatTerms);
  CHECK(matrices["ratio"].get<double>() < kAgreement);
  CHECK(matrices["twist_rad"].get<double>() < kAgreement);
  CHECK(matrices["helpers_m"].get<double>() < kAgreement);
  // A --helper-joints bake: every muscle's helper frames were compared, at every frame, not skipped.
  const bool with_helpers = bake_flags.find("--helper-joints") != std::string::npos;
  CHECK(matrices["helpers_compared"].get<int>() == (with_helpers ? counts.matrix_frames * counts.muscles : 0));
  CHECK(skinning["frames"].get<int>() == counts.skin_frames);
  CHECK(skinning["vertices"].get<int>() == counts.skin_vertices);
  CHECK(skinning["max_m"].get<double>() < skin_bound);
  // The scrubber poses the default clip where rigbake's C++ runtime puts the muscle joints at its times.
  const nlohmann::json& rigger = run.result["rigger"];
  REQUIRE(rigger.is_object());
  CHECK(rigger["reference_frames"].get<int>() == static_cast<int>(fractions.size()));
  CHECK(rigger["reference_m"].get<double>() < kAgreement);
  // Framing the first muscle joint puts the orbit camera's target where the C++ runtime puts that joint.
  CHECK(rigger["camera_vs_reference_m"].get<double>() >= 0.0);
  CHECK(rigger["camera_vs_reference_m"].get<double>() < 1e-3);
  std::printf("view agreement %s: default clip %s, scrubbed muscle joints vs C++ %.3g m over %d times, camera target vs C++ %.3g m\n", label.c_str(),
              rigger["defaultClip"].dump().c_str(), rigger["reference_m"].get<double>(), rigger["reference_frames"].get<int>(),
              rigger.value("camera_vs_reference_m", -1.0));
  // The plugin against the native C API frame by frame, jiggles included (hit at frame 5).
  const nlohmann::json& capi = run.result["capi"];
  INFO(run.result["seconds"].dump());
  REQUIRE(capi.is_object());
  CHECK(capi["frames"].get<int>() == counts.capi_frames);
  CHECK(capi["frames"].get<int>() > 30);
  CHECK(capi["muscles"].get<int>() == counts.muscles);
  CHECK(capi["jiggles"].get<int>() == counts.jiggles);
  CHECK(counts.jiggles >= 2);
  CHECK(capi["largest_jiggle_deg"].get<double>() > 1.0);  // the jiggles moved: a comparison at rest would prove nothing
  CHECK(capi["muscle_m"].get<double>() < kAgreement);
  CHECK(capi["muscle_terms"].get<double>() < kAgreement);
  CHECK(capi["jiggle_m"].get<double>() < kAgreement);
  CHECK(capi["jiggle_terms"].get<double>() < kAgreement);
  CHECK(capi["correction"].get<double>() < kAgreement);
  std::printf("view agreement %s: plugin in Chromium vs native C API over %d frames: muscles %.3g m (%.3g terms), %d jiggles "
              "%.3g m (%.3g terms), corrections %.3g, largest jiggle %.1f deg; stages %s\n",
              label.c_str(), capi["frames"].get<int>(), capi["muscle_m"].get<double>(), capi["muscle_terms"].get<double>(),
              counts.jiggles, capi["jiggle_m"].get<double>(), capi["jiggle_terms"].get<double>(), capi["correction"].get<double>(),
              capi["largest_jiggle_deg"].get<double>(), run.result["seconds"].dump().c_str());
  const long long page_bytes = static_cast<long long>(std::filesystem::file_size(page.page_dir + "/index.html") +
                                                      std::filesystem::file_size(page.page_dir + "/model.js") +
                                                      std::filesystem::file_size(page.page_dir + "/" + kViewPlayerFile));
  // The figures docs/view.md quotes.
  std::printf("view agreement %s: %d muscles, %d clips, %d frames: plugin (WebAssembly) vs C++ muscle matrices max %.3g m (translation), %.3g "
              "(rotation/scale terms), ratio %.3g, twist %.3g rad, helpers %.3g m (%d); "
              "GPU vs C++ skinning max %.3g m over %d frames, %d vertices; page %lld bytes; plugin %.1f us/frame; load %.2f s (with the reference script); browser %.1f s\n",
              label.c_str(), counts.muscles, counts.clips, counts.matrix_frames, matrices["translation_m"].get<double>(),
              matrices["linear"].get<double>(), matrices["ratio"].get<double>(), matrices["twist_rad"].get<double>(),
              matrices["helpers_m"].get<double>(), matrices["helpers_compared"].get<int>(),
              skinning["max_m"].get<double>(), counts.skin_frames, counts.skin_vertices, page_bytes,
              run.result["runtime"].is_object() ? run.result["runtime"].value("us_per_frame", 0.0) : 0.0,
              run.result["seconds"].value("load", 0.0), run.run.value("seconds", 0.0));
}

TEST_CASE("rigbake view: bad input, help, atomic and deterministic output") {
  TempDir dir;
  const std::string player = fakePlayer(dir);
  const std::string sample = test::sampleGlbPathForCli();

  SECTION("--help teaches") {
    const test::CliResult help = test::runCli("view --help");
    CHECK(help.exit_code == 0);
    for (const char* text : {"file://", "runtime", "sampled", "heatmap", "Hit", "rigbake-player.js", "model.js",
                             "install-player.sh", "Example"})
      CHECK(help.out.find(text) != std::string::npos);
  }
  SECTION("a missing input is IO_FILE_NOT_FOUND and writes nothing") {
    const test::CliResult run = test::runCli("view " + viewArg(dir / "none.glb") + " -o " + viewArg(dir / "page") + " --player " + viewArg(player));
    CHECK(run.exit_code == 2);
    CHECK(run.err.rfind("IO_FILE_NOT_FOUND", 0) == 0);
    CHECK_FALSE(std::filesystem::exists(dir / "page"));
  }
  SECTION("an unbaked character is VIEW_NOT_BAKED") {
    const test::CliResult run = test::runCli("view " + viewArg(sample) + " -o " + viewArg(dir / "page") + " --player " + viewArg(player));
    CHECK(run.exit_code == 3);
    CHECK(run.err.rfind("VIEW_NOT_BAKED", 0) == 0);
    CHECK(run.err.find("rigbake bake") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "page"));
  }
  SECTION("a write that fails (a file size limit, as a full disk) names the page's file, not the temporary folder") {
    const std::string baked = bakeForView(sample, "--influences 4", dir / "baked.glb");
    // ulimit -f makes write() fail with EFBIG past 64 blocks; SIGXFSZ, ignored, would otherwise kill the run.
    const ext::CommandResult run = ext::runCommand("ulimit -f 64 && trap '' XFSZ && " + std::string(rigbake::test::kRigbakeCli) + " view " +
                                                   viewArg(baked) + " -o " + viewArg(dir / "page") + " --player " +
                                                   viewArg(player) + " 2>&1");
    INFO(run.output);
    CHECK(run.exit_code == 2);
    CHECK(run.output.rfind("IO_WRITE_FAILED " + (dir / "page") + "/" + kViewModelFile + ": cannot write: File too large", 0) == 0);
    CHECK(run.output.find("rigbake-tmp") == std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "page"));
    for (const auto& entry : std::filesystem::directory_iterator(dir.path))
      CHECK(entry.path().filename().string().find("rigbake-tmp") == std::string::npos);
  }
  SECTION("a missing player bundle is VIEW_PLAYER_MISSING") {
    const test::CliResult run = test::runCli("view " + viewArg(sample) + " -o " + viewArg(dir / "page") + " --player " + viewArg(dir / "none.js"));
    CHECK(run.exit_code == 2);
    CHECK(run.err.rfind("VIEW_PLAYER_MISSING", 0) == 0);
    CHECK(run.err.find("install-player.sh") != std::string::npos);
  }
  SECTION("baked files: the page, its bytes, replacing it, and what it refuses") {
    const std::string baked = bakeForView(sample, "--influences 7", dir / "baked.glb");
    const std::string page = dir / "page";
    const test::CliResult first = test::runCli("view " + viewArg(baked) + " -o " + viewArg(page) + " --player " + viewArg(player) + " --json");
    INFO(first.err);
    REQUIRE(first.exit_code == 0);
    const nlohmann::json summary = nlohmann::json::parse(first.out);
    CHECK(summary["clips"] == 3);
    CHECK(summary["rig_extension"] == true);
    CHECK(summary["packed_influences"] == 7);
    std::set<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(page)) names.insert(entry.path().filename().string());
    CHECK(names == std::set<std::string>{kViewPageFile, kViewModelFile, kViewPlayerFile});
    // The GLB goes in byte for byte, the bundle as given; the page loads them with classic scripts only.
    const std::string model = test::slurp(page + "/" + kViewModelFile);
    CHECK(model.find(base64Encode(test::slurp(baked))) != std::string::npos);
    CHECK(test::slurp(page + "/" + kViewPlayerFile) == test::slurp(player));
    const std::string html = test::slurp(page + "/" + kViewPageFile);
    CHECK(html.find("type=\"module\"") == std::string::npos);
    CHECK(html.find("http") == std::string::npos);
    CHECK(html.find("<title>baked.glb - rigbake view</title>") != std::string::npos);
    // Same input, same bytes; a page rigbake view wrote is replaced in place, leaving no temporary behind.
    const std::string before = html + model;
    const test::CliResult second = test::runCli("view " + viewArg(baked) + " -o " + viewArg(page) + " --player " + viewArg(player));
    REQUIRE(second.exit_code == 0);
    CHECK(test::slurp(page + "/" + kViewPageFile) + test::slurp(page + "/" + kViewModelFile) == before);
    for (const auto& entry : std::filesystem::directory_iterator(dir.path))
      CHECK(entry.path().filename().string().find("rigbake-tmp") == std::string::npos);
    // A directory holding anything else is not overwritten.
    std::ofstream(page + "/notes.txt") << "mine";
    const test::CliResult refused = test::runCli("view " + viewArg(baked) + " -o " + viewArg(page) + " --player " + viewArg(player));
    CHECK(refused.exit_code == 2);
    CHECK(refused.err.rfind("IO_WRITE_FAILED", 0) == 0);
    CHECK(refused.err.find("notes.txt") != std::string::npos);
    CHECK(test::slurp(page + "/notes.txt") == "mine");
    CHECK(test::slurp(page + "/" + kViewModelFile) == model);
    // A rig extension the player cannot evaluate is VIEW_BAKE_INVALID, naming the pointer.
    tinygltf::Model broken;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    REQUIRE(loader.LoadBinaryFromFile(&broken, &error, &warning, baked));
    auto muscles = broken.extensions.at("RIGBAKE_muscle_rig").Get<tinygltf::Value::Object>();
    auto list = muscles.at("muscles").Get<tinygltf::Value::Array>();
    auto first_muscle = list[0].Get<tinygltf::Value::Object>();
    first_muscle["restLength"] = tinygltf::Value(-1.0);
    list[0] = tinygltf::Value(first_muscle);
    muscles["muscles"] = tinygltf::Value(list);
    broken.extensions["RIGBAKE_muscle_rig"] = tinygltf::Value(muscles);
    const std::string broken_path = dir / "broken.glb";
    REQUIRE(loader.WriteGltfSceneToFile(&broken, broken_path, true, true, false, true));
    const test::CliResult invalid = test::runCli("view " + viewArg(broken_path) + " -o " + viewArg(dir / "broken") + " --player " + viewArg(player));
    CHECK(invalid.exit_code == 3);
    CHECK(invalid.err.rfind("VIEW_BAKE_INVALID", 0) == 0);
    CHECK(invalid.err.find("/extensions/RIGBAKE_muscle_rig/muscles") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir / "broken"));
  }
}

TEST_CASE("rigbake view: the page plays every clip of the mannequin in every mode with no console error (Chromium)") {
  if (!browserToolsPresent()) return;
  TempDir dir;
  const std::string baked =
      bakeForView(test::sampleGlbPathForCli(), "--influences 10 --muscle-motion both --jiggle biceps", dir / "baked.glb");
  const std::string page = dir / "view";
  const test::CliResult view = test::runCli("view " + viewArg(baked) + " -o " + viewArg(page));
  INFO(view.err);
  REQUIRE(view.exit_code == 0);
  // The page exactly as written, in its test mode.
  const PageResult run = openPage(page + "/" + kViewPageFile, "?test=1", 180);
  checkCleanRun(run);
  checkClipsPlayed(run, 3);
  INFO(run.raw.substr(0, 6000));
  const nlohmann::json& file = run.result["file"];
  CHECK(file["muscles"] == 38);  // 28 muscles and 10 armpit corrective parts (five carriers a side)
  CHECK(file["jiggles"] == 2);
  CHECK(file["fileInfluences"] == 10);
  CHECK(file["muscleModes"] == nlohmann::json::array({"runtime", "sampled", "off"}));
  CHECK(file["influences"] == nlohmann::json::array({4, 7, 10}));
  // 3 muscle modes x 3 influence counts x heatmap off / on, each through the page's own controls.
  REQUIRE(run.result["modes"].size() == 18);
  for (const auto& mode : run.result["modes"]) {
    INFO(mode.dump());
    CHECK(mode["applied"] == true);
    CHECK(mode["visible"].get<int>() > 500);
    CHECK(mode["glError"] == 0);
  }
  // The Hit button swings the biceps' jiggles out (the largest correction's angle), and they come back to rest.
  const nlohmann::json& hit = run.result["hit"];
  REQUIRE(hit.is_object());
  CHECK(hit["jiggles"] == 2);
  CHECK(hit["peak_deg"].get<double>() > hit["before_deg"].get<double>() + 5.0);
  CHECK(hit["settled_deg"].get<double>() < 0.1 * hit["peak_deg"].get<double>());
  // At the clips' key times the file's channels (sampled) and the plugin (the WebAssembly runtime) put
  // the skinned joints at the same place: the bake sampled the channels through the C++ runtime.
  const nlohmann::json& sampled = run.result["sampled"];
  REQUIRE(sampled.is_object());
  CHECK(sampled["frames"].get<int>() == 9);
  CHECK(sampled["compared"].get<int>() == 9 * 36);  // 38 parts, the 2 jiggling biceps left out
  CHECK(sampled["translation_m"].get<double>() < kAgreement);
  CHECK(sampled["linear"].get<double>() < kAgreement);
  // The rigger's controls; the default clip is the one raising the arms (ElbowFlexion, the first, moves
  // only the forearms), keyed at 30 per second.
  const nlohmann::json rigger = checkRiggerTools(run, 1.0 / 30.0);
  CHECK(rigger["defaultClip"] == "ArmRaise");
  CHECK(rigger["joint_options"].get<int>() == 1 + 38 + 30);
  CHECK(std::abs(rigger["character_height"].get<double>() - 1.80) < 0.01);  // the mannequin's skin: soles at 0, crown at 1.80 m  // whole character, 38 muscle joints, 30 skeleton joints
  std::printf("view page rigger: default %s, scrub moved %.3f m, step %.6f s, camera target %.2g m (F followed %.3f m), grid y %.3g m "
              "(skin's lowest %.3g m, %.2f m across), panel %s\n",
              rigger["defaultClip"].get<std::string>().c_str(), rigger["moved_m"].get<double>(), rigger["next_dt"].get<double>(),
              rigger["camera_target_m"].get<double>(), rigger["framed"][1]["reframe_moved_m"].get<double>(), rigger["grid_y"].get<double>(),
              rigger["bind_min_y"].get<double>(), rigger["grid_size"].get<double>(), rigger["panel"].dump().c_str());
  // From navigation start to the second frame on screen (self_test.js), for docs/view.md.
  REQUIRE(run.result["seconds"]["load"].is_number());
  CHECK(run.result["seconds"]["load"].get<double>() > 0.0);
  std::printf("view page: mannequin, 3 clips x 18 modes, hit peak %.2f deg settled %.2g deg; sampled channels vs the plugin "
              "%.3g m, %.3g (rotation/scale terms); plugin %.1f us/frame; load %.2f s; browser %.1f s\n",
              hit["peak_deg"].get<double>(), hit["settled_deg"].get<double>(), sampled["translation_m"].get<double>(),
              sampled["linear"].get<double>(), run.result["runtime"].value("us_per_frame", 0.0),
              run.result["seconds"]["load"].get<double>(), run.run.value("seconds", 0.0));
}

// Issue 31: a bake compressed after baking, by glTF-Transform with rigbake's config (the rig kept,
// docs/pipelines.md), plays like the bake: the page gets the compressed GLB byte for byte and decodes it
// itself, meshopt with three's MeshoptDecoder (in the bundle), Draco with three's DRACOLoader and the
// decoder files of rigbake-draco.js, which only a Draco file's page gets.
TEST_CASE("rigbake view: meshopt and Draco bakes from glTF-Transform with rigbake's config play with their rig (Chromium)") {
  if (!browserToolsPresent()) return;
  if (!ext::requireTool(test::fileExists(ext::gltfTransformCli()), "gltf-transform (scripts/install-gltf-transform.sh)")) return;
  TempDir dir;
  const std::string baked = bakeForView(test::sampleGlbPathForCli(), "--influences 10", dir / "baked.glb");
  const std::string config = test::sourceDir() + "/gltf-transform/rigbake.config.mjs";
  for (const auto& [verb, extension] : {std::pair<std::string, std::string>{"optimize", "EXT_meshopt_compression"},
                                        {"draco", "KHR_draco_mesh_compression"}}) {
    const std::string compressed = dir / (verb + ".glb");
    const ext::CommandResult made = ext::runCommand(viewArg(ext::gltfTransformCli()) + " " + verb + " " + viewArg(baked) +
                                                    " " + viewArg(compressed) + " --config " + viewArg(config) + " 2>&1");
    INFO(made.output);
    REQUIRE(made.exit_code == 0);
    REQUIRE(test::slurp(compressed).find(extension) != std::string::npos);
    const std::string page = dir / (verb + "-view");
    const test::CliResult view = test::runCli("view " + viewArg(compressed) + " -o " + viewArg(page));
    INFO(view.err);
    REQUIRE(view.exit_code == 0);
    // The compressed bytes themselves: the page's decoders, not rigbake, decode them.
    CHECK(test::slurp(page + "/" + kViewModelFile).find(base64Encode(test::slurp(compressed))) != std::string::npos);
    const bool draco = verb == "draco";
    CHECK(std::filesystem::exists(page + "/" + kViewDracoFile) == draco);
    CHECK((test::slurp(page + "/" + kViewPageFile).find(kViewDracoFile) != std::string::npos) == draco);
    if (draco) {
      // A bundle without the Draco decoder script beside it cannot make a Draco file's page.
      const test::CliResult missing = test::runCli("view " + viewArg(compressed) + " -o " + viewArg(dir / "no-draco") + " --player " +
                                                   viewArg(fakePlayer(dir)));
      CHECK(missing.exit_code == 2);
      CHECK(missing.err.rfind("VIEW_PLAYER_MISSING " + (dir / kViewDracoFile), 0) == 0);
      CHECK_FALSE(std::filesystem::exists(dir / "no-draco"));
    }
    const PageResult run = openPage(page + "/" + kViewPageFile, "?test=1", 180);
    checkCleanRun(run);
    checkClipsPlayed(run, 3);
    CHECK(run.result["file"]["muscles"] == 38);
    CHECK(run.result["file"]["fileInfluences"] == 10);
  }
}

// The conformance suite's ROM clips (docs/rom.md, issue 31) ride along on the mannequin: `rigbake rom`
// appends a forearm twist (the clip that drives the twist curves) and an arm raise (shoulder abduction
// to 170 degrees) after its three own clips, and all five are compared (61 frames each in the C API run).
TEST_CASE("rigbake view: the plugin (WebAssembly runtime, muscles and jiggles) and the GPU skinning match rigbake's C++ on the mannequin and its ROM clips (Chromium)") {
  if (!browserToolsPresent()) return;
  TempDir dir;
  const std::string rom = dir / "mannequin_rom.glb";
  const test::CliResult run =
      test::runCli("rom " + viewArg(test::sampleGlbPathForCli()) + " --clips forearm_twist,shoulder_abduction -o " + viewArg(rom));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  checkAgreement("mannequin and rom_forearm_twist, rom_shoulder_abduction", rom, "--influences 10 --helper-joints --jiggle gow_examples",
                 {0.0, 0.17, 0.41, 0.63, 0.88}, {0.29, 0.71}, 1e-6, 5 * 61);
}

// A clipless character gets its only clips from `rigbake rom`: the KayKit mannequin (no clavicle, no neck
// joint), its ROM elbow flexion and forearm twist, played and compared as above.
TEST_CASE("rigbake view: the plugin (WebAssembly runtime, muscles and jiggles) and the GPU skinning match rigbake's C++ on the clipless KayKit mannequin's ROM clips (Chromium)") {
  if (!browserToolsPresent()) return;
  const std::string kaykit = test::requireAsset("KayKit_Mannequin/manny_med_mod.gltf");
  if (kaykit.empty()) return;
  TempDir dir;
  const std::string rom = dir / "kaykit_rom.glb";
  const test::CliResult run = test::runCli("rom " + viewArg(kaykit) + " --clips elbow_flexion,forearm_twist -o " + viewArg(rom));
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  checkAgreement("KayKit mannequin rom_elbow_flexion, rom_forearm_twist", rom, "--influences 10 --jiggle biceps", {0.0, 0.25, 0.5, 0.75},
                 {0.5}, 1e-6);
}

TEST_CASE("rigbake view: the plugin (WebAssembly runtime, muscles and jiggles) and the GPU skinning match rigbake's C++ on CesiumMan (Chromium)") {
  if (!browserToolsPresent()) return;
  const std::string path = test::requireAsset("CesiumMan.glb");
  if (path.empty()) return;
  checkAgreement("CesiumMan", path, "--influences 7 --jiggle biceps", {0.0, 0.17, 0.41, 0.63, 0.88}, {0.29, 0.71}, kAgreement);
}

TEST_CASE("rigbake view: the plugin (WebAssembly runtime, muscles and jiggles) and the GPU skinning match rigbake's C++ on Quaternius Cyberpunk (Chromium)") {
  if (!browserToolsPresent()) return;
  const std::string path = test::requireAsset("Quaternius_Cyberpunk_Character.glb");
  if (path.empty()) return;
  checkAgreement("Quaternius Cyberpunk", path, "--influences 10 --jiggle biceps", {0.0, 0.31, 0.62, 0.9}, {0.47}, 1e-6);
}

// The plugin's README example, its lines run as written in a plain three.js page (ES modules from an
// import map, served over http by player/test/plugin_example.mjs; Chromium refuses module pages from
// file://): it loads a 10-influence bake with biceps jiggles, plays its first clip and moves the muscles.
TEST_CASE("rigbake view: the rigbake-three plugin's README example plays a bake in a plain three.js page (Chromium)") {
  if (!browserToolsPresent()) return;
  if (!ext::requireTool(ext::onPath("emcc"), "emcc (Debian package emscripten)")) return;
  TempDir dir;
  const std::string baked = bakeForView(test::sampleGlbPathForCli(), "--influences 10 --jiggle biceps", dir / "baked.glb");
  const std::string wasm_dir = test::sourceDir() + "/build/wasm";
  REQUIRE(ext::runCommand("bash " + viewArg(test::sourceDir() + "/scripts/build-wasm.sh") + " " + viewArg(wasm_dir)).exit_code == 0);
  // three as the player installed it (its pinned version, the plugin's peer dependency).
  const std::string three = (std::filesystem::path(installedPlayer()).parent_path() / "node_modules" / "three").string();
  const ext::CommandResult run = ext::runCommand("node " + viewArg(test::sourceDir() + "/player/test/plugin_example.mjs") + " " +
                                                 viewArg(viewChromium()) + " " + viewArg(three) + " " + viewArg(wasm_dir) + " " +
                                                 viewArg(baked) + " 120 2>&1");
  INFO(run.output.substr(0, 4000));
  REQUIRE(run.exit_code == 0);
  std::string last;
  std::istringstream lines(run.output);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("{", 0) == 0) last = line;
  const nlohmann::json page = nlohmann::json::parse(last, nullptr, false);
  REQUIRE(page.is_object());
  CHECK_FALSE(page.value("timedOut", true));
  CHECK(page["console"].empty());
  CHECK(page["exceptions"].empty());
  const nlohmann::json& result = page["result"];
  REQUIRE(result.is_object());
  CHECK(result["errors"].empty());
  CHECK(result["lines"].get<int>() <= 10);
  CHECK(result["muscles"] == 38);
  CHECK(result["jiggles"] == 2);
  CHECK(result["influences"] == nlohmann::json::array({10}));
  CHECK(result["moved_m"].get<double>() > 1e-3);  // the muscles moved off their rest: the rig runs
  CHECK(result["largest_jiggle_deg"].get<double>() > 0.01);
  CHECK(result["glError"] == 0);
  std::printf("plugin README example: %d lines, muscles moved up to %.4f m, largest jiggle %.2f deg, browser %.1f s\n",
              result["lines"].get<int>(), result["moved_m"].get<double>(), result["largest_jiggle_deg"].get<double>(),
              page.value("seconds", 0.0));
}

}  // namespace rigbake::view_test
