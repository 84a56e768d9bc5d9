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
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "runtime/muscle_rig.h"

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
  double position = 0, frame = 0, ratio = 0, twist = 0;
  int clips = 0, frames = 0;
};

// The sampled clips of one Blender run against the C++ runtime at the same times.
Agreement compareWithRuntime(const std::string& baked, const nlohmann::json& clips) {
  const LoadedCharacter loaded = loadCharacter(baked);
  const BakedFileData file = readBakedFileData(loaded);
  REQUIRE(file.rig.present);
  REQUIRE(file.rig.problems.empty());
  const Skeleton& skeleton = loaded.character.skeleton;
  const runtime::MuscleRig<double>& rig = file.rig.rig;
  const size_t muscles = rig.muscles.size();
  Agreement agreement;
  for (const Clip& clip : loaded.character.clips) {
    if (clip.gltf_animation < 0 || clip.measure_only) continue;
    INFO(baked << " clip " << clip.name);
    const std::string key = std::to_string(clip.gltf_animation);
    REQUIRE(clips.contains(key));
    const nlohmann::json& sampled = clips.at(key);
    REQUIRE(sampled["times"].size() >= 2);
    ++agreement.clips;
    for (size_t f = 0; f < sampled["times"].size(); ++f) {
      const double time = sampled["times"][f].get<double>();
      const std::vector<double> joints = jointMatrices(sampleClip(skeleton, clip, time));
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
        double position = 0, frame = 0;
        for (int k = 0; k < 16; ++k) {
          const double difference = std::abs(blender[16 * m + k] - skinned[16 * m + k]);
          if (k >= 12 && k < 15) position = std::max(position, difference);
          if (k < 12 && k % 4 != 3) frame = std::max(frame, difference);
        }
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
      ++agreement.frames;
    }
  }
  REQUIRE(agreement.clips > 0);
  return agreement;
}

struct TestCharacter {
  std::string name;
  std::string input;     // the unbaked character
  std::string move;      // the muscle whose insertion the script moves
};

TEST_CASE("blender add-on: the live rig follows the C++ runtime on every clip, writes the muscle file back, and plays from a saved .blend without the add-on") {
  if (!ext::requireTool(ext::onPath("blender"), "blender (Debian package blender)")) return;
  test::TempDir dir;
  // The mannequin with the ROM clips added (rigbake rom), and CesiumMan (its own armature and clip).
  const std::string mannequin = dir / "mannequin.glb";
  runCliOk("sample -o " + quoted(mannequin));
  runCliOk("rom " + quoted(mannequin) + " -o " + quoted(dir / "mannequin_rom.glb"));
  std::vector<TestCharacter> characters = {{"mannequin", dir / "mannequin_rom.glb", "LeftBicep"}};
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  if (!cesium.empty()) characters.push_back({"CesiumMan", cesium, "LeftBicep"});

  nlohmann::json jobs = {{"addon_dir", test::sourceDir() + "/blender"}, {"jobs", nlohmann::json::array()}};
  for (const TestCharacter& character : characters) {
    const std::string job_dir = dir / character.name;
    std::filesystem::create_directories(job_dir);
    runCliOk("place " + quoted(character.input) + " -o " + quoted(job_dir + "/muscles.json"));
    runCliOk("bake " + quoted(character.input) + " --muscles " + quoted(job_dir + "/muscles.json") + " --helper-joints -o " +
             quoted(job_dir + "/baked.glb"));
    jobs["jobs"].push_back({{"dir", job_dir},
                            {"baked", job_dir + "/baked.glb"},
                            {"muscles", job_dir + "/muscles.json"},
                            {"move", {character.move, "insertion"}}});
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

  for (const TestCharacter& character : characters) {
    INFO(character.name);
    const std::string job_dir = dir / character.name;
    const std::string baked = job_dir + "/baked.glb";
    const Agreement live = compareWithRuntime(baked, readJson(job_dir + "/live.json"));
    const nlohmann::json reopened = readJson(job_dir + "/reopened.json");
    CHECK(reopened["addons"].empty());
    const Agreement saved = compareWithRuntime(baked, reopened["clips"]);
    WARN(character.name << ": " << live.clips << " clips, " << live.frames << " keys; largest difference from the C++ runtime: "
                        << live.position << " m position, " << live.frame << " rotation/scale, ratio " << live.ratio << ", twist "
                        << live.twist << " rad; reopened without the add-on: " << saved.position << " m, " << saved.frame);

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

}  // namespace rigbake::blender_addon_test
