// Times the engine-facing runtime (runtime/) on real characters, one thread, and prints one JSON line
// for bench/run to tabulate:
//
//   runtime_bench rig BAKED.glb
//     runtime::MuscleRigJob<float> and <double> on the rig a bake wrote into BAKED.glb (its
//     RIGBAKE_muscle_rig extension, read back as validate reads it), over every frame of every clip:
//     nanoseconds per evaluation of the whole rig, skinned matrices only and with the helpers.
//
//   runtime_bench capi BAKED.glb OUT_DIR
//     the C API (runtime/rigbake_runtime.h, float) on the same rig, built from the extension's JSON text:
//     nanoseconds per rigbake_rig_evaluate over every key time of every clip (windows of 64 frames,
//     the fastest of kPasses passes per window, the mean over every frame). Writes OUT_DIR/extension.json and OUT_DIR/poses.f32 (the
//     frames' node matrices) for tests/runtime_wasm_check.mjs to time the WebAssembly build on.
//
//   runtime_bench jiggle INPUT PRESETS_DIR MUSCLE_PRESET JIGGLE_PRESET
//     runtime::JiggleJob<float> and <double> on the jiggles a bake of INPUT resolves from
//     JIGGLE_PRESET (as `rigbake bake --jiggle`), driven as an engine drives them at 30 and 60 fps:
//     nanoseconds per frame, per jiggle per frame and per jiggle per internal 240 Hz step.
//
// The model-space joint matrices are computed beforehand (sampling the clips is the engine's work, not
// the runtime's). Each figure is a mean over every frame of each unit's fastest of kPasses runs (see
// rigNanoseconds and jiggleTiming), so that a neighbour on a shared machine inflates it less.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "app/bake_job.h"
#include "formats/gltf_document.h"
#include "formats/muscle_rig_extension.h"
#include "pipeline/bake.h"
#include "pipeline/jiggle.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"
#include "runtime/jiggle.h"
#include "runtime/muscle_rig.h"
#include "runtime/muscle_rig_convert.h"
#include "runtime/rigbake_runtime.h"

using namespace rigbake;

