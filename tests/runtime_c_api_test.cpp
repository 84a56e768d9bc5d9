// The runtime's C API (runtime/rigbake_runtime.h) on real bakes: its JSON reader gives formats/'s rig bit
// for bit; its muscles are the C++ float runtime's bit for bit and the sampled bake's within 1e-5 m; its
// jiggles are JiggleJob's bit for bit, hits included; a C program on the shared library computes the
// same; malformed text is refused with where and why, never a crash.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/baked_gltf.h"
#include "formats/gltf_document.h"
#include "glb_support.h"
#include "pipeline/checks.h"
#include "pipeline/pose.h"
#include "runtime/jiggle.h"
#include "runtime/muscle_rig_convert.h"
#include "runtime/rig_json.h"
#include "runtime/rigbake_runtime.h"

namespace rigbake {
namespace runtime_c_api_test {

using test::runCli;
using test::slurp;
using test::TempDir;

// A bake read three ways: the character (poses), formats/'s data (the rig on skeleton joints) and the
// JSON (the extension's text and the node count the C API needs).
struct Bake {
  std::string path;
  LoadedCharacter loaded;
  BakedFileData file;
  std::string extension_text;
  int node_count = 0;
};

struct RigDeleter {
  void operator()(rigbake_rig* rig) const { rigbake_rig_destroy(rig); }
};
using RigHandle = std::unique_ptr<rigbake_rig, RigDeleter>;

std::unique_ptr<Bake> bakeOf(const TempDir& dir, const std::string& input, const std::string& name, const std::string& flags) {
  auto bake = std::make_unique<Bake>();
  bake->path = dir / (name + ".glb");
  const test::CliResult run = runCli("bake " + test::external::shellQuote(input) + " " + flags + " -o " + bake->path);
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  bake->loaded = loadCharacter(bake->path);
  bake->file = readBakedFileData(bake->loaded);
  const nlohmann::json json = test::glbJson(slurp(bake->path));
  bake->node_count = static_cast<int>(json["nodes"].size());
  if (json.contains("extensions") && json["extensions"].contains("RIGBAKE_muscle_rig"))
    bake->extension_text = json["extensions"]["RIGBAKE_muscle_rig"].dump();
  return bake;
}

// The bakes the cases read, each made once per test process when a case first asks for it (ctest runs
// every case in its own process): the sample (runtime with the biceps jiggles, and sampled) and
// CesiumMan (runtime with the biceps jiggles; null when the asset is not there outside CI).
const TempDir& bakeDir() {
  static const TempDir dir;
  return dir;
}
const Bake& sampleRuntime() {
  static const std::unique_ptr<Bake> bake = bakeOf(bakeDir(), test::sampleGlbPathForCli(), "sample_runtime", "--jiggle biceps");
  return *bake;
}
const Bake& sampleSampled() {
  // Without jiggles: a sampled bake's jiggles rotate the skinned joints' channels.
  static const std::unique_ptr<Bake> bake = bakeOf(bakeDir(), test::sampleGlbPathForCli(), "sample_sampled", "--muscle-motion sampled");
  return *bake;
}
const Bake* cesium() {
  static const std::unique_ptr<Bake> bake = [] {
    const std::string path = test::requireAsset("CesiumMan.glb");
    return path.empty() ? nullptr : bakeOf(bakeDir(), path, "cesium", "--jiggle biceps");
  }();
  return bake.get();
}

RigHandle createRig(const Bake& bake) {
  RigHandle rig(rigbake_rig_create(bake.extension_text.data(), bake.extension_text.size(), bake.node_count));
  INFO(rigbake_last_error());
  REQUIRE(rig);
  return rig;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// The pose's world matrices as the C API takes them (one per node, identity for non-joint nodes) and
// as the C++ runtime took them before (one per skeleton joint), both in float.
void poseMatrices(const Bake& bake, const Pose& pose, std::vector<float>* nodes, std::vector<float>* joints) {
  const Skeleton& skeleton = bake.loaded.character.skeleton;
  nodes->assign(16 * static_cast<size_t>(bake.node_count), 0.0f);
  for (int n = 0; n < bake.node_count; ++n)
    for (int k = 0; k < 4; ++k) (*nodes)[16 * n + 5 * k] = 1.0f;
  joints->assign(16 * static_cast<size_t>(skeleton.size()), 0.0f);
  for (int j = 0; j < skeleton.size(); ++j) {
    const Eigen::Matrix4d m = pose.world[j].matrix();
    for (int k = 0; k < 16; ++k) {
      (*joints)[16 * j + k] = static_cast<float>(m.data()[k]);
      (*nodes)[16 * static_cast<size_t>(skeleton.nodes[j]) + k] = static_cast<float>(m.data()[k]);
    }
  }
}

void compareRigs(const Bake& bake) {
  runtime::RigFile read;
  std::string error;
  REQUIRE(runtime::readRigJson(bake.extension_text.data(), bake.extension_text.size(), bake.node_count, &read, &error));
  const FileMuscleRig& formats = bake.file.rig;
  REQUIRE(formats.present);
  REQUIRE(formats.problems.empty());
  const std::vector<int>& node = bake.loaded.character.skeleton.nodes;
  REQUIRE(read.rig.muscles.size() == formats.rig.muscles.size());
  REQUIRE(read.rig.keys.size() == formats.rig.keys.size());
  CHECK(read.rig.joint_count == bake.node_count);
  int numbers = 0;
  for (size_t m = 0; m < read.rig.muscles.size(); ++m) {
    const runtime::RigMuscle<double>& a = read.rig.muscles[m];
    const runtime::RigMuscle<double>& b = formats.rig.muscles[m];
    INFO(formats.names[m]);
    CHECK(read.muscle_names[m] == formats.names[m]);
    CHECK(read.skinned_nodes[m] == node[formats.skinned_joint[m]]);
    CHECK(a.origin_joint == node[b.origin_joint]);
    CHECK(a.insertion_joint == node[b.insertion_joint]);
    CHECK(a.carrier_joint == node[b.carrier_joint]);
    CHECK(read.muscle_corrective[m] == (formats.kinds[m] == PartKind::kCorrective));
    std::vector<std::pair<const double*, const double*>> arrays = {
        {a.origin_local, b.origin_local}, {a.insertion_local, b.insertion_local}, {a.fibre_local, b.fibre_local},
        {a.up_local, b.up_local}, {a.twist_axis_local, b.twist_axis_local}};
    for (auto [x, y] : arrays)
      for (int k = 0; k < 3; ++k, ++numbers) CHECK(sameBits(x[k], y[k]));
    for (int k = 0; k < 4; ++k, ++numbers) CHECK(sameBits(a.insertion_bind_in_origin[k], b.insertion_bind_in_origin[k]));
    for (int k = 0; k < 2; ++k, ++numbers) CHECK(sameBits(a.driver_offset[k], b.driver_offset[k]));
    for (int k = 0; k < 16; ++k, ++numbers) CHECK(sameBits(a.skinned_in_carrier[k], b.skinned_in_carrier[k]));
    for (auto [x, y] : {std::pair<double, double>{a.rest_length, b.rest_length}, {a.compression, b.compression},
                        {a.stretch, b.stretch}, {a.driver_fraction, b.driver_fraction}}) {
      CHECK(sameBits(x, y));
      ++numbers;
    }
    CHECK(a.ratio_key_begin == b.ratio_key_begin);
    CHECK(a.ratio_key_count == b.ratio_key_count);
    CHECK(a.twist_key_begin == b.twist_key_begin);
    CHECK(a.twist_key_count == b.twist_key_count);
  }
  for (size_t k = 0; k < read.rig.keys.size(); ++k) {
    const runtime::ResponseKey<double>& a = read.rig.keys[k];
    const runtime::ResponseKey<double>& b = formats.rig.keys[k];
    CHECK((sameBits(a.at, b.at) && sameBits(a.up, b.up) && sameBits(a.side, b.side) && sameBits(a.scale, b.scale)));
    numbers += 4;
  }
  std::printf("C API reader vs formats/ reader, %s: %zu muscles, %d numbers, bit for bit\n",
              std::filesystem::path(bake.path).filename().c_str(), read.rig.muscles.size(), numbers);
}

TEST_CASE("runtime C API: its JSON reader gives formats/'s rig bit for bit (sample, CesiumMan)") {
  compareRigs(sampleRuntime());
  if (cesium()) compareRigs(*cesium());
}

// Every frame of every clip at the bake's own sample times: the C API's skinned matrices equal
// MuscleRigJob<float>'s on formats/'s rig (the same code on the same numbers) bit for bit; returns the
// frames compared.
int compareWithCppRuntime(const Bake& bake, const Bake* sampled, double* worst_sampled) {
  const RigHandle rig = createRig(bake);
  const runtime::MuscleRig<float> cpp = runtime::convertMuscleRig<float>(bake.file.rig.rig);
  const size_t muscles = cpp.muscles.size();
  REQUIRE(static_cast<size_t>(rigbake_rig_muscle_count(rig.get())) == muscles);
  const Character& character = bake.loaded.character;
  std::vector<float> nodes, joints, ours(16 * muscles), theirs(16 * muscles), helpers(48 * muscles), drivers(3 * muscles);
  std::vector<runtime::MuscleDrivers<float>> cpp_drivers(muscles);
  std::vector<float> cpp_helpers(48 * muscles);
  int frames = 0;
  for (size_t c = 0; c < character.clips.size(); ++c) {
    const Clip& times_clip = sampled ? sampled->loaded.character.clips[c] : character.clips[c];
    for (double t : sampleTimes(times_clip, sampled ? 0.0 : 30.0)) {
      poseMatrices(bake, sampleClip(character.skeleton, character.clips[c], t), &nodes, &joints);
      REQUIRE(rigbake_rig_evaluate(rig.get(), nodes.data(), ours.data(), helpers.data(), drivers.data()) == RIGBAKE_OK);
      runtime::MuscleRigJob<float> job;
      job.rig = &cpp;
      job.joint_matrices = joints;
      job.skinned_matrices = theirs;
      job.helper_matrices = cpp_helpers;
      job.drivers = cpp_drivers;
      REQUIRE(job.Run());
      for (size_t k = 0; k < ours.size(); ++k) REQUIRE(sameBits(ours[k], theirs[k]));
      for (size_t k = 0; k < helpers.size(); ++k) REQUIRE(sameBits(helpers[k], cpp_helpers[k]));
      for (size_t m = 0; m < muscles; ++m) {
        REQUIRE(sameBits(drivers[3 * m], cpp_drivers[m].ratio));
        REQUIRE(sameBits(drivers[3 * m + 1], cpp_drivers[m].clamped_ratio));
        REQUIRE(sameBits(drivers[3 * m + 2], cpp_drivers[m].twist));
      }
      if (sampled) {
        // The sampled bake's skinned joint, found by name, played from its channels.
        const Pose played = sampleClip(sampled->loaded.character.skeleton, sampled->loaded.character.clips[c], t);
        for (size_t m = 0; m < muscles; ++m) {
          const std::string& name = character.skeleton.names[bake.file.rig.skinned_joint[m]];
          const int joint = sampled->loaded.character.skeleton.find(name);
          REQUIRE(joint >= 0);
          const Eigen::Matrix4d expected = played.world[joint].matrix();
          for (int k = 0; k < 16; ++k) *worst_sampled = std::max(*worst_sampled, std::abs(ours[16 * m + k] - expected.data()[k]));
        }
      }
      ++frames;
    }
  }
  return frames;
}

TEST_CASE("runtime C API: muscles are the C++ float runtime's bit for bit and the sampled bake's within 1e-5 m on every clip") {
  double worst = 0.0;
  const int frames = compareWithCppRuntime(sampleRuntime(), &sampleSampled(), &worst);
  std::printf("C API muscles vs sampled bake (sample): %d frames, largest difference %.3g m\n", frames, worst);
  CHECK(frames > 100);
  CHECK(worst <= 1e-5);
  if (cesium()) {
    double unused = 0.0;
    CHECK(compareWithCppRuntime(*cesium(), nullptr, &unused) > 10);
  }
}

// The extension's jiggles as JiggleSpec<float>, read with nlohmann (not the C API's reader).
runtime::JiggleRig<float> referenceJiggles(const Bake& bake) {
  const nlohmann::json extension = nlohmann::json::parse(bake.extension_text);
  runtime::JiggleRig<float> rig;
  rig.joint_count = bake.node_count;
  for (const nlohmann::json& item : extension.at("jiggles")) {
    runtime::JiggleSpec<float> spec;
    spec.joint = item.at("node").get<int>();
    spec.parent = item.at("parentNode").get<int>();
    spec.root = item.at("rootNode").get<int>();
    for (int k = 0; k < 3; ++k) {
      spec.aim_axis[k] = static_cast<float>(item.at("aimAxis")[k].get<double>());
      spec.major_axis[k] = static_cast<float>(item.at("majorAxis")[k].get<double>());
      spec.root_up[k] = static_cast<float>(item.at("rootUp")[k].get<double>());
    }
    spec.length = static_cast<float>(item.at("length").get<double>());
    spec.stiffness = static_cast<float>(item.at("stiffness").get<double>());
    spec.damping = static_cast<float>(item.at("damping").get<double>());
    spec.clamp_major_deg = static_cast<float>(item.at("clampMajorDeg").get<double>());
    spec.clamp_minor_deg = static_cast<float>(item.at("clampMinorDeg").get<double>());
    REQUIRE(*runtime::jiggleSpecProblem(spec, bake.node_count) == '\0');
    rig.jiggles.push_back(runtime::buildJiggleSettings(spec));
  }
  return rig;
}

TEST_CASE("runtime C API: jiggles are JiggleJob's bit for bit over every clip at 30 fps, a hit and a reset included") {
  const Bake& bake = sampleRuntime();
  const RigHandle rig = createRig(bake);
  const runtime::JiggleRig<float> reference = referenceJiggles(bake);
  const size_t jiggles = reference.jiggles.size();
  REQUIRE(jiggles >= 2);
  REQUIRE(static_cast<size_t>(rigbake_rig_jiggle_count(rig.get())) == jiggles);
  std::vector<runtime::JiggleState> states(jiggles);
  const size_t muscles = static_cast<size_t>(rigbake_rig_muscle_count(rig.get()));
  std::vector<float> nodes, joints, skinned(16 * muscles);
  std::vector<float> ours[4] = {std::vector<float>(4 * jiggles), std::vector<float>(4 * jiggles), std::vector<float>(16 * jiggles),
                                std::vector<float>(3 * jiggles)};
  std::vector<float> theirs[4] = {ours[0], ours[1], ours[2], ours[3]};
  const float hit[3] = {0.3f, 0.0f, 1.0f};
  const Character& character = bake.loaded.character;
  int frames = 0;
  double largest_angle = 0.0;
  for (size_t c = 0; c < character.clips.size(); ++c) {
    const std::vector<double> times = sampleTimes(character.clips[c], 30.0);
    for (size_t f = 0; f < times.size(); ++f) {
      poseMatrices(bake, sampleClip(character.skeleton, character.clips[c], times[f]), &nodes, &joints);
      REQUIRE(rigbake_rig_evaluate(rig.get(), nodes.data(), skinned.data(), nullptr, nullptr) == RIGBAKE_OK);
      REQUIRE(rigbake_rig_store_skinned(rig.get(), skinned.data(), nodes.data()) == RIGBAKE_OK);
      if (f == 0) {
        // Each clip starts from rest, as a game starts a character.
        REQUIRE(rigbake_jiggle_reset(rig.get(), nodes.data(), nullptr, 0.0f) == RIGBAKE_OK);
        runtime::JiggleResetJob<float> reset;
        reset.rig = &reference;
        reset.joint_matrices = nodes;
        reset.states = states;
        REQUIRE(reset.Run());
      }
      if (f == 10) {
        REQUIRE(rigbake_jiggle_impulse(rig.get(), 0, hit, 1.5f) == RIGBAKE_OK);
        REQUIRE(runtime::applyJiggleImpulse<float>(states, 0, hit, 1.5f));
      }
      const float dt = f == 0 ? 0.0f : static_cast<float>(times[f] - times[f - 1]);
      REQUIRE(rigbake_jiggle_step(rig.get(), nodes.data(), dt, 0, ours[0].data(), ours[1].data(), ours[2].data(), ours[3].data()) ==
              RIGBAKE_OK);
      runtime::JiggleJob<float> job;
      job.rig = &reference;
      job.joint_matrices = nodes;
      job.delta_time = dt;
      job.states = states;
      job.corrections = theirs[0];
      job.local_rotations = theirs[1];
      job.model_matrices = theirs[2];
      job.points = theirs[3];
      REQUIRE(job.Run());
      for (int o = 0; o < 4; ++o)
        for (size_t k = 0; k < ours[o].size(); ++k) REQUIRE(sameBits(ours[o][k], theirs[o][k]));
      for (size_t j = 0; j < jiggles; ++j)
        largest_angle = std::max(largest_angle, 2.0 * std::acos(std::min(1.0, std::abs(double(ours[0][4 * j + 3])))));
      ++frames;
    }
  }
  std::printf("C API jiggles vs JiggleJob<float>: %zu jiggles, %d frames, largest correction %.2f deg, bit for bit\n", jiggles, frames,
              largest_angle * 180.0 / 3.14159265358979323846);
  CHECK(frames > 100);
  // The jiggles moved: a comparison of two rigs at rest would prove nothing.
  CHECK(largest_angle > 1e-3);
}

// The frames tests/c_api/runtime_c_check.c and tests/runtime_wasm_check.mjs run: every clip's poses at
// 30 fps in one sequence, written with the extension's text for a program to read.
struct FrameInputs {
  std::string json_path, poses_path;
  std::vector<float> poses;
  size_t frames = 0;
};
constexpr float kFrameSeconds = 1.0f / 30.0f;

FrameInputs writeFrameInputs(const Bake& bake, const TempDir& dir, size_t clip_count) {
  FrameInputs in;
  in.json_path = dir / "extension.json";
  in.poses_path = dir / "poses.f32";
  std::ofstream(in.json_path, std::ios::binary) << bake.extension_text;
  const Character& character = bake.loaded.character;
  REQUIRE(!character.clips.empty());
  std::vector<float> nodes, joints;
  for (size_t c = 0; c < std::min(clip_count, character.clips.size()); ++c) {
    for (double t : sampleTimes(character.clips[c], 30.0)) {
      poseMatrices(bake, sampleClip(character.skeleton, character.clips[c], t), &nodes, &joints);
      in.poses.insert(in.poses.end(), nodes.begin(), nodes.end());
      ++in.frames;
    }
  }
  std::ofstream(in.poses_path, std::ios::binary).write(reinterpret_cast<const char*>(in.poses.data()), in.poses.size() * sizeof(float));
  return in;
}

// The programs' frame seconds: printed as decimal text, read back as a float.
float frameSecondsAsRead() { return static_cast<float>(std::atof(std::to_string(kFrameSeconds).c_str())); }
std::string programArguments(const Bake& bake, const FrameInputs& in, const std::string& out_path) {
  return in.json_path + " " + std::to_string(bake.node_count) + " " + in.poses_path + " " + std::to_string(kFrameSeconds) + " " + out_path;
}

// The same frames through the in-process C API: per frame the skinned matrices, then the corrections.
std::vector<float> inProcessFrames(const Bake& bake, const FrameInputs& in) {
  const RigHandle rig = createRig(bake);
  const size_t muscles = static_cast<size_t>(rigbake_rig_muscle_count(rig.get()));
  const size_t jiggles = static_cast<size_t>(rigbake_rig_jiggle_count(rig.get()));
  const size_t node_floats = 16 * static_cast<size_t>(bake.node_count);
  std::vector<float> expected, skinned(16 * muscles), corrections(4 * jiggles);
  const float hit[3] = {0.0f, 0.0f, 1.0f};
  for (size_t f = 0; f < in.frames; ++f) {
    std::vector<float> pose(in.poses.begin() + f * node_floats, in.poses.begin() + (f + 1) * node_floats);
    REQUIRE(rigbake_rig_evaluate(rig.get(), pose.data(), skinned.data(), nullptr, nullptr) == RIGBAKE_OK);
    REQUIRE(rigbake_rig_store_skinned(rig.get(), skinned.data(), pose.data()) == RIGBAKE_OK);
    if (f == 5 && jiggles > 0) REQUIRE(rigbake_jiggle_impulse(rig.get(), -1, hit, 2.0f) == RIGBAKE_OK);
    REQUIRE(rigbake_jiggle_step(rig.get(), pose.data(), f == 0 ? 0.0f : frameSecondsAsRead(), 0, corrections.data(), nullptr, nullptr,
                                nullptr) == RIGBAKE_OK);
    expected.insert(expected.end(), skinned.begin(), skinned.end());
    expected.insert(expected.end(), corrections.begin(), corrections.end());
  }
  return expected;
}

std::vector<float> readFloats(const std::string& path) {
  const std::string bytes = slurp(path);
  std::vector<float> values(bytes.size() / sizeof(float));
  std::memcpy(values.data(), bytes.data(), values.size() * sizeof(float));
  return values;
}

TEST_CASE("runtime C API: a C program and Python ctypes on the shared library compute what the in-process API does, bit for bit") {
  const Bake& bake = sampleRuntime();
  TempDir dir;
  const FrameInputs in = writeFrameInputs(bake, dir, 1);
  const std::vector<float> expected = inProcessFrames(bake, in);
  // The C99 program, and the Python script loading the library the program links (as Blender's add-on does).
  const std::string library = rigbake::test::kRuntimeLibrary;
  for (const std::string& program : {std::string(rigbake::test::kRuntimeCCheck),
                                     "/usr/bin/python3 " + std::string(RIGBAKE_SOURCE_DIR) + "/tests/runtime_ctypes_check.py " + library}) {
    INFO(program);
    const std::string out_path = dir / "out.f32";
    std::remove(out_path.c_str());
    REQUIRE(std::system((program + " " + programArguments(bake, in, out_path)).c_str()) == 0);
    const std::vector<float> written = readFloats(out_path);
    REQUIRE(written.size() == expected.size());
    CHECK(std::memcmp(written.data(), expected.data(), written.size() * sizeof(float)) == 0);
  }
}

TEST_CASE("runtime C API: the WebAssembly build in node matches the native float C API within 1e-5 on every clip (sample, CesiumMan)") {
  const bool tools = test::external::requireTool(test::external::onPath("emcc") && test::external::onPath("node"),
                                                 "emcc (Debian package emscripten) and node");
  if (!tools) return;
  const std::string wasm_dir = std::string(RIGBAKE_SOURCE_DIR) + "/build/wasm";
  REQUIRE(std::system(("bash " + std::string(RIGBAKE_SOURCE_DIR) + "/scripts/build-wasm.sh " + wasm_dir + " >/dev/null").c_str()) == 0);
  for (const Bake* bake : {&sampleRuntime(), cesium()}) {
    if (!bake) continue;
    INFO(bake->path);
    TempDir dir;
    const FrameInputs in = writeFrameInputs(*bake, dir, 1000);
    const std::string out_path = dir / "out.f32";
    const std::string command = "node " + std::string(RIGBAKE_SOURCE_DIR) + "/tests/runtime_wasm_check.mjs " + wasm_dir + " " +
                                programArguments(*bake, in, out_path);
    REQUIRE(std::system(command.c_str()) == 0);
    const std::vector<float> expected = inProcessFrames(*bake, in);
    const std::vector<float> written = readFloats(out_path);
    REQUIRE(written.size() == expected.size());
    const size_t muscles = bake->file.rig.rig.muscles.size();
    const size_t per_frame = expected.size() / in.frames, muscle_floats = 16 * muscles;
    double worst_muscle = 0.0, worst_jiggle = 0.0;
    for (size_t k = 0; k < expected.size(); ++k) {
      const double difference = std::abs(double(written[k]) - double(expected[k]));
      double& worst = k % per_frame < muscle_floats ? worst_muscle : worst_jiggle;
      worst = std::max(worst, difference);
    }
    std::printf("WebAssembly vs native float C API, %s: %zu frames, %zu muscles (largest matrix difference %.3g), %zu jiggles (largest "
                "quaternion difference %.3g)\n",
                std::filesystem::path(bake->path).filename().c_str(), in.frames, muscles, worst_muscle,
                (per_frame - muscle_floats) / 4, worst_jiggle);
    CHECK(in.frames > 30);
    CHECK(per_frame > muscle_floats);  // jiggles were compared too
    CHECK(worst_muscle <= 1e-5);
    CHECK(worst_jiggle <= 1e-5);
  }
}

// The WebAssembly build in the browser, through the three.js plugin that plays it there, against this
// native library frame by frame (muscles and jiggles, a hit included): tests/view_test.cpp's agreement
// cases, in headless Chromium.

TEST_CASE("runtime C API: malformed extension text is refused with where and why, every truncation included") {
  const Bake& bake = sampleRuntime();
  const std::string& text = bake.extension_text;
  auto refusal = [&](const std::string& json, int node_count) {
    rigbake_rig* rig = rigbake_rig_create(json.data(), json.size(), node_count);
    const std::string message = rigbake_last_error();
    rigbake_rig_destroy(rig);
    return rig ? std::string() : message;
  };
  CHECK(refusal(text, bake.node_count).empty());
  // Truncations: every length in the first and last 2000 bytes (the root and the jiggles), a stride in between.
  int refused = 0;
  for (size_t n = 0; n < text.size(); n += (n < 2000 || n + 2000 > text.size()) ? 1 : 61) {
    const std::string message = refusal(text.substr(0, n), bake.node_count);
    REQUIRE_FALSE(message.empty());
    ++refused;
  }
  CHECK(refused > 4000);
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string copy = text;
    const size_t at = copy.find(from);
    REQUIRE(at != std::string::npos);
    return copy.replace(at, from.size(), to);
  };
  CHECK(refusal(edited("\"version\":1", "\"version\":1.0"), bake.node_count) == "RIGBAKE_muscle_rig /version: must be 1");
  CHECK(refusal(edited("\"compression\":", "\"compression\":-"), bake.node_count).find("compression / stretch") != std::string::npos);
  CHECK(refusal(edited("\"originNode\":", "\"originNode\":1e9,\"x\":"), bake.node_count) ==
        "RIGBAKE_muscle_rig /muscles/0/originNode: must be a node index");
  CHECK(refusal(edited("\"stiffness\":", "\"stiffness\":7,\"y\":"), bake.node_count) ==
        "RIGBAKE_muscle_rig /jiggles/0: stiffness must be in [0, 1]");
  CHECK(refusal(edited("\"muscles\":[", "\"muscles\":[1,"), bake.node_count) == "RIGBAKE_muscle_rig /muscles/0: must be an object");
  CHECK(refusal(edited("\"muscles\":", "\"muscles\":[],\"muscles\":"), bake.node_count).find("duplicate member name") != std::string::npos);
  CHECK(refusal(std::string(100, '[') + std::string(100, ']'), bake.node_count).find("nested deeper") != std::string::npos);
  CHECK(refusal(text, bake.node_count - 1).find("must be a node index below") != std::string::npos);
  CHECK(refusal(text + ",", bake.node_count).find("unexpected text after the JSON value") != std::string::npos);
}

}  // namespace runtime_c_api_test
}  // namespace rigbake
