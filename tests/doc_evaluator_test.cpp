// The RIGBAKE_muscle_rig document is enough to implement the rig: tests/doc_evaluator/muscle_rig_from_doc.mjs,
// written from docs/extensions/RIGBAKE_muscle_rig.md and the schema alone (never from runtime/ or player/),
// evaluates real bakes in node, and this case holds its skinned joints, helpers and drivers to the C++
// runtime's MuscleRigJob<double> on the same float poses: the mannequin's and CesiumMan's clips and a
// `rigbake rom` forearm twist (the clip that drives the twist curves).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "glb_support.h"
#include "pipeline/pose.h"
#include "runtime/jiggle.h"
#include "runtime/muscle_rig.h"
#include "runtime/muscle_rig_convert.h"

namespace rigbake {
namespace doc_evaluator_test {

using test::runCli;
using test::slurp;
using test::TempDir;

struct Figures {
  double translation = 0.0, linear = 0.0, helper_translation = 0.0, helper_linear = 0.0, ratio = 0.0, twist = 0.0;
  double largest_twist = 0.0;
  size_t frames = 0, muscles = 0, helper_numbers = 0;
};

// Bakes INPUT, writes the poses of the clips whose name starts with CLIP_PREFIX (every clip for "") at
// 30 fps as tests/runtime_c_api_test.cpp does for the WebAssembly check (every node's world matrix in
// float, identity for non-joint nodes), runs the node evaluator on them and compares.
Figures compareOn(const std::string& input, const std::string& clip_prefix) {
  TempDir dir;
  const std::string baked = dir / "baked.glb";
  const test::CliResult run = runCli("bake " + test::external::shellQuote(input) + " --helper-joints -o " + baked);
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const LoadedCharacter loaded = loadCharacter(baked);
  const BakedFileData file = readBakedFileData(loaded);
  const nlohmann::json json = test::glbJson(slurp(baked));
  const int node_count = static_cast<int>(json["nodes"].size());
  const std::string json_path = dir / "extension.json", poses_path = dir / "poses.f32", out_path = dir / "out.f64";
  std::ofstream(json_path, std::ios::binary) << json["extensions"]["RIGBAKE_muscle_rig"].dump();

  const Skeleton& skeleton = loaded.character.skeleton;
  const runtime::MuscleRig<double> rig = runtime::convertMuscleRig<double>(file.rig.rig);
  const size_t muscles = rig.muscles.size();
  std::vector<float> poses;
  std::vector<double> expected;  // per frame and muscle: skinned (16), helpers (48), drivers (3)
  std::vector<double> joints(16 * static_cast<size_t>(skeleton.size())), skinned(16 * muscles), helpers(48 * muscles);
  std::vector<runtime::MuscleDrivers<double>> drivers(muscles);
  Figures figures;
  figures.muscles = muscles;
  for (const Clip& clip : loaded.character.clips) {
    if (clip.name.rfind(clip_prefix, 0) != 0) continue;
    for (double t : sampleTimes(clip, 30.0)) {
      const Pose pose = sampleClip(skeleton, clip, t);
      std::vector<float> nodes(16 * static_cast<size_t>(node_count), 0.0f);
      for (int n = 0; n < node_count; ++n)
        for (int k = 0; k < 4; ++k) nodes[16 * n + 5 * k] = 1.0f;
      for (int j = 0; j < skeleton.size(); ++j) {
        const Eigen::Matrix4d m = pose.world[j].matrix();
        for (int k = 0; k < 16; ++k) {
          const float value = static_cast<float>(m.data()[k]);
          nodes[16 * static_cast<size_t>(skeleton.nodes[j]) + k] = value;
          joints[16 * j + k] = value;  // the float the evaluator reads, widened
        }
      }
      poses.insert(poses.end(), nodes.begin(), nodes.end());
      runtime::MuscleRigJob<double> job;
      job.rig = &rig;
      job.joint_matrices = joints;
      job.skinned_matrices = skinned;
      job.helper_matrices = helpers;
      job.drivers = drivers;
      REQUIRE(job.Run());
      for (size_t m = 0; m < muscles; ++m) {
        expected.insert(expected.end(), skinned.begin() + 16 * m, skinned.begin() + 16 * (m + 1));
        expected.insert(expected.end(), helpers.begin() + 48 * m, helpers.begin() + 48 * (m + 1));
        expected.insert(expected.end(), {drivers[m].ratio, drivers[m].clamped_ratio, drivers[m].twist});
      }
      ++figures.frames;
    }
  }
  REQUIRE(figures.frames > 0);
  std::ofstream(poses_path, std::ios::binary).write(reinterpret_cast<const char*>(poses.data()), poses.size() * sizeof(float));
  const std::string command = "node " + std::string(RIGBAKE_SOURCE_DIR) + "/tests/doc_evaluator_check.mjs " + json_path + " " +
                              std::to_string(node_count) + " " + poses_path + " " + out_path;
  REQUIRE(std::system(command.c_str()) == 0);
  const std::string bytes = slurp(out_path);
  REQUIRE(bytes.size() == expected.size() * sizeof(double));
  std::vector<double> written(expected.size());
  std::memcpy(written.data(), bytes.data(), bytes.size());

  const nlohmann::json& extension_muscles = json["extensions"]["RIGBAKE_muscle_rig"]["muscles"];
  REQUIRE(extension_muscles.size() == muscles);
  for (size_t k = 0; k < expected.size(); ++k) {
    const size_t m = (k / 67) % muscles, at = k % 67;
    const double difference = std::abs(written[k] - expected[k]);
    if (at < 16) {
      if (at % 4 == 3) continue;  // the bottom row, 0 0 0 1 in both
      (at >= 12 ? figures.translation : figures.linear) = std::max(at >= 12 ? figures.translation : figures.linear, difference);
    } else if (at < 64) {
      if (!extension_muscles[m].contains("helperNodes") || at % 4 == 3) continue;
      const bool translation = (at - 16) % 16 >= 12;
      double& worst = translation ? figures.helper_translation : figures.helper_linear;
      worst = std::max(worst, difference);
      ++figures.helper_numbers;
    } else if (at < 66) {
      figures.ratio = std::max(figures.ratio, difference);
    } else {
      // The twist is in (−π, π]: near ±π the two sides may land on either end.
      figures.twist = std::max(figures.twist, std::min(difference, std::abs(difference - 2 * 3.14159265358979323846)));
      figures.largest_twist = std::max(figures.largest_twist, std::abs(expected[k]));
    }
  }
  std::printf("doc evaluator vs MuscleRigJob<double>, %s%s: %zu frames, %zu muscles; largest differences: skinned translation %.3g m, "
              "rotation/scale %.3g; helpers %.3g m, %.3g; ratio %.3g; twist %.3g rad (largest twist %.2f rad)\n",
              std::filesystem::path(input).filename().c_str(), clip_prefix.empty() ? "" : (" clips " + clip_prefix + "*").c_str(),
              figures.frames, figures.muscles, figures.translation, figures.linear, figures.helper_translation, figures.helper_linear,
              figures.ratio, figures.twist, figures.largest_twist);
  CHECK(figures.muscles > 10);
  CHECK(figures.helper_numbers > 0);  // the bake wrote helper nodes, so equation 9 was compared
  CHECK(figures.translation <= 1e-5);
  CHECK(figures.linear <= 1e-4);
  CHECK(figures.helper_translation <= 1e-5);
  CHECK(figures.helper_linear <= 1e-4);
  CHECK(figures.ratio <= 1e-4);
  CHECK(figures.twist <= 1e-4);
  return figures;
}

TEST_CASE("doc evaluator: a node evaluator written from the RIGBAKE_muscle_rig document alone matches the C++ runtime (sample, CesiumMan, ROM)") {
  if (!test::external::requireTool(test::external::onPath("node"), "node")) return;
  compareOn(test::sampleGlbPathForCli(), "");
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  if (!cesium.empty()) compareOn(cesium, "");
  // A ROM clip on the mannequin: the forearm twist turns the insertion joints about the fibre, so the
  // twist driver and the twist curves (equations 4-6) are exercised, not only the ratio.
  TempDir dir;
  const std::string rom = dir / "rom.glb";
  const test::CliResult run = runCli("rom " + test::sampleGlbPathForCli() + " --clips forearm_twist -o " + rom);
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const Figures figures = compareOn(rom, "rom_");
  CHECK(figures.largest_twist > 0.5);
}

// The jiggles (equation 10) stepped by tests/doc_evaluator/jiggles_from_doc.mjs against JiggleJob<double>,
// driven as tests/runtime_c_api_test.cpp drives the C API: every clip of INPUT baked with `--jiggle biceps`
// at 30 fps and again at 50 fps (which 240 Hz does not divide, so the leftover time, the interpolated
// step poses and the extrapolated output of 10b and 10f are compared too). Each clip's run: a reset at
// rest at its first frame, a hit on the first jiggle at frame 5, one long frame (a hitch: the clip jumps
// kLongFrameKeys samples ahead in one frame) stepped with a cap of kMaxSteps steps, and a reset moving
// with the target (10a's second pose: the sample before at 30 fps, after at 50 fps). The jiggling nodes
// are muscle skinned nodes, so their matrices are MuscleRigJob's (10, "Order").
constexpr int kLongFrameKeys = 12;  // 0.4 s at 30 fps (96 steps due), 0.24 s at 50 fps (57 or 58)
constexpr int kMaxSteps = 10;

struct JiggleFigures {
  double point = 0.0, correction = 0.0, matrix_translation = 0.0, matrix_linear = 0.0, largest_angle = 0.0;
  double cap_effect = 0.0, velocity_effect = 0.0;  // how far the capped frame and the moving reset are from uncapped / at rest
  size_t frames = 0, jiggles = 0;
};

runtime::JiggleRig<double> jiggleRigOf(const nlohmann::json& extension, int node_count) {
  runtime::JiggleRig<double> jiggle_rig;
  jiggle_rig.joint_count = node_count;
  for (const nlohmann::json& item : extension.at("jiggles")) {
    runtime::JiggleSpec<double> spec;
    spec.joint = item.at("node").get<int>();
    spec.parent = item.at("parentNode").get<int>();
    spec.root = item.at("rootNode").get<int>();
    for (int k = 0; k < 3; ++k) {
      spec.aim_axis[k] = item.at("aimAxis")[k].get<double>();
      spec.major_axis[k] = item.at("majorAxis")[k].get<double>();
      spec.root_up[k] = item.at("rootUp")[k].get<double>();
    }
    spec.length = item.at("length").get<double>();
    spec.stiffness = item.at("stiffness").get<double>();
    spec.damping = item.at("damping").get<double>();
    spec.clamp_major_deg = item.at("clampMajorDeg").get<double>();
    spec.clamp_minor_deg = item.at("clampMinorDeg").get<double>();
    REQUIRE(*runtime::jiggleSpecProblem(spec, node_count) == '\0');
    jiggle_rig.jiggles.push_back(runtime::buildJiggleSettings(spec));
  }
  return jiggle_rig;
}

// The largest difference between two jiggle states' points after one more frame of `dt` on `nodes`.
double pointsApart(const runtime::JiggleRig<double>& rig, const std::vector<double>& nodes, double dt, int max_steps,
                   std::vector<runtime::JiggleState> a, int a_max_steps, std::vector<runtime::JiggleState> b) {
  std::vector<double> pa(3 * a.size()), pb(3 * b.size());
  for (int pass = 0; pass < 2; ++pass) {
    runtime::JiggleJob<double> job;
    job.rig = &rig;
    job.joint_matrices = nodes;
    job.delta_time = dt;
    job.max_steps = pass == 0 ? a_max_steps : max_steps;
    job.states = pass == 0 ? runtime::Span<runtime::JiggleState>(a) : runtime::Span<runtime::JiggleState>(b);
    job.points = pass == 0 ? runtime::Span<double>(pa) : runtime::Span<double>(pb);
    REQUIRE(job.Run());
  }
  double apart = 0.0;
  for (size_t k = 0; k < pa.size(); ++k) apart = std::max(apart, std::abs(pa[k] - pb[k]));
  return apart;
}

JiggleFigures compareJigglesOn(const std::string& input) {
  TempDir dir;
  const std::string baked = dir / "baked.glb";
  const test::CliResult run = runCli("bake " + test::external::shellQuote(input) + " --jiggle biceps -o " + baked);
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const LoadedCharacter loaded = loadCharacter(baked);
  const BakedFileData file = readBakedFileData(loaded);
  const nlohmann::json json = test::glbJson(slurp(baked));
  const nlohmann::json& extension = json["extensions"]["RIGBAKE_muscle_rig"];
  const int node_count = static_cast<int>(json["nodes"].size());
  const std::string json_path = dir / "extension.json", poses_path = dir / "poses.f64", frames_path = dir / "frames.json",
                    out_path = dir / "out.f64";
  std::ofstream(json_path, std::ios::binary) << extension.dump();
  const runtime::JiggleRig<double> jiggle_rig = jiggleRigOf(extension, node_count);
  JiggleFigures figures;
  figures.jiggles = jiggle_rig.jiggles.size();
  const size_t jiggles = figures.jiggles;
  REQUIRE(jiggles >= 2);

  const Skeleton& skeleton = loaded.character.skeleton;
  const runtime::MuscleRig<double> rig = runtime::convertMuscleRig<double>(file.rig.rig);
  const size_t muscles = rig.muscles.size();
  std::vector<double> poses, expected, joints(16 * static_cast<size_t>(skeleton.size())), skinned(16 * muscles);
  std::vector<double> corrections(4 * jiggles), points(3 * jiggles), model_matrices(16 * jiggles);
  std::vector<runtime::JiggleState> states(jiggles);
  size_t pose_count = 0;
  // Every node's un-jiggled world matrix at `time` of `clip` (muscle skinned nodes: MuscleRigJob's), appended
  // to the poses the evaluator reads; returns the matrices and the pose's index there.
  auto poseAt = [&](const Clip& clip, double time, std::vector<double>* nodes) {
    const Pose pose = sampleClip(skeleton, clip, time);
    nodes->assign(16 * static_cast<size_t>(node_count), 0.0);
    for (int n = 0; n < node_count; ++n)
      for (int k = 0; k < 4; ++k) (*nodes)[16 * n + 5 * k] = 1.0;
    for (int j = 0; j < skeleton.size(); ++j) {
      const Eigen::Matrix4d m = pose.world[j].matrix();
      for (int k = 0; k < 16; ++k) {
        const double value = static_cast<float>(m.data()[k]);  // the float an engine gives, widened
        (*nodes)[16 * static_cast<size_t>(skeleton.nodes[j]) + k] = value;
        joints[16 * j + k] = value;
      }
    }
    runtime::MuscleRigJob<double> muscle_job;
    muscle_job.rig = &rig;
    muscle_job.joint_matrices = joints;
    muscle_job.skinned_matrices = skinned;
    REQUIRE(muscle_job.Run());
    for (size_t m = 0; m < muscles; ++m) {
      const size_t node = extension["muscles"][m].at("skinnedNode").get<size_t>();
      std::copy(skinned.begin() + 16 * m, skinned.begin() + 16 * (m + 1), nodes->begin() + 16 * node);
    }
    poses.insert(poses.end(), nodes->begin(), nodes->end());
    return pose_count++;
  };
  nlohmann::json frames = nlohmann::json::array();
  const double hit[3] = {0.3, 0.0, 1.0};
  std::vector<double> nodes, second;
  for (const double fps : {30.0, 50.0}) {
    for (const Clip& clip : loaded.character.clips) {
      const std::vector<double> all = sampleTimes(clip, fps);
      REQUIRE(all.size() > static_cast<size_t>(3 * kLongFrameKeys));
      // The frames: every sample but the kLongFrameKeys - 1 skipped after the long frame's start.
      const size_t long_from = all.size() / 3, moving_reset_at = 2 * all.size() / 3;
      std::vector<size_t> keys;
      std::vector<runtime::JiggleState> at_rest;  // the states a reset at rest would have given at moving_reset_at
      for (size_t k = 0; k < all.size(); ++k)
        if (k <= long_from || k >= long_from + kLongFrameKeys) keys.push_back(k);
      for (size_t f = 0; f < keys.size(); ++f) {
        const size_t key = keys[f];
        const double time = all[key];
        const size_t pose = poseAt(clip, time, &nodes);
        nlohmann::json frame = {{"pose", pose}, {"reset", f == 0}, {"hit", nullptr}, {"maxSteps", 0}};
        double dt = f == 0 ? 0.0 : time - all[keys[f - 1]];
        if (f == 0) {
          runtime::JiggleResetJob<double> reset;
          reset.rig = &jiggle_rig;
          reset.joint_matrices = nodes;
          reset.states = states;
          REQUIRE(reset.Run());
        } else if (key == moving_reset_at) {
          // A character appearing in motion: the reset is given the pose one sample away and starts the
          // jiggle points moving with their targets; no time passes on the reset frame (10a).
          const size_t other_key = fps == 30.0 ? key - 1 : key + 1;
          const double delta = all[other_key] - time;
          const size_t other = poseAt(clip, all[other_key], &second);
          at_rest = states;
          runtime::JiggleResetJob<double> reset;
          reset.rig = &jiggle_rig;
          reset.joint_matrices = nodes;
          reset.velocity_matrices = second;
          reset.velocity_time = delta;
          reset.states = states;
          REQUIRE(reset.Run());
          runtime::JiggleResetJob<double> rest_reset = reset;
          rest_reset.velocity_matrices = {};
          rest_reset.velocity_time = 0;
          rest_reset.states = at_rest;
          REQUIRE(rest_reset.Run());
          frame["reset"] = {{"pose", other}, {"delta", delta}};
          dt = 0.0;
        }
        if (f == 5) {
          REQUIRE(runtime::applyJiggleImpulse<double>(states, 0, hit, 1.5));
          frame["hit"] = nlohmann::json::array({0, hit, 1.5});
        }
        const int max_steps = key == long_from + kLongFrameKeys ? kMaxSteps : 0;
        if (max_steps > 0) {
          REQUIRE(std::floor(dt * 240.0) > kMaxSteps);  // more steps are due than the cap lets through
          figures.cap_effect = std::max(figures.cap_effect, pointsApart(jiggle_rig, nodes, dt, 0, states, max_steps, states));
        }
        if (f > 0 && keys[f - 1] == moving_reset_at) {
          // The next frame after the moving reset, against a reset at rest there: the velocity mattered.
          figures.velocity_effect = std::max(figures.velocity_effect, pointsApart(jiggle_rig, nodes, dt, 0, states, 0, at_rest));
        }
        frame["dt"] = dt;
        frame["maxSteps"] = max_steps;
        frames.push_back(frame);
        runtime::JiggleJob<double> job;
        job.rig = &jiggle_rig;
        job.joint_matrices = nodes;
        job.delta_time = dt;
        job.max_steps = max_steps;
        job.states = states;
        job.corrections = corrections;
        job.points = points;
        job.model_matrices = model_matrices;
        REQUIRE(job.Run());
        for (size_t j = 0; j < jiggles; ++j) {
          expected.insert(expected.end(), corrections.begin() + 4 * j, corrections.begin() + 4 * (j + 1));
          expected.insert(expected.end(), points.begin() + 3 * j, points.begin() + 3 * (j + 1));
          expected.insert(expected.end(), model_matrices.begin() + 16 * j, model_matrices.begin() + 16 * (j + 1));
        }
      }
    }
  }
  figures.frames = frames.size();
  std::ofstream(poses_path, std::ios::binary).write(reinterpret_cast<const char*>(poses.data()), poses.size() * sizeof(double));
  std::ofstream(frames_path, std::ios::binary) << frames.dump();
  const std::string command = "node " + std::string(RIGBAKE_SOURCE_DIR) + "/tests/doc_evaluator_jiggle_check.mjs " + json_path + " " +
                              std::to_string(node_count) + " " + poses_path + " " + frames_path + " " + out_path;
  REQUIRE(std::system(command.c_str()) == 0);
  const std::string bytes = slurp(out_path);
  REQUIRE(bytes.size() == expected.size() * sizeof(double));
  std::vector<double> written(expected.size());
  std::memcpy(written.data(), bytes.data(), bytes.size());
  for (size_t at = 0; at < expected.size(); at += 23) {
    // q and -q are the same rotation.
    double same = 0.0, opposite = 0.0;
    for (int k = 0; k < 4; ++k) {
      same = std::max(same, std::abs(written[at + k] - expected[at + k]));
      opposite = std::max(opposite, std::abs(written[at + k] + expected[at + k]));
    }
    figures.correction = std::max(figures.correction, std::min(same, opposite));
    for (int k = 4; k < 7; ++k) figures.point = std::max(figures.point, std::abs(written[at + k] - expected[at + k]));
    for (int k = 0; k < 16; ++k) {
      double& worst = k >= 12 ? figures.matrix_translation : figures.matrix_linear;
      worst = std::max(worst, std::abs(written[at + 7 + k] - expected[at + 7 + k]));
    }
    figures.largest_angle =
        std::max(figures.largest_angle, 2.0 * std::acos(std::min(1.0, std::abs(expected[at + 3]))) * 180.0 / 3.14159265358979323846);
  }
  std::printf("doc evaluator jiggles vs JiggleJob<double>, %s --jiggle biceps, 30 and 50 fps: %zu frames, %zu jiggles, largest correction "
              "%.2f deg; the cap moved the long frame's points %.3g m, the moving reset the next frame's %.3g m; largest differences: "
              "point %.3g m, correction quaternion %.3g, jiggled world matrix %.3g m, %.3g\n",
              std::filesystem::path(input).filename().c_str(), figures.frames, jiggles, figures.largest_angle, figures.cap_effect,
              figures.velocity_effect, figures.point, figures.correction, figures.matrix_translation, figures.matrix_linear);
  CHECK(figures.largest_angle > 1.0);  // the jiggles moved, so the spring, the hit and the clamp were compared
  CHECK(figures.cap_effect > 1e-4);       // the cap changed the long frame: an evaluator without it would differ
  CHECK(figures.velocity_effect > 1e-5);  // the reset's velocity changed what follows
  // Both sides step in double from the same numbers, so anything above rounding is a different equation:
  // reading 10g's S as the full R_localᵀ · (local linear part) instead of its diagonal was 7.2e-8 off on
  // CesiumMan, whose float-rounded poses give the jiggling nodes' local matrices a shear of that size.
  CHECK(figures.point <= 1e-9);
  CHECK(figures.correction <= 1e-9);
  CHECK(figures.matrix_translation <= 1e-9);
  CHECK(figures.matrix_linear <= 1e-9);
  return figures;
}

TEST_CASE("doc evaluator: the jiggles written from the RIGBAKE_muscle_rig document alone match JiggleJob<double> (sample, CesiumMan, hits, resets, cap)") {
  if (!test::external::requireTool(test::external::onPath("node"), "node")) return;
  compareJigglesOn(test::sampleGlbPathForCli());
  const std::string cesium = test::requireAsset("CesiumMan.glb");
  if (!cesium.empty()) compareJigglesOn(cesium);
}

}  // namespace doc_evaluator_test
}  // namespace rigbake