namespace {

// Each measurement is the fastest of kPasses, so that a neighbour on a shared machine (or the
// scheduler) inflates it less.
constexpr int kPasses = 9;
// The rig is evaluated over windows of consecutive frames whose joint matrices fit in a core's L2
// cache (an engine evaluates the rig right after computing the matrices, so they are in cache).
constexpr size_t kWindowBytes = 64 * 1024;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Keeps the compiler from treating outputs as unused (Run() lives in another translation unit, so it
// cannot drop the calls anyway; this also makes the figures print something that depends on them).
volatile double g_sink = 0.0;


// Nanoseconds per evaluation of the whole rig over `frames` (joint_count * 16 numbers per frame, one
// frame after the other).
template <typename Real>
double rigNanoseconds(const runtime::MuscleRig<double>& source, const std::vector<double>& frames, bool helpers) {
  const runtime::MuscleRig<Real> rig = runtime::convertMuscleRig<Real>(source);
  const size_t per_frame = 16 * static_cast<size_t>(rig.joint_count);
  const std::vector<Real> matrices(frames.begin(), frames.end());
  const size_t frame_count = matrices.size() / per_frame;
  const size_t window = std::max<size_t>(1, kWindowBytes / (per_frame * sizeof(Real)));
  std::vector<Real> skinned(16 * rig.muscles.size()), helper(helpers ? 48 * rig.muscles.size() : 0);
  runtime::MuscleRigJob<Real> job;
  job.rig = &rig;
  job.skinned_matrices = runtime::Span<Real>(skinned);
  job.helper_matrices = runtime::Span<Real>(helper);
  job.joint_matrices = runtime::Span<const Real>(matrices.data(), per_frame);
  if (frame_count == 0 || !job.Validate()) throw std::runtime_error("the muscle rig does not fit the file's joint matrices");
  auto evaluate = [&](size_t frame) {
    job.joint_matrices = runtime::Span<const Real>(matrices.data() + frame * per_frame, per_frame);
    job.Run();
  };
  // Per window the fastest of its passes (a pass over a window takes some 0.1 ms, so a pass that the
  // scheduler interrupted is rarely the fastest), summed over the windows: the mean over every frame.
  double seconds = 0.0;
  for (size_t begin = 0; begin < frame_count; begin += window) {
    const size_t end = std::min(frame_count, begin + window);
    for (size_t f = begin; f < end; ++f) evaluate(f);  // brings the window into cache, untimed
    double fastest = 0.0;
    for (int pass = 0; pass < kPasses; ++pass) {
      const Clock::time_point start = Clock::now();
      for (size_t f = begin; f < end; ++f) evaluate(f);
      const double elapsed = secondsSince(start);
      if (pass == 0 || elapsed < fastest) fastest = elapsed;
    }
    seconds += fastest;
    g_sink = g_sink + static_cast<double>(skinned[12]);
  }
  return 1e9 * seconds / static_cast<double>(frame_count);
}

int benchRig(const std::string& baked) {
  LoadedCharacter loaded = loadCharacter(baked);
  const Character& character = loaded.character;
  const LoadedMuscleRig file = readMuscleRigExtension(modelOf(*loaded.document), character);
  if (!file.present) throw std::runtime_error(baked + " has no " + std::string(kMuscleRigExtension) + " extension");
  if (!file.problems.empty()) throw std::runtime_error(baked + ": " + file.problems.front());
  // Every sampled frame of every clip, at the clip's own key times (what the bake samples).
  std::vector<double> frames;
  size_t frame_count = 0;
  for (const Clip& clip : character.clips) {
    for (double t : sampleTimes(clip, 0.0)) {
      const std::vector<double> m = jointMatrices(sampleClip(character.skeleton, clip, t));
      frames.insert(frames.end(), m.begin(), m.end());
      ++frame_count;
    }
  }
  if (frame_count == 0) {
    const std::vector<double> m = jointMatrices(restPose(character.skeleton));
    frames.insert(frames.end(), m.begin(), m.end());
    frame_count = 1;
  }
  // The same with denormals flushed to zero (SSE's FTZ and DAZ, which games usually run with): float
  // results that fall into the denormal range otherwise cost a microcode assist each.
  nlohmann::json float_ftz = nullptr;
#if defined(__SSE__)
  const unsigned int mxcsr = _mm_getcsr();
  _mm_setcsr(mxcsr | 0x8040u);  // FTZ (bit 15) and DAZ (bit 6)
  float_ftz = rigNanoseconds<float>(file.rig, frames, false);
  _mm_setcsr(mxcsr);
#endif
  const int keys = static_cast<int>(file.rig.keys.size());
  std::cout << nlohmann::json{{"input", baked},
                              {"muscles", file.rig.muscles.size()},
                              {"joints", file.rig.joint_count},
                              {"keys", keys},
                              {"clips", character.clips.size()},
                              {"frames", frame_count},
                              {"float_skinned_ns", rigNanoseconds<float>(file.rig, frames, false)},
                              {"float_helpers_ns", rigNanoseconds<float>(file.rig, frames, true)},
                              {"float_skinned_ftz_ns", float_ftz},
                              {"double_skinned_ns", rigNanoseconds<double>(file.rig, frames, false)},
                              {"double_helpers_ns", rigNanoseconds<double>(file.rig, frames, true)}}
                   .dump()
            << "\n";
  return 0;
}

// An engine's joint matrices for one frame: the skeleton's model-space matrices followed by the muscle
// rig's skinned joints (docs/runtime.md, "Jiggle"), computed beforehand.
std::vector<double> engineMatrices(const Skeleton& skeleton, const Clip& clip, double time,
                                   const runtime::MuscleRig<double>& muscle_rig) {
  std::vector<double> matrices = jointMatrices(sampleClip(skeleton, clip, time));
  std::vector<double> skinned(16 * muscle_rig.muscles.size());
  runtime::MuscleRigJob<double> job;
  job.rig = &muscle_rig;
  job.joint_matrices = runtime::Span<const double>(matrices);
  job.skinned_matrices = runtime::Span<double>(skinned);
  if (!job.Run()) throw std::runtime_error("the muscle rig does not fit the skeleton");
  matrices.insert(matrices.end(), skinned.begin(), skinned.end());
  return matrices;
}

struct JiggleTiming {
  double frame_ns = 0.0;  // one Run for every jiggle
  double steps_per_frame = 0.0;
  size_t frames = 0;  // timed frames
};

// What reading the clock twice costs, to take off each timed Run: the fastest of many tries.
double clockOverheadSeconds() {
  double fastest = 1.0;
  for (int k = 0; k < 1000; ++k) {
    const Clock::time_point start = Clock::now();
    fastest = std::min(fastest, secondsSince(start));
  }
  return fastest;
}

// One engine run per clip at `fps`: a reset on the clip's first frame (untimed), then one JiggleJob
// per frame with the frame's delta time, outputs the corrections an engine multiplies onto its local
// rotations. The state carries from frame to frame, so each frame is timed on its own: kPasses Runs
// from the same saved state (restored untimed), the fastest counted; the mean over every frame.
template <typename Real>
JiggleTiming jiggleTiming(const runtime::JiggleRig<Real>& rig, const std::vector<std::vector<double>>& clip_frames, double fps) {
  std::vector<std::vector<Real>> clips;
  for (const std::vector<double>& frames : clip_frames) clips.emplace_back(frames.begin(), frames.end());
  const size_t per_frame = 16 * static_cast<size_t>(rig.joint_count);
  const size_t n = rig.jiggles.size();
  std::vector<runtime::JiggleState> states(n), saved(n);
  std::vector<Real> corrections(4 * n);
  const Real dt = static_cast<Real>(1.0 / fps);
  const double overhead = clockOverheadSeconds();
  JiggleTiming timing;
  timing.steps_per_frame = std::round(1.0 / fps / runtime::kJiggleStepSeconds);
  double seconds = 0.0;
  for (const std::vector<Real>& clip : clips) {
    const size_t count = clip.size() / per_frame;
    if (count < 2) continue;
    std::fill(states.begin(), states.end(), runtime::JiggleState{});
    runtime::JiggleResetJob<Real> reset;
    reset.rig = &rig;
    reset.joint_matrices = runtime::Span<const Real>(clip.data(), per_frame);
    reset.velocity_matrices = runtime::Span<const Real>(clip.data() + per_frame, per_frame);
    reset.velocity_time = dt;
    reset.states = runtime::Span<runtime::JiggleState>(states);
    if (!reset.Run()) throw std::runtime_error("the jiggle rig does not fit the joint matrices");
    runtime::JiggleJob<Real> job;
    job.rig = &rig;
    job.delta_time = dt;
    job.states = runtime::Span<runtime::JiggleState>(states);
    job.corrections = runtime::Span<Real>(corrections);
    for (size_t f = 1; f < count; ++f) {
      job.joint_matrices = runtime::Span<const Real>(clip.data() + f * per_frame, per_frame);
      saved = states;
      double fastest = 0.0;
      for (int pass = 0; pass < kPasses; ++pass) {
        if (pass > 0) states = saved;  // the same vector: job.states still points at it
        const Clock::time_point start = Clock::now();
        job.Run();
        const double elapsed = secondsSince(start);
        if (pass == 0 || elapsed < fastest) fastest = elapsed;
      }
      seconds += std::max(0.0, fastest - overhead);
      ++timing.frames;
    }
    g_sink = g_sink + static_cast<double>(corrections[0]);
  }
  timing.frame_ns = timing.frames ? 1e9 * seconds / static_cast<double>(timing.frames) : 0.0;
  return timing;
}

nlohmann::json jiggleRow(const char* real, double fps, size_t jiggles, const JiggleTiming& t) {
  const double per_jiggle = jiggles ? t.frame_ns / static_cast<double>(jiggles) : 0.0;
  return {{"real", real},
          {"fps", fps},
          {"frames", t.frames},
          {"steps_per_frame", t.steps_per_frame},
          {"frame_ns", t.frame_ns},
          {"jiggle_frame_ns", per_jiggle},
          {"jiggle_step_ns", t.steps_per_frame > 0 ? per_jiggle / t.steps_per_frame : 0.0}};
}

int benchJiggle(const std::string& input, const std::string& presets, const std::string& muscle_preset,
                const std::string& jiggle_preset) {
  // The bake resolves the preset against the placed muscles and chooses each muscle's carrier joint;
  // its result holds both, as they go into the file's extension. No volume figures, no regions: only
  // the rig is timed here.
  app::BakeRequest request;
  request.character.path = input;
  request.output = "unwritten.glb";
  request.preset = muscle_preset;
  request.regions = "";
  request.jiggle = jiggle_preset;
  request.options.influences = 10;
  request.options.measure_quality = false;
  const app::BakeOutputs out = app::bakeJob(request, app::loadPresets(presets));
  const Character& character = out.character.loaded.character;
  const BakeResult& bake = out.bake;
  const runtime::MuscleRig<double> muscle_rig = buildMuscleRig(bake.muscles, character.skeleton);
  std::vector<int> carriers;
  for (const MusclePart& part : bake.muscles.parts) carriers.push_back(muscleCarrierJoint(part));
  const runtime::JiggleRig<float> rig_float = buildJiggleRig<float>(bake.jiggles, character.skeleton, carriers);
  const runtime::JiggleRig<double> rig_double = buildJiggleRig<double>(bake.jiggles, character.skeleton, carriers);
  nlohmann::json rows = nlohmann::json::array();
  for (double fps : {30.0, 60.0}) {
    std::vector<std::vector<double>> clip_frames;
    for (const Clip& clip : character.clips) {
      std::vector<double> frames;
      for (int k = 0; k / fps <= clip.duration + 1e-9; ++k) {
        const std::vector<double> m = engineMatrices(character.skeleton, clip, k / fps, muscle_rig);
        frames.insert(frames.end(), m.begin(), m.end());
      }
      clip_frames.push_back(std::move(frames));
    }
    rows.push_back(jiggleRow("float", fps, rig_float.jiggles.size(), jiggleTiming(rig_float, clip_frames, fps)));
    rows.push_back(jiggleRow("double", fps, rig_double.jiggles.size(), jiggleTiming(rig_double, clip_frames, fps)));
  }
  nlohmann::json names = nlohmann::json::array();
  for (const JiggleSetup& setup : bake.jiggles) names.push_back(setup.name);
  std::cout << nlohmann::json{{"input", input},
                              {"preset", jiggle_preset},
                              {"jiggles", names},
                              {"clips", character.clips.size()},
                              {"rows", rows}}
                   .dump()
            << "\n";
  return 0;
}

// The C API's float evaluation over every key time of every clip, as the WebAssembly build is timed on
// the same frames (tests/runtime_wasm_check.mjs with BENCH set).
int benchCapi(const std::string& baked, const std::string& out_dir) {
  const std::string bytes = [&] {
    std::ifstream in(baked, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  std::uint32_t json_length = 0;
  if (bytes.size() < 20) throw std::runtime_error(baked + " is not a GLB");
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const nlohmann::json gltf = nlohmann::json::parse(bytes.substr(20, json_length));
  const std::string extension = gltf.at("extensions").at(kMuscleRigExtension).dump();
  const int node_count = static_cast<int>(gltf.at("nodes").size());
  rigbake_rig* rig = rigbake_rig_create(extension.data(), extension.size(), node_count);
  if (!rig) throw std::runtime_error(baked + ": " + rigbake_last_error());
  LoadedCharacter loaded = loadCharacter(baked);
  const Skeleton& skeleton = loaded.character.skeleton;
  std::vector<float> frames;
  for (const Clip& clip : loaded.character.clips) {
    for (double t : sampleTimes(clip, 0.0)) {
      const Pose pose = sampleClip(skeleton, clip, t);
      std::vector<float> nodes(16 * static_cast<size_t>(node_count), 0.0f);
      for (int j = 0; j < skeleton.size(); ++j)
        for (int k = 0; k < 16; ++k) nodes[16 * static_cast<size_t>(skeleton.nodes[j]) + k] = static_cast<float>(pose.world[j].matrix().data()[k]);
      frames.insert(frames.end(), nodes.begin(), nodes.end());
    }
  }
  const size_t per_frame = 16 * static_cast<size_t>(node_count), frame_count = frames.size() / per_frame;
  if (frame_count == 0) throw std::runtime_error(baked + " has no clip to time the rig on");
  std::vector<float> skinned(16 * static_cast<size_t>(rigbake_rig_muscle_count(rig)));
  // As rigNanoseconds times the job, and tests/runtime_wasm_check.mjs the WebAssembly build: windows of
  // 64 consecutive frames, per window the fastest of kPasses passes, summed: the mean over every frame.
  // Half a second of warm-up first, as the WebAssembly build gets.
  constexpr size_t kWindowFrames = 64;
  auto run = [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) rigbake_rig_evaluate(rig, frames.data() + f * per_frame, skinned.data(), nullptr, nullptr);
  };
  for (const Clock::time_point warm = Clock::now(); secondsSince(warm) < 0.5;) run(0, frame_count);
  double seconds = 0.0;
  for (size_t begin = 0; begin < frame_count; begin += kWindowFrames) {
    const size_t end = std::min(frame_count, begin + kWindowFrames);
    double fastest = 0.0;
    for (int pass = 0; pass < kPasses; ++pass) {
      const Clock::time_point start = Clock::now();
      run(begin, end);
      const double elapsed = secondsSince(start);
      if (pass == 0 || elapsed < fastest) fastest = elapsed;
    }
    seconds += fastest;
  }
  const double fastest = seconds;
  g_sink = g_sink + static_cast<double>(skinned[12]);
  std::ofstream(out_dir + "/extension.json", std::ios::binary) << extension;
  std::ofstream(out_dir + "/poses.f32", std::ios::binary).write(reinterpret_cast<const char*>(frames.data()), frames.size() * sizeof(float));
  std::cout << nlohmann::json{{"input", baked},
                              {"muscles", rigbake_rig_muscle_count(rig)},
                              {"nodes", node_count},
                              {"frames", frame_count},
                              {"native_float_ns", 1e9 * fastest / static_cast<double>(frame_count)}}
                   .dump()
            << "\n";
  rigbake_rig_destroy(rig);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "rig" && argc == 3) return benchRig(argv[2]);
    if (mode == "capi" && argc == 4) return benchCapi(argv[2], argv[3]);
    if (mode == "jiggle" && argc == 6) return benchJiggle(argv[2], argv[3], argv[4], argv[5]);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 3;
  }
  std::cerr << "usage: runtime_bench rig BAKED.glb\n"
               "       runtime_bench capi BAKED.glb OUT_DIR\n"
               "       runtime_bench jiggle INPUT PRESETS_DIR MUSCLE_PRESET JIGGLE_PRESET\n";
  return 1;
}
