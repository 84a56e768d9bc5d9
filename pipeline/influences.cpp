// Influence pruning and quantization.
// Sources: the God of War Ragnarök talk (Tenghao Wang, "Joint-Based Skin Deformation in God of War
// Ragnarök"), section "Increase Bone Influences per Vertex": 4, 7 or 10 influences per vertex at a
// weight precision of 0.001. Largest-remainder (Hamilton) apportionment is the classic way to round
// shares to integers whose total is fixed, here the full scale, moving no share by a whole unit or more.
// glTF 2.0 specification 3.7.3.3 "Skinned Mesh Attributes": JOINTS_n as UNSIGNED_BYTE/UNSIGNED_SHORT,
// WEIGHTS_n as FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT with a linear sum of 1, unused joints 0.
#include "pipeline/influences.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "core/error.h"
#include "pipeline/parallel.h"

namespace rigbake {

int InfluenceSet::vertexCount() const {
  return slots_per_vertex > 0 ? static_cast<int>(joints.size()) / slots_per_vertex : 0;
}

int QuantizedInfluences::vertexCount() const {
  return slots_per_vertex > 0 ? static_cast<int>(joints.size()) / slots_per_vertex : 0;
}

namespace {

struct Slot {
  int joint;
  double weight;
};

struct IntegerSlot {
  int joint;
  std::int64_t units;
};

void requireShape(int slots_per_vertex, size_t joints, size_t weights, const char* what) {
  if (slots_per_vertex <= 0 || joints != weights || joints % static_cast<size_t>(slots_per_vertex) != 0)
    fail(errc::INTERNAL, "", std::string(what) + ": joints and weights do not hold whole vertices");
}

// A stable sort for the few slots of one vertex: insertion sort, which allocates nothing (std::stable_sort
// takes a buffer from the heap on every call). A stable sort's result is defined by the comparison
// alone, so it is std::stable_sort's.
template <typename Iterator, typename Less>
void stableSortSmall(Iterator begin, Iterator end, Less less) {
  for (Iterator i = begin; i != end; ++i) {
    auto value = std::move(*i);
    Iterator j = i;
    for (; j != begin && less(value, *(j - 1)); --j) *j = std::move(*(j - 1));
    *j = std::move(value);
  }
}

// Per-vertex working lists, kept from vertex to vertex so that the loops over every vertex do not
// allocate per vertex (the same steps on the same values: the same results).
struct VertexScratch {
  std::vector<Slot> slots, merged;
  std::vector<IntegerSlot> units;
  std::vector<double> remainders;
  std::vector<std::int64_t> integer_remainders;
  std::vector<bool> eligible;
  std::vector<size_t> rank;
};

// body(begin, end) over [0, vertices) in chunks on up to `threads` threads: each vertex's outputs are
// its own, so the result is the same at any count; an error is the lowest vertex's, as in one pass.
void forVertexChunks(int threads, int vertices, const std::function<void(int begin, int end)>& body) {
  constexpr size_t kVerticesPerChunk = 8192;
  parallelFor(threads, static_cast<size_t>(std::max(vertices, 0)), kVerticesPerChunk,
              [&](size_t, size_t begin, size_t end) { body(static_cast<int>(begin), static_cast<int>(end)); });
}

// The non-zero slots of one vertex, a joint named twice merged into one slot (both slots move the
// vertex by the same matrix, so their sum is the joint's influence), in canonical order, into
// scratch->merged.
const std::vector<Slot>& canonicalSlots(const InfluenceSet& set, int vertex, VertexScratch* scratch) {
  const int slots = set.slots_per_vertex;
  std::vector<Slot>& out = scratch->slots;
  out.clear();
  for (int k = 0; k < slots; ++k) {
    size_t index = static_cast<size_t>(vertex) * slots + k;
    double weight = set.weights[index];
    if (!std::isfinite(weight) || weight < 0.0)
      fail(errc::INTERNAL, "", "vertex " + std::to_string(vertex) + " has a negative or non-finite weight");
    if (weight == 0.0) continue;
    if (set.joints[index] < 0)
      fail(errc::INTERNAL, "", "vertex " + std::to_string(vertex) + " has a negative joint index");
    out.push_back({set.joints[index], weight});
  }
  std::sort(out.begin(), out.end(), [](const Slot& a, const Slot& b) { return a.joint < b.joint; });
  std::vector<Slot>& merged = scratch->merged;
  merged.clear();
  for (const Slot& slot : out) {
    if (!merged.empty() && merged.back().joint == slot.joint) {
      merged.back().weight += slot.weight;
    } else {
      merged.push_back(slot);
    }
  }
  stableSortSmall(merged.begin(), merged.end(), [](const Slot& a, const Slot& b) { return a.weight > b.weight; });
  return merged;
}

// Hands out the units still missing after rounding down, one each in order of decreasing remainder
// (equal remainders: earlier slot first). Only slots with a non-zero input weight take part, so a joint
// that had no influence never gains one.
template <typename Remainder>
void distributeMissingUnits(std::vector<IntegerSlot>& slots, const std::vector<Remainder>& remainders,
                            const std::vector<bool>& eligible, std::int64_t full_scale, std::vector<size_t>* rank_scratch) {
  std::int64_t total = 0;
  for (const IntegerSlot& slot : slots) total += slot.units;
  std::vector<size_t>& rank = *rank_scratch;
  rank.clear();
  for (size_t k = 0; k < slots.size(); ++k) {
    if (eligible[k]) rank.push_back(k);
  }
  if (rank.empty()) fail(errc::INTERNAL, "", "a vertex has no weight to quantize");
  stableSortSmall(rank.begin(), rank.end(), [&](size_t a, size_t b) { return remainders[a] > remainders[b]; });
  // Exact arithmetic leaves 0 <= missing < rank.size(). Floating-point shares can stray by an ulp, so
  // the loops also cope with a surplus and wrap around instead of trusting that bound.
  std::int64_t missing = full_scale - total;
  for (size_t i = 0; missing > 0; ++i, --missing) slots[rank[i % rank.size()]].units += 1;
  for (size_t i = 0; missing < 0; ++i) {
    IntegerSlot& slot = slots[rank[rank.size() - 1 - i % rank.size()]];
    if (slot.units > 0) {
      slot.units -= 1;
      ++missing;
    }
  }
}

// Writes one vertex in canonical order into `out` starting at `base` (sorting `slots`); zero slots get
// joint 0.
void writeCanonical(std::vector<IntegerSlot>& slots, int slots_per_vertex, size_t base, QuantizedInfluences* out) {
  stableSortSmall(slots.begin(), slots.end(), [](const IntegerSlot& a, const IntegerSlot& b) {
    if (a.units != b.units) return a.units > b.units;
    return a.joint < b.joint;
  });
  for (int k = 0; k < slots_per_vertex; ++k) {
    bool used = k < static_cast<int>(slots.size()) && slots[k].units > 0;
    out->joints[base + k] = used ? slots[k].joint : 0;
    out->weights[base + k] = used ? static_cast<std::uint16_t>(slots[k].units) : 0;
  }
}

void requireFullScale(int full_scale) {
  if (full_scale < 1 || full_scale > 65535)
    fail(errc::INTERNAL, "", "full scale " + std::to_string(full_scale) + " does not fit 16-bit weights");
}

}  // namespace

InfluenceSet normalizedInfluences(const InfluenceSet& set, int threads) {
  InfluenceSet out = set;
  forVertexChunks(threads, set.vertexCount(), [&](int begin, int end) {
    for (int v = begin; v < end; ++v) {
      double sum = 0.0;
      for (int k = 0; k < set.slots_per_vertex; ++k) sum += set.weights[v * set.slots_per_vertex + k];
      for (int k = 0; k < set.slots_per_vertex; ++k) out.weights[v * set.slots_per_vertex + k] /= sum;
    }
  });
  return out;
}

InfluenceSet influencesFromMesh(const MeshPart& part) {
  InfluenceSet set;
  set.slots_per_vertex = part.influences_per_vertex;
  set.joints = part.joints;
  set.weights = part.weights;
  for (size_t i = 0; i < set.weights.size(); ++i) {
    if (set.weights[i] == 0.0) set.joints[i] = 0;
  }
  return set;
}

std::vector<InfluenceIssue> checkInfluences(const InfluenceSet& set, int joint_count) {
  requireShape(set.slots_per_vertex, set.joints.size(), set.weights.size(), "checkInfluences");
  std::vector<InfluenceIssue> issues;
  const int slots = set.slots_per_vertex;
  for (int v = 0; v < set.vertexCount(); ++v) {
    double sum = 0.0;
    bool vertex_broken = false;
    for (int k = 0; k < slots; ++k) {
      size_t index = static_cast<size_t>(v) * slots + k;
      double weight = set.weights[index];
      if (!std::isfinite(weight)) {
        issues.push_back({InfluenceProblem::kWeightNotFinite, v, k});
        vertex_broken = true;
        continue;
      }
      if (weight < 0.0) {
        issues.push_back({InfluenceProblem::kWeightNegative, v, k});
        vertex_broken = true;
        continue;
      }
      if (weight > 0.0 && (set.joints[index] < 0 || set.joints[index] >= joint_count))
        issues.push_back({InfluenceProblem::kJointOutOfRange, v, k});
      sum += weight;
    }
    if (!vertex_broken && !(sum > 0.0)) issues.push_back({InfluenceProblem::kWeightSumZero, v, -1});
  }
  return issues;
}

InfluenceSet pruneInfluences(const InfluenceSet& set, int max_influences, int threads) {
  requireShape(set.slots_per_vertex, set.joints.size(), set.weights.size(), "pruneInfluences");
  if (max_influences < 1) fail(errc::INTERNAL, "", "pruneInfluences needs at least one influence per vertex");
  InfluenceSet out;
  out.slots_per_vertex = max_influences;
  const int vertices = set.vertexCount();
  out.joints.assign(static_cast<size_t>(vertices) * max_influences, 0);
  out.weights.assign(static_cast<size_t>(vertices) * max_influences, 0.0);
  forVertexChunks(threads, vertices, [&](int begin, int end) {
    VertexScratch scratch;
    for (int v = begin; v < end; ++v) {
      const std::vector<Slot>& slots = canonicalSlots(set, v, &scratch);
      if (slots.empty()) fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " has no weight to prune");
      const size_t count = std::min(slots.size(), static_cast<size_t>(max_influences));
      double kept = 0.0;
      for (size_t k = 0; k < count; ++k) kept += slots[k].weight;
      size_t base = static_cast<size_t>(v) * max_influences;
      for (size_t k = 0; k < count; ++k) {
        out.joints[base + k] = slots[k].joint;
        out.weights[base + k] = slots[k].weight / kept;
      }
    }
  });
  return out;
}

