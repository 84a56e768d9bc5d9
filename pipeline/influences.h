// The influence stage of the bake: per-vertex (joint, weight) lists pruned to the influence budget of
// the God of War Ragnarök talk ("Increase Bone Influences per Vertex": 4, 7 or 10 influences per vertex,
// weight precision 0.001), quantized to integers that sum exactly to their full scale, and laid out as
// glTF 2.0 JOINTS_n/WEIGHTS_n data a writer can copy into buffers unchanged.
//
// Canonical vertex order, which every function here produces and the packers rely on: slots sorted by
// weight descending, equal weights by joint index ascending, zero-weight slots last and carrying
// joint 0 (the glTF validator warns ACCESSOR_JOINTS_USED_ZERO_WEIGHT otherwise). A joint appears in
// at most one non-zero slot of a vertex (the validator's ACCESSOR_JOINTS_INDEX_DUPLICATE rule); joint 0
// may also fill zero-weight slots, which the validator allows.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "anatomy/character.h"

namespace rigbake {

// The talk's weight precision, 0.001: weights are integers in thousandths.
constexpr int kMilliScale = 1000;
// Full scales of glTF normalized UNSIGNED_BYTE and UNSIGNED_SHORT weights.
constexpr int kUnsignedByteScale = 255;
constexpr int kUnsignedShortScale = 65535;

// glTF 2.0 accessor.componentType codes.
constexpr int kGltfUnsignedByte = 5121;
constexpr int kGltfUnsignedShort = 5123;

// Full-precision influences. Slot k of vertex v is joints[v * slots_per_vertex + k] with weight
// weights[v * slots_per_vertex + k]; a slot with weight 0 means "no influence".
struct InfluenceSet {
  int slots_per_vertex = 0;
  std::vector<int> joints;
  std::vector<double> weights;
  int vertexCount() const;
};

// Influences as integers in units of 1/full_scale, in canonical order; every vertex sums to exactly
// full_scale. All supported full scales (1000, 255, 65535) fit 16 bits.
struct QuantizedInfluences {
  int slots_per_vertex = 0;
  int full_scale = kMilliScale;
  std::vector<int> joints;
  std::vector<std::uint16_t> weights;
  int vertexCount() const;
};

// What checkInfluences() finds; the bake turns each into a user error naming the mesh and vertex.
enum class InfluenceProblem { kJointOutOfRange, kWeightNotFinite, kWeightNegative, kWeightSumZero };

struct InfluenceIssue {
  InfluenceProblem problem = InfluenceProblem::kJointOutOfRange;
  int vertex = -1;
  int slot = -1;  // -1 for kWeightSumZero, which concerns the whole vertex
};

// A glTF accessor as a writer must declare it (accessor.type is "SCALAR", "VEC2" or "VEC4").
struct AccessorDescription {
  int component_type = 0;  // kGltfUnsignedByte or kGltfUnsignedShort
  std::string type;
  int count = 0;
  bool normalized = false;
};

// One vertex attribute: its semantic, its accessor and `count` elements tightly packed in little endian.
// Every element is a multiple of 4 bytes long, as glTF requires of vertex attributes, so the bytes can
// go into a buffer view without byteStride or padding.
struct VertexAttributeData {
  std::string semantic;
  AccessorDescription accessor;
  std::vector<std::uint8_t> bytes;
};

// How standardSkinAttributes() stores WEIGHTS_n: normalized UNSIGNED_BYTE (sum 255) or UNSIGNED_SHORT
// (sum 65535). UNSIGNED_SHORT keeps the 0.001 weights to within 1/65535; UNSIGNED_BYTE cannot hold
// 0.001 steps and moves each weight by up to about 1/255.
enum class WeightStorage { kUnsignedByte, kUnsignedShort };

// Which weights the bake writes as WEIGHTS_n (always UNSIGNED_SHORT). The packed buffers always hold
// the talk's 0.001 steps.
enum class GltfWeights {
  kMilli,    // "milli": the 0.001 weights the packed buffers hold (the talk's precision)
  kUnorm16,  // "unorm16": the pruned weights rounded to 1/65535, all UNSIGNED_SHORT can hold; for
             // engines that skin with WEIGHTS_n, the same bytes with about a fiftieth of the error
};

// "milli" or "unorm16", as --gltf-weights and build manifests spell them.
const char* gltfWeightsName(GltfWeights weights);
// False for any other name.
bool parseGltfWeights(const std::string& name, GltfWeights* weights);

// A skinned mesh part's slots as the loader read them (skeleton joint indices), with zero-weight slots
// set to joint 0. Weights are left as the file stored them, not renormalized.
InfluenceSet influencesFromMesh(const MeshPart& part);

// Each vertex's weights divided by their sum (which must not be 0: run checkInfluences() first).
// The per-vertex functions below take the threads to run on (pipeline/parallel.h); their results do not
// depend on it.
InfluenceSet normalizedInfluences(const InfluenceSet& set, int threads = 1);

// Every problem that would make pruning or quantizing meaningless: a joint outside [0, joint_count)
// in a non-zero slot, a NaN/infinite or negative weight, a vertex whose weights sum to 0.
// Run it first and report what it finds: pruneInfluences() and quantizeInfluences() throw Error
// INTERNAL on negative, non-finite or all-zero weights, standardSkinAttributes() on a joint out of range.
std::vector<InfluenceIssue> checkInfluences(const InfluenceSet& set, int joint_count);

// Keeps each vertex's `max_influences` largest weights (equal weights: lower joint index first, so the
// result does not depend on slot order), after merging slots that repeat a joint, and rescales them to
// sum to 1. The result has exactly max_influences slots per vertex, in canonical order.
InfluenceSet pruneInfluences(const InfluenceSet& set, int max_influences, int threads = 1);

// Integers in units of 1/full_scale summing exactly to full_scale, by largest-remainder rounding of
// w / sum(w) * full_scale: each weight is rounded down, then the units still missing go one each to
// the largest remainders (equal remainders: the slot that comes first in canonical order). Every result
// is therefore within one unit of the exact share. A weight that rounds to 0 becomes a zero slot.
// Same slot count as the input; weights need not sum to 1.
QuantizedInfluences quantizeInfluences(const InfluenceSet& set, int full_scale = kMilliScale, int threads = 1);

// The same largest-remainder rounding from one integer scale to another, done exactly in integers:
// w_new = floor(w * new_scale / old_scale) plus one unit for the largest remainders
// (w * new_scale) mod old_scale. Used to map the 0.001 weights onto 255 or 65535.
QuantizedInfluences requantizeInfluences(const QuantizedInfluences& quantized, int full_scale, int threads = 1);

// Weights as fractions w / full_scale, slots unchanged.
InfluenceSet dequantizeInfluences(const QuantizedInfluences& quantized, int threads = 1);

// glTF JOINTS_n and WEIGHTS_n for n = 0 .. ceil(slots / 4) - 1, in that order (JOINTS_0, WEIGHTS_0,
// JOINTS_1, ...). Weights are `quantized` requantized to 255 or 65535, so each vertex's integers across
// all WEIGHTS_n sum exactly to the full scale; slots past quantized.slots_per_vertex are zero with
// joint 0. Joints are UNSIGNED_BYTE when joint_count <= 256, else UNSIGNED_SHORT (joint_count must not
// exceed 65536). Joint indices are copied as given: the writer's skin.joints must list joints in
// that index order.
std::vector<VertexAttributeData> standardSkinAttributes(const QuantizedInfluences& quantized, int joint_count,
                                                        WeightStorage storage, int threads = 1);

}  // namespace rigbake
