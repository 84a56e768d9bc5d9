// The C API (runtime/rigbake_runtime.h) over the runtime's jobs: it owns what a job is handed (the
// float rigs, the jiggles' states) and turns each call into one job's Validate() and Run(), so that the
// equations stay in runtime/muscle_rig.cpp and runtime/jiggle.cpp alone. Nothing here may throw across
// the C boundary: only rigbake_rig_create allocates, and it catches what allocation throws.
#include "runtime/rigbake_runtime.h"

#include <cmath>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "runtime/jiggle.h"
#include "runtime/muscle_rig.h"
#include "runtime/muscle_rig_convert.h"
#include "runtime/rig_json.h"

struct rigbake_rig {
  int node_count = 0;
  rigbake::runtime::MuscleRig<float> muscles;
  rigbake::runtime::JiggleRig<float> jiggles;
  std::vector<rigbake::runtime::JiggleState> states;
  std::vector<std::string> muscle_names, jiggle_names;
  std::vector<int> muscle_nodes;  // per muscle 7: skinned, origin, insertion, carrier, base, tip, driver
  std::vector<bool> corrective;
  std::vector<unsigned char> node_used;
};

namespace {

using namespace rigbake::runtime;

// Fixed storage: a message is set without allocating, so that any call may fail without throwing.
thread_local char last_error[512] = "";

int fail(int code, const char* message) {
  std::strncpy(last_error, message, sizeof(last_error) - 1);
  last_error[sizeof(last_error) - 1] = '\0';
  return code;
}

int succeed() {
  last_error[0] = '\0';
  return RIGBAKE_OK;
}

std::size_t matrixFloats(const rigbake_rig* rig) { return static_cast<std::size_t>(rig->node_count) * 16; }

JiggleSpec<float> narrowSpec(const JiggleSpec<double>& spec) {
  JiggleSpec<float> out;
  out.joint = spec.joint;
  out.parent = spec.parent;
  out.root = spec.root;
  for (int k = 0; k < 3; ++k) {
    out.aim_axis[k] = static_cast<float>(spec.aim_axis[k]);
    out.major_axis[k] = static_cast<float>(spec.major_axis[k]);
    out.root_up[k] = static_cast<float>(spec.root_up[k]);
  }
  out.length = static_cast<float>(spec.length);
  out.stiffness = static_cast<float>(spec.stiffness);
  out.damping = static_cast<float>(spec.damping);
  out.clamp_major_deg = static_cast<float>(spec.clamp_major_deg);
  out.clamp_minor_deg = static_cast<float>(spec.clamp_minor_deg);
  return out;
}

void buildRig(const RigFile& file, int node_count, rigbake_rig* rig) {
  rig->node_count = node_count;
  rig->muscles = convertMuscleRig<float>(file.rig);
  rig->jiggles.joint_count = node_count;
  for (const JiggleSpec<double>& spec : file.jiggles) rig->jiggles.jiggles.push_back(buildJiggleSettings(narrowSpec(spec)));
  rig->states.assign(file.jiggles.size(), JiggleState());
  rig->muscle_names = file.muscle_names;
  rig->jiggle_names = file.jiggle_names;
  rig->corrective = file.muscle_corrective;
  rig->node_used.assign(static_cast<std::size_t>(node_count), 0);
  for (std::size_t m = 0; m < file.rig.muscles.size(); ++m) {
    const RigMuscle<double>& muscle = file.rig.muscles[m];
    const int nodes[7] = {file.skinned_nodes[m], muscle.origin_joint, muscle.insertion_joint, muscle.carrier_joint,
                          file.helper_nodes[3 * m], file.helper_nodes[3 * m + 1], file.helper_nodes[3 * m + 2]};
    rig->muscle_nodes.insert(rig->muscle_nodes.end(), nodes, nodes + 7);
    for (int k = 1; k <= 3; ++k) rig->node_used[nodes[k]] = 1;
  }
  for (const JiggleSpec<double>& spec : file.jiggles) {
    for (int node : {spec.joint, spec.parent, spec.root}) {
      if (node >= 0) rig->node_used[node] = 1;
    }
  }
}

}  // namespace

