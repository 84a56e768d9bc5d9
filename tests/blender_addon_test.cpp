// The Blender add-on (blender/rigbake_blender, docs/blender.md) in Debian's Blender, headless. One
// Blender run imports every character's bake with the add-on (tests/blender_rig_check.py "live"),
// samples every clip at every key, writes the muscle file back unedited and with one locator moved,
// and saves a .blend; a second run opens each .blend without the add-on ("reopen") and samples again.
// Here the samples are compared with rigbake's C++ runtime (runtime::MuscleRigJob<double> on the
// file's RIGBAKE_muscle_rig extension at the same times), the unedited file with the muscle file the
// bake read, and a bake of the edited file with where the locator was moved. Blender starts take
// seconds each, so every character shares the two runs.
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <map>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "runtime/muscle_rig.h"
#include "runtime/rigbake_runtime.h"

namespace rigbake::blender_addon_test {

namespace ext = rigbake::test::external;

constexpr double kPositionTolerance = 1e-4;  // metres, world position of a muscle joint (the bound)
constexpr double kFrameTolerance = 1e-3;     // rotation and scale terms of its matrix
constexpr double kMovedTolerance = 1e-6;     // metres, a moved locator after export and bake
constexpr double kRoundTripTolerance = 1e-9;

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

std::string quoted(const std::string& text) { return ext::shellQuote(text); }

void runCliOk(const std::string& args) {
  const test::CliResult run = test::runCli(args);
  INFO("rigbake " << args << "\n" << run.err);
  REQUIRE(run.exit_code == 0);
}

// Every number of `a` within `tolerance` of `b`'s at the same place, and the same keys and sizes.
void requireNumbersEqual(const nlohmann::json& a, const nlohmann::json& b, const std::string& where, double* largest) {
  INFO(where);
  REQUIRE(a.type() == b.type());
  if (a.is_object()) {
    REQUIRE(a.size() == b.size());
    for (auto it = a.begin(); it != a.end(); ++it) {
      REQUIRE(b.contains(it.key()));
      requireNumbersEqual(it.value(), b.at(it.key()), where + "/" + it.key(), largest);
    }
  } else if (a.is_array()) {
    REQUIRE(a.size() == b.size());
    for (size_t i = 0; i < a.size(); ++i) requireNumbersEqual(a[i], b[i], where + "/" + std::to_string(i), largest);
  } else if (a.is_number()) {
    const double difference = std::abs(a.get<double>() - b.get<double>());
    *largest = std::max(*largest, difference);
    REQUIRE(difference <= kRoundTripTolerance);
  } else {
    REQUIRE(a == b);
  }
}

struct Agreement {
  double position = 0, frame = 0, ratio = 0, twist = 0, helper_position = 0, helper_frame = 0;
  double jiggle_position = 0, jiggle_frame = 0;  // jiggling skeleton joints
  double jiggle_turn = 0;  // the runtime's own jiggle: largest rotation term of jiggled minus animated
  int clips = 0, frames = 0, muscles_compared = 0, skeleton_jiggle_frames = 0;
};

// The glTF JSON chunk of a GLB.
nlohmann::json glbJson(const std::string& path) {
  const std::string bytes = test::slurp(path);
  REQUIRE(bytes.size() > 20);
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, sizeof(length));
  return nlohmann::json::parse(bytes.substr(20, length));
}

// The runtime's C API on the file's extension (what the add-on loads through ctypes), to play the
// jiggles as Blender's frame handler does: started at rest on a clip's first key, then stepped
// through the keys in order.
struct CRig {
  rigbake_rig* rig = nullptr;
  int node_count = 0;
  explicit CRig(const std::string& glb) {
    const nlohmann::json document = glbJson(glb);
    const std::string text = document["extensions"]["RIGBAKE_muscle_rig"].dump();
    node_count = static_cast<int>(document["nodes"].size());
    rig = rigbake_rig_create(text.data(), text.size(), node_count);
    INFO(rigbake_last_error());
    REQUIRE(rig != nullptr);
  }
  ~CRig() { rigbake_rig_destroy(rig); }
  CRig(const CRig&) = delete;
  CRig& operator=(const CRig&) = delete;
};