QuantizedInfluences quantizeInfluences(const InfluenceSet& set, int full_scale, int threads) {
  requireShape(set.slots_per_vertex, set.joints.size(), set.weights.size(), "quantizeInfluences");
  requireFullScale(full_scale);
  QuantizedInfluences out;
  out.slots_per_vertex = set.slots_per_vertex;
  out.full_scale = full_scale;
  out.joints.assign(set.joints.size(), 0);
  out.weights.assign(set.joints.size(), 0);
  forVertexChunks(threads, set.vertexCount(), [&](int begin, int end) {
    VertexScratch scratch;
    for (int v = begin; v < end; ++v) {
      const std::vector<Slot>& slots = canonicalSlots(set, v, &scratch);
      double sum = 0.0;
      for (const Slot& slot : slots) sum += slot.weight;
      if (!(sum > 0.0)) fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " has no weight to quantize");
      std::vector<IntegerSlot>& units = scratch.units;
      std::vector<double>& remainders = scratch.remainders;
      units.resize(slots.size());
      remainders.resize(slots.size());
      scratch.eligible.assign(slots.size(), true);
      for (size_t k = 0; k < slots.size(); ++k) {
        double share = slots[k].weight / sum * full_scale;
        double whole = std::floor(share);
        units[k] = {slots[k].joint, static_cast<std::int64_t>(whole)};
        remainders[k] = share - whole;
      }
      distributeMissingUnits(units, remainders, scratch.eligible, full_scale, &scratch.rank);
      writeCanonical(units, out.slots_per_vertex, static_cast<size_t>(v) * out.slots_per_vertex, &out);
    }
  });
  return out;
}

