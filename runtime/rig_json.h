// rigbake runtime: the RIGBAKE_muscle_rig extension's JSON text read into the runtime's rigs, with no
// dependency (no JSON library, no glTF library), for the C API (runtime/rigbake_runtime.h) and so for
// every engine, the Blender add-on and the WebAssembly build. formats/muscle_rig_extension.cpp reads the
// same object through tinygltf for rigbake's own tools; tests/runtime_c_api_test.cpp holds the two
// readers to the same rig, bit for bit, on real bakes.
//
// The JSON reader is strict RFC 8259 (no comments, no trailing commas, no NaN, no duplicate member
// names, strings with valid escapes only) and bounded: at most kRigJsonMaxDepth nested arrays and
// objects and kRigJsonMaxBytes of text, so that a hostile file cannot exhaust the stack. It throws
// nothing of its own; only std::bad_alloc can leave it (the C API catches it).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "runtime/jiggle.h"
#include "runtime/muscle_rig.h"

namespace rigbake::runtime {

constexpr int kRigJsonMaxDepth = 64;
constexpr std::size_t kRigJsonMaxBytes = std::size_t(1) << 28;  // 256 MiB: far beyond any rig

// The extension as the runtime evaluates it. Joints are glTF node indices: rig.joint_count and every
// jiggle's joint_count are the node count the caller gave, and a job is given one matrix per node.
struct RigFile {
  MuscleRig<double> rig;                 // prepared (prepareMuscleRig) when the read succeeded
  std::vector<std::string> muscle_names;
  std::vector<bool> muscle_corrective;   // kind "corrective"
  std::vector<int> skinned_nodes;        // per muscle
  std::vector<int> helper_nodes;         // per muscle base, tip, driver; -1 when the file has none
  std::vector<std::string> jiggle_names;
  std::vector<JiggleSpec<double>> jiggles;  // joint / parent / root are node indices (-1: model space)
};

// Reads the extension object (the value of the glTF root's extensions.RIGBAKE_muscle_rig, as text of
// `size` bytes; it need not be zero-terminated) for a file of `node_count` nodes. On success returns
// true with *out filled; otherwise false, *out unspecified, and *error one line: a JSON pointer into
// the object and what is wrong there, e.g. "/muscles/3/originNode: must be a node index below 57".
// Checks what formats/ checks (version 1, every member's type and size, node indices in range, the
// rig's lengths, limits and key order by rigProblem) except that a node is a joint of a skin, which
// the extension alone cannot tell; and each jiggle by jiggleSpecProblem. Unknown members are ignored,
// as formats/ ignores them.
bool readRigJson(const char* text, std::size_t size, int node_count, RigFile* out, std::string* error);

}  // namespace rigbake::runtime