enum class JiggledMuscles { kPlayed, kAtRest };
enum class Clips { kEvery, kSampled };  // every clip of the file must be sampled, or those sampled

// Whether the file's muscle `m` has helper joints (the bake writes them for every muscle or none).
bool muscleHasHelpers(const std::string& glb, size_t m) {
  static std::map<std::string, nlohmann::json> documents;
  if (!documents.count(glb)) documents[glb] = glbJson(glb);
  return documents[glb]["extensions"]["RIGBAKE_muscle_rig"]["muscles"][m].contains("helperNodes");
}

// The sampled clips of one Blender run against the C++ runtime at the same times: every muscle against
// MuscleRigJob<double>, a jiggled one against the C API's jiggle (kPlayed) or at rest (kAtRest: a
// .blend opened without the add-on has no frame handler, and the add-on saves it with the jiggles at rest).
Agreement compareWithRuntime(const std::string& baked, const nlohmann::json& clips, JiggledMuscles jiggled_muscles,
                             int* jiggled_compared, Clips which = Clips::kEvery) {
  const LoadedCharacter loaded = loadCharacter(baked);
  const BakedFileData file = readBakedFileData(loaded);
  REQUIRE(file.rig.present);
  REQUIRE(file.rig.problems.empty());
  const Skeleton& skeleton = loaded.character.skeleton;
  const runtime::MuscleRig<double>& rig = file.rig.rig;
  const size_t muscles = rig.muscles.size();
  CRig c_rig(baked);
  const int jiggles = rigbake_rig_jiggle_count(c_rig.rig);
  std::vector<int> jiggle_of(muscles, -1);
  for (int j = 0; j < jiggles; ++j) {
    for (size_t m = 0; m < muscles; ++m) {
      if (rigbake_rig_muscle_node(c_rig.rig, static_cast<int>(m), 0) == rigbake_rig_jiggle_node(c_rig.rig, j, 0)) jiggle_of[m] = j;
    }
  }
  Agreement agreement;
  // A jiggling skeleton joint turns its descendants with it; Blender's drivers read the locators as
  // they are shown (jiggled) where the runtime reads the un-jiggled pose, so the muscles riding one at
  // or below such a joint are not compared (docs/blender.md).
  std::vector<bool> below_jiggle(skeleton.size(), false);
  for (int j = 0; j < jiggles; ++j) {
    const int node = rigbake_rig_jiggle_node(c_rig.rig, j, 0);
    for (int joint = 0; joint < skeleton.size(); ++joint) {
      for (int up = joint; up >= 0 && skeleton.nodes[joint] >= 0; up = skeleton.parents[up]) {
        if (skeleton.nodes[up] == node && std::find(jiggle_of.begin(), jiggle_of.end(), j) == jiggle_of.end()) below_jiggle[joint] = true;
      }
    }
  }
  std::vector<bool> compared(muscles, true);
  for (size_t m = 0; m < muscles; ++m) {
    const runtime::RigMuscle<double>& muscle = rig.muscles[m];
    for (int joint : {muscle.origin_joint, muscle.insertion_joint, muscle.carrier_joint}) compared[m] = compared[m] && !below_jiggle[joint];
    if (compared[m]) ++agreement.muscles_compared;
  }
  REQUIRE(agreement.muscles_compared > 0);
  if (jiggles == 0) CHECK(agreement.muscles_compared == static_cast<int>(muscles));
  for (const Clip& clip : loaded.character.clips) {
    if (clip.gltf_animation < 0 || clip.measure_only) continue;
    INFO(baked << " clip " << clip.name);
    const std::string key = std::to_string(clip.gltf_animation);
    if (which == Clips::kSampled && !clips.contains(key)) continue;
    REQUIRE(clips.contains(key));
    const nlohmann::json& sampled = clips.at(key);
    REQUIRE(sampled["times"].size() >= 2);
    ++agreement.clips;
    double last_time = 0;
    for (size_t f = 0; f < sampled["times"].size(); ++f) {
      const double time = sampled["times"][f].get<double>();
      const Pose pose = sampleClip(skeleton, clip, time);
      const std::vector<double> joints = jointMatrices(pose);
      std::vector<float> nodes(16 * c_rig.node_count, 0.0f), c_skinned(16 * muscles), jiggled(16 * std::max(jiggles, 1));
      for (int j = 0; j < skeleton.size(); ++j) {
        for (int k = 0; k < 16; ++k) nodes[16 * skeleton.nodes[j] + k] = static_cast<float>(pose.world[j].matrix()(k % 4, k / 4));
      }
      REQUIRE(rigbake_rig_evaluate(c_rig.rig, nodes.data(), c_skinned.data(), nullptr, nullptr) == RIGBAKE_OK);
      REQUIRE(rigbake_rig_store_skinned(c_rig.rig, c_skinned.data(), nodes.data()) == RIGBAKE_OK);
      if (f == 0) REQUIRE(rigbake_jiggle_reset(c_rig.rig, nodes.data(), nullptr, 0.0f) == RIGBAKE_OK);
      const float step = f == 0 ? 0.0f : static_cast<float>(time - last_time);
      REQUIRE(rigbake_jiggle_step(c_rig.rig, nodes.data(), step, 0, nullptr, nullptr, jiggled.data(), nullptr) == RIGBAKE_OK);
      last_time = time;
      std::vector<double> skinned(16 * muscles), helpers(48 * muscles);
      std::vector<runtime::MuscleDrivers<double>> drivers(muscles);
      runtime::MuscleRigJob<double> job;
      job.rig = &rig;
      job.joint_matrices = runtime::Span<const double>(joints.data(), joints.size());
      job.skinned_matrices = skinned;
      job.helper_matrices = helpers;
      job.drivers = drivers;
      REQUIRE(job.Run());
      const std::vector<double> blender = sampled["skinned"][f].get<std::vector<double>>();
      REQUIRE(blender.size() == skinned.size());
      for (size_t m = 0; m < muscles; ++m) {
        INFO("time " << time << " muscle " << file.rig.names[m]);
        if (!compared[m]) continue;
        if (jiggle_of[m] >= 0) ++*jiggled_compared;
        double position = 0, frame = 0;
        for (int k = 0; k < 16; ++k) {
          // A .blend opened without the add-on (kAtRest) was saved with its jiggles at rest.
          const bool played = jiggle_of[m] >= 0 && jiggled_muscles == JiggledMuscles::kPlayed;
          const double reference = played ? jiggled[16 * jiggle_of[m] + k] : skinned[16 * m + k];
          const double difference = std::abs(blender[16 * m + k] - reference);
          if (k >= 12 && k < 15) position = std::max(position, difference);
          if (k < 12 && k % 4 != 3) frame = std::max(frame, difference);
        }
        INFO("blender " << nlohmann::json(std::vector<double>(blender.begin() + 16 * m, blender.begin() + 16 * m + 16)).dump());
        const double ratio = std::abs(sampled["ratio"][f][m].get<double>() - drivers[m].clamped_ratio);
        double twist = std::abs(sampled["twist"][f][m].get<double>() - drivers[m].twist);
        twist = std::min(twist, std::abs(twist - 2 * M_PI));  // -π and π are the same twist
        INFO("position " << position << " frame " << frame << " ratio " << ratio << " twist " << twist);
        CHECK(position <= kPositionTolerance);
        CHECK(frame <= kFrameTolerance);
        agreement.position = std::max(agreement.position, position);
        agreement.frame = std::max(agreement.frame, frame);
        agreement.ratio = std::max(agreement.ratio, ratio);
        agreement.twist = std::max(agreement.twist, twist);
      }
      // The helper joints (equation 9), muscle by muscle in the extension's order, when baked.
      const std::vector<double> blender_helpers = sampled["helpers"][f].get<std::vector<double>>();
      size_t at = 0;
      for (size_t m = 0; m < muscles; ++m) {
        if (!muscleHasHelpers(baked, m)) continue;
        REQUIRE(at + 48 <= blender_helpers.size());
        for (int k = 0; k < 48 && compared[m]; ++k) {
          const double difference = std::abs(blender_helpers[at + k] - helpers[48 * m + k]);
          if (k % 16 >= 12 && k % 16 < 15) agreement.helper_position = std::max(agreement.helper_position, difference);
          if (k % 16 < 12 && k % 4 != 3) agreement.helper_frame = std::max(agreement.helper_frame, difference);
        }
        at += 48;
      }
      CHECK(at == blender_helpers.size());
      // Jiggling skeleton joints (played by the add-on's frame handler through a constraint) against
      // the C API's jiggled world matrix of each.
      const nlohmann::json& indices = sampled["skeleton_jiggles"];
      const std::vector<double> blender_jiggled = sampled["skeleton_jiggled"][f].get<std::vector<double>>();
      REQUIRE(blender_jiggled.size() == 16 * indices.size());
      // Without the add-on (kAtRest) the file was saved with its jiggles at rest: the joint is where
      // the clip puts it.
      for (size_t i = 0; i < indices.size(); ++i) {
        const int j = indices[i].get<int>();
        REQUIRE(j < jiggles);
        const int node = rigbake_rig_jiggle_node(c_rig.rig, j, 0);
        const auto joint = std::find(skeleton.nodes.begin(), skeleton.nodes.end(), node);
        REQUIRE(joint != skeleton.nodes.end());
        const Eigen::Matrix4d animated = pose.world[joint - skeleton.nodes.begin()].matrix();
        double position = 0, frame = 0;
        for (int k = 0; k < 16; ++k) {
          const double reference = jiggled_muscles == JiggledMuscles::kPlayed ? jiggled[16 * j + k] : animated(k % 4, k / 4);
          if (k < 12 && k % 4 != 3) agreement.jiggle_turn = std::max(agreement.jiggle_turn, std::abs(jiggled[16 * j + k] - animated(k % 4, k / 4)));
          const double difference = std::abs(blender_jiggled[16 * i + k] - reference);
          if (k >= 12 && k < 15) position = std::max(position, difference);
          if (k < 12 && k % 4 != 3) frame = std::max(frame, difference);
        }
        INFO("time " << time << " jiggle " << j << " position " << position << " frame " << frame);
        CHECK(position <= kPositionTolerance);
        CHECK(frame <= kFrameTolerance);
        agreement.jiggle_position = std::max(agreement.jiggle_position, position);
        agreement.jiggle_frame = std::max(agreement.jiggle_frame, frame);
        ++agreement.skeleton_jiggle_frames;
      }
      ++agreement.frames;
    }
  }
  REQUIRE(agreement.clips > 0);
  CHECK(agreement.helper_position <= kPositionTolerance);
  CHECK(agreement.helper_frame <= kFrameTolerance);
  return agreement;
}