QuantizedInfluences requantizeInfluences(const QuantizedInfluences& quantized, int full_scale, int threads) {
  requireShape(quantized.slots_per_vertex, quantized.joints.size(), quantized.weights.size(),
               "requantizeInfluences");
  requireFullScale(full_scale);
  requireFullScale(quantized.full_scale);
  QuantizedInfluences out;
  out.slots_per_vertex = quantized.slots_per_vertex;
  out.full_scale = full_scale;
  out.joints.assign(quantized.joints.size(), 0);
  out.weights.assign(quantized.joints.size(), 0);
  const int slots = quantized.slots_per_vertex;
  const std::int64_t old_scale = quantized.full_scale;
  forVertexChunks(threads, quantized.vertexCount(), [&](int begin, int end) {
    VertexScratch scratch;
    std::vector<IntegerSlot>& units = scratch.units;
    std::vector<std::int64_t>& remainders = scratch.integer_remainders;
    std::vector<bool>& eligible = scratch.eligible;
    for (int v = begin; v < end; ++v) {
      size_t base = static_cast<size_t>(v) * slots;
      units.resize(static_cast<size_t>(slots));
      remainders.resize(static_cast<size_t>(slots));
      eligible.resize(static_cast<size_t>(slots));
      std::int64_t sum = 0;
      for (int k = 0; k < slots; ++k) {
        std::int64_t scaled = static_cast<std::int64_t>(quantized.weights[base + k]) * full_scale;
        units[k] = {quantized.joints[base + k], scaled / old_scale};
        remainders[k] = scaled % old_scale;
        eligible[k] = quantized.weights[base + k] > 0;
        sum += quantized.weights[base + k];
      }
      if (sum != old_scale)
        fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " weights sum to " + std::to_string(sum) + ", not " +
                                 std::to_string(old_scale));
      distributeMissingUnits(units, remainders, eligible, full_scale, &scratch.rank);
      writeCanonical(units, slots, base, &out);
    }
  });
  return out;
}