extern "C" {

unsigned int rigbake_runtime_version(void) { return RIGBAKE_RUNTIME_VERSION; }

const char* rigbake_last_error(void) { return last_error; }

rigbake_rig* rigbake_rig_create(const char* json, size_t json_size, int node_count) {
  try {
    RigFile file;
    std::string error;
    if (!readRigJson(json, json_size, node_count, &file, &error)) {
      fail(RIGBAKE_ERROR_INVALID, ("RIGBAKE_muscle_rig " + error).c_str());
      return nullptr;
    }
    rigbake_rig* rig = new rigbake_rig();
    buildRig(file, node_count, rig);
    succeed();
    return rig;
  } catch (const std::bad_alloc&) {
    fail(RIGBAKE_ERROR_MEMORY, "out of memory building the rig");
  } catch (...) {
    fail(RIGBAKE_ERROR_INVALID, "the rig could not be built");
  }
  return nullptr;
}

void rigbake_rig_destroy(rigbake_rig* rig) { delete rig; }

int rigbake_rig_node_count(const rigbake_rig* rig) { return rig ? rig->node_count : -1; }
int rigbake_rig_muscle_count(const rigbake_rig* rig) { return rig ? static_cast<int>(rig->muscles.muscles.size()) : -1; }
int rigbake_rig_jiggle_count(const rigbake_rig* rig) { return rig ? static_cast<int>(rig->jiggles.jiggles.size()) : -1; }

const char* rigbake_rig_muscle_name(const rigbake_rig* rig, int muscle) {
  if (!rig || muscle < 0 || muscle >= rigbake_rig_muscle_count(rig)) return nullptr;
  return rig->muscle_names[muscle].c_str();
}

int rigbake_rig_muscle_is_corrective(const rigbake_rig* rig, int muscle) {
  if (!rig || muscle < 0 || muscle >= rigbake_rig_muscle_count(rig)) return -1;
  return rig->corrective[muscle] ? 1 : 0;
}

int rigbake_rig_muscle_node(const rigbake_rig* rig, int muscle, int which) {
  if (!rig || muscle < 0 || muscle >= rigbake_rig_muscle_count(rig) || which < 0 || which > 6) return -1;
  return rig->muscle_nodes[7 * static_cast<std::size_t>(muscle) + which];
}

const char* rigbake_rig_jiggle_name(const rigbake_rig* rig, int jiggle) {
  if (!rig || jiggle < 0 || jiggle >= rigbake_rig_jiggle_count(rig)) return nullptr;
  return rig->jiggle_names[jiggle].c_str();
}

int rigbake_rig_jiggle_node(const rigbake_rig* rig, int jiggle, int which) {
  if (!rig || jiggle < 0 || jiggle >= rigbake_rig_jiggle_count(rig) || which < 0 || which > 2) return -1;
  const JiggleSettings<float>& s = rig->jiggles.jiggles[jiggle];
  return which == 0 ? s.joint : which == 1 ? s.parent : s.root;
}

int rigbake_rig_node_used(const rigbake_rig* rig, int node) {
  if (!rig || node < 0 || node >= rig->node_count) return -1;
  return rig->node_used[node];
}

int rigbake_rig_evaluate(const rigbake_rig* rig, const float* node_matrices, float* skinned_matrices, float* helper_matrices,
                         float* drivers) {
  if (!rig || !node_matrices || !skinned_matrices) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_rig_evaluate: null rig or array");
  const std::size_t count = rig->muscles.muscles.size();
  MuscleRigJob<float> job;
  job.rig = &rig->muscles;
  job.joint_matrices = Span<const float>(node_matrices, matrixFloats(rig));
  job.skinned_matrices = Span<float>(skinned_matrices, count * 16);
  if (helper_matrices) job.helper_matrices = Span<float>(helper_matrices, count * 48);
  // MuscleDrivers<float> is three floats, ratio, clamped ratio, twist, as the header promises.
  static_assert(sizeof(MuscleDrivers<float>) == 3 * sizeof(float), "drivers are three floats");
  if (drivers) job.drivers = Span<MuscleDrivers<float>>(reinterpret_cast<MuscleDrivers<float>*>(drivers), count);
  if (!job.Run()) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_rig_evaluate: the arrays do not fit the rig");
  return succeed();
}

int rigbake_rig_store_skinned(const rigbake_rig* rig, const float* skinned_matrices, float* node_matrices) {
  if (!rig || !skinned_matrices || !node_matrices) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_rig_store_skinned: null rig or array");
  const std::size_t count = rig->muscles.muscles.size();
  for (std::size_t m = 0; m < count; ++m)
    std::memcpy(node_matrices + 16 * static_cast<std::size_t>(rig->muscle_nodes[7 * m]), skinned_matrices + 16 * m, 16 * sizeof(float));
  return succeed();
}

int rigbake_jiggle_reset(rigbake_rig* rig, const float* node_matrices, const float* velocity_matrices, float velocity_time) {
  if (!rig || !node_matrices) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_reset: null rig or array");
  if (velocity_matrices && !(std::isfinite(velocity_time) && velocity_time != 0.0f))
    return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_reset: velocity_time must be finite and non-zero");
  JiggleResetJob<float> job;
  job.rig = &rig->jiggles;
  job.joint_matrices = Span<const float>(node_matrices, matrixFloats(rig));
  if (velocity_matrices) {
    job.velocity_matrices = Span<const float>(velocity_matrices, matrixFloats(rig));
    job.velocity_time = velocity_time;
  }
  job.states = Span<JiggleState>(rig->states);
  if (!job.Run()) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_reset: the arrays do not fit the rig");
  return succeed();
}

int rigbake_jiggle_step(rigbake_rig* rig, const float* node_matrices, float delta_time, int max_steps, float* corrections,
                        float* local_rotations, float* model_matrices, float* points) {
  if (!rig || !node_matrices) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_step: null rig or array");
  if (!(std::isfinite(delta_time) && delta_time >= 0.0f) || max_steps < 0)
    return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_step: delta_time must be finite and >= 0, max_steps >= 0");
  const std::size_t count = rig->jiggles.jiggles.size();
  JiggleJob<float> job;
  job.rig = &rig->jiggles;
  job.joint_matrices = Span<const float>(node_matrices, matrixFloats(rig));
  job.delta_time = delta_time;
  job.max_steps = max_steps;
  job.states = Span<JiggleState>(rig->states);
  if (corrections) job.corrections = Span<float>(corrections, count * 4);
  if (local_rotations) job.local_rotations = Span<float>(local_rotations, count * 4);
  if (model_matrices) job.model_matrices = Span<float>(model_matrices, count * 16);
  if (points) job.points = Span<float>(points, count * 3);
  if (!job.Run()) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_step: the arrays do not fit the rig");
  return succeed();
}

int rigbake_jiggle_impulse(rigbake_rig* rig, int jiggle, const float* direction, float magnitude) {
  if (!rig || !direction) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_impulse: null rig or direction");
  const int count = rigbake_rig_jiggle_count(rig);
  if (jiggle < -1 || jiggle >= count) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_impulse: no such jiggle");
  if (!std::isfinite(magnitude)) return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_impulse: magnitude must be finite");
  const Span<JiggleState> states(rig->states);
  if (jiggle >= 0) {
    if (!applyJiggleImpulse<float>(states, static_cast<std::size_t>(jiggle), direction, magnitude))
      return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_impulse: the direction must be non-zero and finite");
    return succeed();
  }
  for (int j = 0; j < count; ++j) {
    if (!applyJiggleImpulse<float>(states, static_cast<std::size_t>(j), direction, magnitude))
      return fail(RIGBAKE_ERROR_ARGUMENT, "rigbake_jiggle_impulse: the direction must be non-zero and finite");
  }
  return succeed();
}

}  // extern "C"