struct TestCharacter {
  std::string name;
  std::string input;     // the unbaked character
  std::string move;      // the muscle whose insertion the script moves
  std::string bake_flags;
};

TEST_CASE("Blender add-on: the live rig follows the C++ runtime on every clip, writes the muscle file back, and plays from a saved .blend without the add-on") {
  if (!ext::requireTool(ext::onPath("blender"), "blender (Debian package blender)")) return;
  test::TempDir dir;
  // The mannequin with ROM clips added (rigbake rom), and CesiumMan (its own armature and clip).
  const std::string mannequin = dir / "mannequin.glb";
  runCliOk("sample -o " + quoted(mannequin));
  // Two ROM clips that move what the mannequin's own three clips do not (the shoulder forwards, the
  // spine's twist); all ten cost Blender another 500 keys to sample for code paths these run.
  runCliOk("rom " + quoted(mannequin) + " --clips shoulder_flexion,spine_twist -o " + quoted(dir / "mannequin_rom.glb"));
  // The mannequin with the talk's jiggles (presets/jiggle/gow_examples.json) on both hands and the head,
  // skeleton joints, and on the left biceps' skinned joint, played by the runtime library. The preset's
  // forearm-twist jiggles are left out: the biceps ride the forearm twist joints, and a muscle riding a
  // jiggling skeleton joint is not compared (its drivers read the jiggled pose in Blender).
  nlohmann::json jiggles = readJson(test::sourceDir() + "/presets/jiggle/gow_examples.json");
  jiggles.erase("$schema");
  nlohmann::json kept = nlohmann::json::array();
  for (const nlohmann::json& jiggle : jiggles["jiggles"]) {
    if (jiggle.value("landmark", "").rfind("forearm_twist", 0) != 0) kept.push_back(jiggle);
  }
  REQUIRE(kept.size() == 4);
  jiggles["jiggles"] = kept;
  std::ofstream(dir / "jiggles.json") << jiggles.dump();
  std::vector<TestCharacter> characters = {{"mannequin", dir / "mannequin_rom.glb", "LeftBicep", "--jiggle " + quoted(dir / "jiggles.json")}};
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  if (!cesium.empty()) characters.push_back({"CesiumMan", cesium, "LeftBicep", ""});
  // Cyberpunk: its armature node scales x100 (FBX2glTF), so its bind matrices and its bones' frames do.
  const std::string cyberpunk = test::requireAsset("Quaternius_Cyberpunk_Character.glb");
  if (!cyberpunk.empty()) characters.push_back({"Cyberpunk", cyberpunk, "LeftBicep", ""});

  nlohmann::json jobs = {{"addon_dir", test::sourceDir() + "/blender"}, {"jobs", nlohmann::json::array()}};
  for (const TestCharacter& character : characters) {
    const std::string job_dir = dir / character.name;
    std::filesystem::create_directories(job_dir);
    runCliOk("place " + quoted(character.input) + " -o " + quoted(job_dir + "/muscles.json"));
    runCliOk("bake " + quoted(character.input) + " --muscles " + quoted(job_dir + "/muscles.json") + " --helper-joints " +
             character.bake_flags + " -o " + quoted(job_dir + "/baked.glb"));
    jobs["jobs"].push_back({{"dir", job_dir},
                            {"runtime_library", rigbake::test::kRuntimeLibrary},
                            {"baked", job_dir + "/baked.glb"},
                            {"muscles", job_dir + "/muscles.json"},
                            {"move", {character.move, "insertion"}}});
  }
  // The operators on the sample character; CesiumMan's muscle file is the foreign one.
  if (!cesium.empty()) {
    std::filesystem::create_directories(dir / "operators");
    jobs["operators"] = {{"dir", dir / "operators"},
                         {"rigbake", rigbake::test::kRigbakeCli},
                         {"character", mannequin},
                         {"foreign_muscles", dir / "CesiumMan/muscles.json"}};
  }
  const std::string jobs_path = dir / "jobs.json";
  std::ofstream(jobs_path) << jobs.dump();
  const std::string script = test::sourceDir() + "/tests/blender_rig_check.py";
  for (const char* mode : {"live", "reopen"}) {
    const ext::CommandResult run = ext::runCommand("blender --background --factory-startup --python-exit-code 1 --python " +
                                                   quoted(script) + " -- " + mode + " " + quoted(jobs_path) + " 2>&1");
    INFO(mode << ":\n" << run.output.substr(run.output.size() > 6000 ? run.output.size() - 6000 : 0));
    REQUIRE(run.exit_code == 0);
    // The importer prints and swallows an exception of the add-on's hook: it must not have failed.
    REQUIRE(run.output.find("RIGBAKE_IMPORT_FAILED") == std::string::npos);
    REQUIRE(run.output.find("Dependency cycle") == std::string::npos);
  }

  if (!cesium.empty()) {
    const nlohmann::json operators = readJson(dir / "operators/operators.json");
    INFO(operators.dump());
    for (const char* name : {"place", "bake", "validate", "mirror", "export"}) CHECK(operators[name] == nlohmann::json::array({"FINISHED"}));
    CHECK(operators["armatures"] == 1);
    CHECK(test::fileExists(dir / "operators/exported.json"));
    // rigbake's own line, code first, as the operator's one-line report.
    std::string error = operators.value("foreign_bake_error", "");
    while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
    CHECK(error.find("MUSCLES_MISMATCH ") != std::string::npos);
    CHECK(error.find('\n') == std::string::npos);
  }
  for (const TestCharacter& character : characters) {
    INFO(character.name);
    const std::string job_dir = dir / character.name;
    const std::string baked = job_dir + "/baked.glb";
    int jiggled = 0, jiggled_reopened = 0;
    const Agreement live = compareWithRuntime(baked, readJson(job_dir + "/live.json"), JiggledMuscles::kPlayed, &jiggled);
    if (!character.bake_flags.empty()) {
      CHECK(jiggled > 0);
      CHECK(live.skeleton_jiggle_frames > 0);
      // The jiggles move far more than the tolerance, so a jiggle not played (or frozen) would fail.
      CHECK(live.jiggle_turn > 20 * kFrameTolerance);
      // Bake jiggles to action on the first clip, then that clip played from the keys alone.
      const nlohmann::json baked_jiggles = readJson(job_dir + "/baked_jiggles.json");
      int jiggled_baked = 0;
      const Agreement keyed = compareWithRuntime(baked, baked_jiggles["clips"], JiggledMuscles::kPlayed, &jiggled_baked, Clips::kSampled);
      CHECK(keyed.clips == 1);
      CHECK(jiggled_baked > 0);
      CHECK(keyed.skeleton_jiggle_frames > 0);
      CHECK(baked_jiggles["keys"].get<int>() == keyed.frames * 4);  // the skinned bone and three skeleton joints, per frame
      WARN(character.name << ": jiggles baked to action, " << baked_jiggles["keys"] << " keys, played without the handler: skeleton "
                          << keyed.jiggle_position << " m, " << keyed.jiggle_frame << "; muscles " << keyed.position << " m, " << keyed.frame);
    }
    const nlohmann::json reopened = readJson(job_dir + "/reopened.json");
    CHECK(reopened["addons"].empty());
    const Agreement saved = compareWithRuntime(baked, reopened["clips"], JiggledMuscles::kAtRest, &jiggled_reopened);
    CHECK(saved.skeleton_jiggle_frames == live.skeleton_jiggle_frames);
    WARN(character.name << ": " << live.clips << " clips, " << live.frames << " keys; largest difference from the C++ runtime: "
                        << live.position << " m position, " << live.frame << " rotation/scale, ratio " << live.ratio << ", twist "
                        << live.twist << " rad (" << jiggled << " jiggled muscle frames; " << live.muscles_compared
                        << " muscles compared); skeleton jiggles " << live.jiggle_position << " m, " << live.jiggle_frame << " ("
                        << live.skeleton_jiggle_frames << " frames, turning up to " << live.jiggle_turn << "); helpers " << live.helper_position << " m, " << live.helper_frame
                        << "; reopened without the add-on: " << saved.position << " m, " << saved.frame
                        << " (skeleton jiggles at rest: " << saved.jiggle_position << " m, " << saved.jiggle_frame << ")");

    double largest = 0;
    requireNumbersEqual(readJson(job_dir + "/roundtrip.json"), readJson(job_dir + "/muscles.json"), "roundtrip.json", &largest);

    // Bake with the edited file: the moved insertion is where the script put it.
    const nlohmann::json target = readJson(job_dir + "/moved_target.json");
    runCliOk("bake " + quoted(character.input) + " --muscles " + quoted(job_dir + "/moved.json") + " -o " +
             quoted(job_dir + "/moved.glb"));
    const LoadedCharacter moved = loadCharacter(job_dir + "/moved.glb");
    const BakedFileData file = readBakedFileData(moved);
    REQUIRE(file.rig.present);
    const auto found = std::find(file.rig.names.begin(), file.rig.names.end(), target["muscle"].get<std::string>());
    REQUIRE(found != file.rig.names.end());
    const runtime::RigMuscle<double>& muscle = file.rig.rig.muscles[found - file.rig.names.begin()];
    const Eigen::Vector3d expected(target["world"][0].get<double>(), target["world"][1].get<double>(), target["world"][2].get<double>());
    const Eigen::Vector3d baked_insertion = moved.character.skeleton.bind_world[muscle.insertion_joint] *
                                            Eigen::Vector3d(muscle.insertion_local[0], muscle.insertion_local[1], muscle.insertion_local[2]);
    INFO("baked insertion " << baked_insertion.transpose() << ", moved to " << expected.transpose());
    CHECK((baked_insertion - expected).norm() <= kMovedTolerance);
  }
}

TEST_CASE("Blender add-on: its bl_info version is rigbake's version") {
  const std::string text = test::slurp(test::sourceDir() + "/blender/rigbake_blender/__init__.py");
  std::string version = RIGBAKE_VERSION;
  for (char& c : version) {
    if (c == '.') c = ',';
  }
  std::string expected = "\"version\": (" + version + ")";
  for (size_t at = expected.find(','); at != std::string::npos; at = expected.find(',', at + 2)) expected.insert(at + 1, " ");
  CHECK(text.find(expected) != std::string::npos);
}

}  // namespace rigbake::blender_addon_test