InfluenceSet dequantizeInfluences(const QuantizedInfluences& quantized, int threads) {
  requireShape(quantized.slots_per_vertex, quantized.joints.size(), quantized.weights.size(),
               "dequantizeInfluences");
  InfluenceSet out;
  out.slots_per_vertex = quantized.slots_per_vertex;
  out.joints = quantized.joints;
  out.weights.resize(quantized.weights.size());
  const size_t slots = static_cast<size_t>(quantized.slots_per_vertex);
  forVertexChunks(threads, quantized.vertexCount(), [&](int begin, int end) {
    for (size_t i = static_cast<size_t>(begin) * slots; i < static_cast<size_t>(end) * slots; ++i)
      out.weights[i] = static_cast<double>(quantized.weights[i]) / quantized.full_scale;
  });
  return out;
}

std::vector<VertexAttributeData> standardSkinAttributes(const QuantizedInfluences& quantized, int joint_count,
                                                        WeightStorage storage, int threads) {
  if (joint_count < 1 || joint_count > 65536)
    fail(errc::INTERNAL, "", "glTF joint indices are at most 16 bits; joint count " + std::to_string(joint_count));
  const bool byte_weights = storage == WeightStorage::kUnsignedByte;
  QuantizedInfluences stored =
      requantizeInfluences(quantized, byte_weights ? kUnsignedByteScale : kUnsignedShortScale, threads);
  const bool byte_joints = joint_count <= 256;
  const int slots = stored.slots_per_vertex;
  const int sets = (slots + 3) / 4;
  const int vertices = stored.vertexCount();
  const size_t joint_bytes = byte_joints ? 1 : 2, weight_bytes = byte_weights ? 1 : 2;
  // Little-endian, as glTF's buffers are.
  auto put = [](std::uint8_t* at, unsigned value, size_t bytes) {
    at[0] = static_cast<std::uint8_t>(value & 0xffu);
    if (bytes == 2) at[1] = static_cast<std::uint8_t>((value >> 8) & 0xffu);
  };
  std::vector<VertexAttributeData> attributes;
  for (int set = 0; set < sets; ++set) {
    VertexAttributeData joints;
    joints.semantic = "JOINTS_" + std::to_string(set);
    joints.accessor = {byte_joints ? kGltfUnsignedByte : kGltfUnsignedShort, "VEC4", vertices, false};
    VertexAttributeData weights;
    weights.semantic = "WEIGHTS_" + std::to_string(set);
    weights.accessor = {byte_weights ? kGltfUnsignedByte : kGltfUnsignedShort, "VEC4", vertices, true};
    joints.bytes.resize(static_cast<size_t>(vertices) * 4 * joint_bytes);
    weights.bytes.resize(static_cast<size_t>(vertices) * 4 * weight_bytes);
    // Each vertex writes its own eight fields: chunks of vertices on the bake's threads.
    forVertexChunks(threads, vertices, [&](int begin, int end) {
      for (int v = begin; v < end; ++v) {
        for (int c = 0; c < 4; ++c) {
          int k = set * 4 + c;
          size_t index = static_cast<size_t>(v) * slots + k;
          unsigned joint = k < slots ? static_cast<unsigned>(stored.joints[index]) : 0u;
          unsigned weight = k < slots ? stored.weights[index] : 0u;
          if (joint >= static_cast<unsigned>(joint_count))
            fail(errc::INTERNAL, "", "vertex " + std::to_string(v) + " names joint " + std::to_string(joint) +
                                     " of " + std::to_string(joint_count));
          const size_t field = 4 * static_cast<size_t>(v) + static_cast<size_t>(c);
          put(joints.bytes.data() + field * joint_bytes, joint, joint_bytes);
          put(weights.bytes.data() + field * weight_bytes, weight, weight_bytes);
        }
      }
    });
    attributes.push_back(std::move(joints));
    attributes.push_back(std::move(weights));
  }
  return attributes;
}

const char* gltfWeightsName(GltfWeights weights) {
  return weights == GltfWeights::kUnorm16 ? "unorm16" : "milli";
}

bool parseGltfWeights(const std::string& name, GltfWeights* weights) {
  for (GltfWeights candidate : {GltfWeights::kMilli, GltfWeights::kUnorm16}) {
    if (name == gltfWeightsName(candidate)) {
      *weights = candidate;
      return true;
    }
  }
  return false;
}

}  // namespace rigbake
