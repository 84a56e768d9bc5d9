// Batched single-precision skinning (pipeline/skinning_batch.h): the layout of a part's vertices in
// groups of four that share their joints, and of one frame's skin matrices with every entry in all
// four lanes. The per-group loop is in the header, so that callers consume each group while it is in
// registers.
#include "pipeline/skinning_batch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "core/error.h"
#include "pipeline/parallel.h"
#include "pipeline/skinning.h"

namespace rigbake {

int DualQuaternionPivots::rowOf(int joint) {
  if (joint >= static_cast<int>(row_of_joint.size())) row_of_joint.resize(static_cast<size_t>(joint) + 1, -1);
  if (row_of_joint[joint] < 0) {
    row_of_joint[joint] = static_cast<int>(joints.size());
    joints.push_back(joint);
  }
  return row_of_joint[joint];
}

namespace {

// One vertex's merged slots before grouping.
struct VertexSlots {
  std::uint32_t first = 0, count = 0;  // into the joint and weight lists
  std::uint8_t dual_quaternion_slots = 0;
  int pivot = -1;  // set 0's first joint in its slot order, when dual quaternions are wanted
  double set0_total = 0.0;
};

void splat(float value, Float4* out) {
  for (float& lane : out->v) lane = value;
}

// What mergeSlots() reuses from vertex to vertex.
struct MergeScratch {
  using Slot = std::pair<std::uint16_t, std::array<double, kSkinSets>>;
  std::vector<Slot> sorted;
  std::vector<Slot> merged;        // in the order the joints come
  std::vector<std::uint64_t> keys;  // joint << 32 | entry in `merged`
  std::vector<int> slot_of_joint;  // joint -> its entry in `merged`, -1 between vertices
};

// One vertex's joints over every set, ascending, with each set's weight summed in double (plus minus
// minus); set 0's total and first joint go into `vertex`. Ascending joints make each set's sum
// independent of the other sets: a joint only another set uses adds an exact zero to it.
void mergeSlots(const std::array<SetWeights, kSkinSets>& sets, size_t v, MergeScratch* scratch, VertexSlots* vertex) {
  auto& merged = scratch->merged;
  auto& slot_of_joint = scratch->slot_of_joint;
  merged.clear();
  vertex->set0_total = 0.0;
  vertex->pivot = -1;
  auto slotOf = [&](int joint) {
    if (joint < 0 || joint > std::numeric_limits<std::uint16_t>::max())
      fail(errc::INTERNAL, "", "skinning batch: joint " + std::to_string(joint) + " out of range");
    if (static_cast<size_t>(joint) >= slot_of_joint.size()) slot_of_joint.resize(static_cast<size_t>(joint) + 1, -1);
    int& slot = slot_of_joint[static_cast<size_t>(joint)];
    if (slot < 0) {
      slot = static_cast<int>(merged.size());
      merged.push_back({static_cast<std::uint16_t>(joint), {0.0, 0.0, 0.0, 0.0}});
    }
    return static_cast<size_t>(slot);
  };
  for (int set = 0; set < kSkinSets; ++set) {
    for (int sign = 0; sign < 2; ++sign) {
      const InfluenceSet* influences = sign == 0 ? sets[set].plus : sets[set].minus;
      if (influences == nullptr) continue;
      const size_t count = static_cast<size_t>(influences->slots_per_vertex);
      for (size_t k = 0; k < count; ++k) {
        const double weight = influences->weights[v * count + k];
        if (weight == 0.0) continue;
        const int joint = influences->joints[v * count + k];
        merged[slotOf(joint)].second[set] += sign == 0 ? weight : -weight;
        if (set == 0 && sign == 0) {
          vertex->set0_total += weight;
          if (vertex->pivot < 0) vertex->pivot = joint;
        }
      }
    }
  }
  for (const auto& slot : merged) slot_of_joint[slot.first] = -1;
  // Ordered by joint (each joint once) through 8-byte keys: sorting the 40-byte slots themselves moved
  // each of them several times.
  auto& keys = scratch->keys;
  keys.resize(merged.size());
  for (size_t i = 0; i < merged.size(); ++i) keys[i] = static_cast<std::uint64_t>(merged[i].first) << 32 | i;
  std::sort(keys.begin(), keys.end());
  auto& sorted = scratch->sorted;
  sorted.resize(merged.size());
  for (size_t i = 0; i < keys.size(); ++i) sorted[i] = merged[keys[i] & 0xffffffffu];
}

// Two vertices skinned alike: the same dual-quaternion slots and pivot, and the same joints.
bool sameSlots(const VertexSlots& a, const VertexSlots& b, const std::vector<std::uint16_t>& joints) {
  return a.count == b.count && a.dual_quaternion_slots == b.dual_quaternion_slots && a.pivot == b.pivot &&
         std::equal(joints.begin() + a.first, joints.begin() + a.first + a.count, joints.begin() + b.first);
}

// The batch's vertex order: by (dual-quaternion slots, pivot), then by joint list (lexicographically),
// equal ones in their order in `vertices`, as std::stable_sort would give it. Without the sort of every
// vertex (serial: 4-7 ms per 100k-vertex batch, 1.2 ms this way): each distinct list, a class, is found
// through a hash table and numbered as it first appears, the classes alone are sorted (673-802 of them
// in the 100k sample's batches, no two equal), and the vertices are counted into their class's place in
// vertex order.
std::vector<size_t> groupOrder(const std::vector<VertexSlots>& slots, const std::vector<std::uint16_t>& joints) {
  auto hashOf = [&](const VertexSlots& v) {
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the key and the joints
    auto mix = [&](std::uint64_t x) { h = (h ^ x) * 1099511628211ull; };
    mix(v.dual_quaternion_slots);
    mix(static_cast<std::uint32_t>(v.pivot));
    mix(v.count);
    for (std::uint32_t k = 0; k < v.count; ++k) mix(joints[v.first + k]);
    return h;
  };
  std::vector<size_t> representative;  // class -> its first vertex
  std::vector<std::uint64_t> class_hash;
  std::vector<int> table(1024, -1);  // open addressing, class ids; at most half full
  auto insert = [&](int c) {
    size_t at = class_hash[static_cast<size_t>(c)] & (table.size() - 1);
    while (table[at] >= 0) at = (at + 1) & (table.size() - 1);
    table[at] = c;
  };
  std::vector<int> class_of(slots.size());
  for (size_t i = 0; i < slots.size(); ++i) {
    const std::uint64_t h = hashOf(slots[i]);
    size_t at = h & (table.size() - 1);
    int found = -1;
    for (; table[at] >= 0; at = (at + 1) & (table.size() - 1)) {
      const int c = table[at];
      if (class_hash[static_cast<size_t>(c)] == h && sameSlots(slots[representative[static_cast<size_t>(c)]], slots[i], joints)) {
        found = c;
        break;
      }
    }
    if (found < 0) {
      found = static_cast<int>(representative.size());
      representative.push_back(i);
      class_hash.push_back(h);
      if (2 * representative.size() > table.size()) {
        table.assign(2 * table.size(), -1);
        for (int c = 0; c < found; ++c) insert(c);
      }
      insert(found);
    }
    class_of[i] = found;
  }
  std::vector<int> by_rank(representative.size());
  std::iota(by_rank.begin(), by_rank.end(), 0);
  std::sort(by_rank.begin(), by_rank.end(), [&](int ca, int cb) {
    const VertexSlots &a = slots[representative[static_cast<size_t>(ca)]], &b = slots[representative[static_cast<size_t>(cb)]];
    const auto key_a = std::make_pair(a.dual_quaternion_slots, a.pivot), key_b = std::make_pair(b.dual_quaternion_slots, b.pivot);
    if (key_a != key_b) return key_a < key_b;
    return std::lexicographical_compare(joints.begin() + a.first, joints.begin() + a.first + a.count, joints.begin() + b.first,
                                        joints.begin() + b.first + b.count);
  });
  // Each class's first place in the order, then the vertices in vertex order.
  std::vector<size_t> members(representative.size(), 0);
  for (int c : class_of) ++members[static_cast<size_t>(c)];
  std::vector<size_t> first_of_class(representative.size(), 0);
  size_t place = 0;
  for (int c : by_rank) {
    first_of_class[static_cast<size_t>(c)] = place;
    place += members[static_cast<size_t>(c)];
  }
  std::vector<size_t> order(slots.size());
  for (size_t i = 0; i < slots.size(); ++i) order[first_of_class[static_cast<size_t>(class_of[i])]++] = i;
  return order;
}

}  // namespace

SkinningBatch buildSkinningBatch(const std::vector<Eigen::Vector3d>& bind_positions, const std::vector<int>& vertices,
                                 const Eigen::Vector3d& centre, const std::array<SetWeights, kSkinSets>& sets,
                                 const std::vector<char>& dual_quaternions, int dual_quaternion_joints,
                                 DualQuaternionPivots* pivots, int threads) {
  // Each vertex's joints, ascending. Their weights in each set are summed in double, here and again
  // when the groups are laid out (the same sums in the same order, so the same bits): keeping every
  // vertex's double weights until then took 32 bytes per slot, the bake's peak at 100k vertices.
  // Chunks of vertices in parallel, each listing its joints apart; the lists are joined in chunk order.
  constexpr size_t kVerticesPerChunk = 4096;
  std::vector<VertexSlots> slots(vertices.size());
  std::vector<std::vector<std::uint16_t>> chunk_joints(parallelChunkCount(vertices.size(), kVerticesPerChunk));
  parallelFor(threads, vertices.size(), kVerticesPerChunk, [&](size_t chunk, size_t begin, size_t end) {
    MergeScratch scratch;
    std::vector<std::uint16_t>& joints = chunk_joints[chunk];
    for (size_t i = begin; i < end; ++i) {
      VertexSlots& vertex = slots[i];
      mergeSlots(sets, static_cast<size_t>(vertices[i]), &scratch, &vertex);
      vertex.first = static_cast<std::uint32_t>(joints.size());
      vertex.count = static_cast<std::uint32_t>(scratch.sorted.size());
      for (const auto& slot : scratch.sorted) joints.push_back(slot.first);
      if (dual_quaternions[i] && sets[0].plus != nullptr && vertex.pivot >= 0) {
        // Set 0's joints are the lowest ones below dual_quaternion_joints (the others' skeleton joints
        // blend in with weight 0).
        size_t count = 0;
        for (const auto& [joint, joint_weights] : scratch.sorted) {
          if (joint_weights[0] != 0.0 && joint >= dual_quaternion_joints)
            fail(errc::INTERNAL, "", "skinning batch: joint " + std::to_string(joint) + " has no dual quaternion");
          if (joint < dual_quaternion_joints) ++count;
        }
        vertex.dual_quaternion_slots = static_cast<std::uint8_t>(std::min<size_t>(count, 255));
      } else {
        vertex.pivot = -1;
      }
    }
  });
  std::vector<std::uint16_t> joints;
  {
    size_t total = 0;
    for (const std::vector<std::uint16_t>& list : chunk_joints) total += list.size();
    joints.reserve(total);
    for (size_t chunk = 0; chunk < chunk_joints.size(); ++chunk) {
      const std::uint32_t offset = static_cast<std::uint32_t>(joints.size());
      const size_t begin = chunk * kVerticesPerChunk, end = std::min(vertices.size(), begin + kVerticesPerChunk);
      for (size_t i = begin; i < end; ++i) slots[i].first += offset;
      joints.insert(joints.end(), chunk_joints[chunk].begin(), chunk_joints[chunk].end());
      std::vector<std::uint16_t>().swap(chunk_joints[chunk]);
    }
  }

  // Vertices with the same joints (and the same dual-quaternion pivot) form groups; within a group
  // they keep their order in `vertices`.
  auto sameJoints = [&](const VertexSlots& a, const VertexSlots& b) { return sameSlots(a, b, joints); };
  const std::vector<size_t> order = groupOrder(slots, joints);

  // The groups first, so that every array of the batch is allocated once at its final size: grown by
  // push_back they would hold up to twice their size for as long as the batch lives, and the batches of
  // every part and weight set live through the whole deformation pass.
  std::vector<size_t> group_end;
  size_t slot_total = 0;
  for (size_t begin = 0; begin < order.size();) {
    size_t end = begin + 1;
    while (end < order.size() && end - begin < kSkinLanes && sameJoints(slots[order[begin]], slots[order[end]])) ++end;
    group_end.push_back(end);
    slot_total += slots[order[begin]].count;
    begin = end;
  }
  const size_t groups = group_end.size();

  SkinningBatch batch;
  batch.centre = centre;
  batch.vertex.reserve(kSkinLanes * groups);
  batch.positions.reserve(3 * groups);
  batch.first_slot.reserve(groups + 1);
  batch.joints.reserve(slot_total);
  batch.dual_quaternion_slots.reserve(groups);
  batch.pivot_row.reserve(groups);
  batch.inverse_total.reserve(groups);
  batch.first_slot.push_back(0);
  size_t begin = 0;
  for (const size_t end : group_end) {
    const VertexSlots& shared = slots[order[begin]];
    Float4 x, y, z, inverse_total;
    splat(1.0f, &inverse_total);
    for (size_t lane = 0; lane < kSkinLanes; ++lane) {
      const bool used = begin + lane < end;
      const size_t i = used ? order[begin + lane] : 0;
      batch.vertex.push_back(used ? vertices[i] : -1);
      if (!used) continue;
      const Eigen::Vector3d p = bind_positions[static_cast<size_t>(vertices[i])] - centre;
      x.v[lane] = static_cast<float>(p.x());
      y.v[lane] = static_cast<float>(p.y());
      z.v[lane] = static_cast<float>(p.z());
      if (slots[i].set0_total != 0.0) inverse_total.v[lane] = static_cast<float>(1.0 / slots[i].set0_total);
    }
    batch.positions.push_back(x);
    batch.positions.push_back(y);
    batch.positions.push_back(z);
    batch.inverse_total.push_back(inverse_total);
    batch.dual_quaternion_slots.push_back(shared.dual_quaternion_slots);
    batch.pivot_row.push_back(shared.pivot >= 0 ? pivots->rowOf(shared.pivot) : 0);
    for (std::uint32_t k = 0; k < shared.count; ++k) batch.joints.push_back(joints[shared.first + k]);
    batch.first_slot.push_back(static_cast<std::uint32_t>(batch.joints.size()));
    begin = end;
  }
  // The groups' weights, slot by slot and set by set, four lanes at a time: each group's own range,
  // groups in parallel.
  batch.weights.resize(static_cast<size_t>(kSkinSets) * slot_total);
  constexpr size_t kGroupsPerChunk = 1024;
  parallelFor(threads, groups, kGroupsPerChunk, [&](size_t, size_t first_group, size_t last_group) {
    MergeScratch scratch;
    VertexSlots merged;
    for (size_t g = first_group; g < last_group; ++g) {
      const size_t group_begin = g == 0 ? 0 : group_end[g - 1];
      const size_t first_weight = static_cast<size_t>(kSkinSets) * batch.first_slot[g];
      const std::uint32_t count = batch.first_slot[g + 1] - batch.first_slot[g];
      for (size_t lane = 0; lane + group_begin < group_end[g]; ++lane) {
        mergeSlots(sets, static_cast<size_t>(vertices[order[group_begin + lane]]), &scratch, &merged);
        for (std::uint32_t k = 0; k < count; ++k)
          for (int set = 0; set < kSkinSets; ++set)
            batch.weights[first_weight + static_cast<size_t>(kSkinSets) * k + static_cast<size_t>(set)].v[lane] =
                static_cast<float>(scratch.sorted[k].second[static_cast<size_t>(set)]);
      }
    }
  });
  return batch;
}

void prepareFloatSkinFrame(const std::vector<Eigen::Affine3d>& frame, const Eigen::Vector3d& centre,
                           int dual_quaternion_joints, const DualQuaternionPivots& pivots, FloatSkinFrame* out) {
  const size_t joint_count = frame.size();
  out->centre = centre;
  for (int r = 0; r < 3; ++r) splat(static_cast<float>(centre[r]), &out->centre_lanes[static_cast<size_t>(r)]);
  out->linear.resize(12 * joint_count);
  double reach = 0.0;
  for (size_t j = 0; j < joint_count; ++j) {
    // M - I and the centred translation t + (M - I) c, in double, so that a joint that barely moves
    // gives small offsets with all their digits.
    const Eigen::Matrix3d linear = frame[j].linear() - Eigen::Matrix3d::Identity();
    const Eigen::Vector3d translation = frame[j].translation() + linear * centre;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        splat(static_cast<float>(c < 3 ? linear(r, c) : translation[r]), &out->linear[12 * j + static_cast<size_t>(4 * r + c)]);
    reach = std::max(reach, linear.norm() + translation.norm());
  }
  out->reach = reach;

  const int dq = std::min(dual_quaternion_joints, static_cast<int>(joint_count));
  out->dual_quaternion_joints = dq;
  out->dual_quaternion.resize(8 * static_cast<size_t>(dq));
  out->real_double.resize(static_cast<size_t>(dq));
  out->stretch_double.resize(static_cast<size_t>(dq));
  out->rigid = true;
  for (int j = 0; j < dq; ++j) {
    Eigen::Quaterniond real, dual;
    splitDualQuaternion(frame[j], &real, &dual, &out->stretch_double[j]);
    // A rigid joint's stretch is the identity up to the iteration's rounding (1e-16).
    if ((out->stretch_double[j] - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-12) out->rigid = false;
    for (int k = 0; k < 4; ++k) {
      out->real_double[j][k] = real.coeffs()[k];
      splat(static_cast<float>(real.coeffs()[k]), &out->dual_quaternion[8 * static_cast<size_t>(j) + static_cast<size_t>(k)]);
      splat(static_cast<float>(dual.coeffs()[k]), &out->dual_quaternion[8 * static_cast<size_t>(j) + 4 + static_cast<size_t>(k)]);
    }
  }
  out->stretch.resize(out->rigid ? 0 : 12 * static_cast<size_t>(dq));
  for (int j = 0; j < dq; ++j) {
    if (out->rigid) {
      // The centred map's dual part, 0.5 t' r with t' = t + (M - I) c, as splitDualQuaternion() forms it
      // (the rotation does not depend on the translation).
      const Eigen::Vector3d t = frame[j].translation() + (frame[j].linear() - Eigen::Matrix3d::Identity()) * centre;
      const std::array<double, 4>& r = out->real_double[j];
      Eigen::Quaterniond dual = Eigen::Quaterniond(0.0, t.x(), t.y(), t.z()) * Eigen::Quaterniond(r[3], r[0], r[1], r[2]);
      dual.coeffs() *= 0.5;
      for (int k = 0; k < 4; ++k)
        splat(static_cast<float>(dual.coeffs()[k]), &out->dual_quaternion[8 * static_cast<size_t>(j) + 4 + static_cast<size_t>(k)]);
      continue;
    }
    const Eigen::Matrix3d& stretch = out->stretch_double[j];
    const Eigen::Vector3d stretched_centre = stretch * centre;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        splat(static_cast<float>(c < 3 ? stretch(r, c) : stretched_centre[r]),
              &out->stretch[12 * static_cast<size_t>(j) + static_cast<size_t>(4 * r + c)]);
  }
  out->signs.assign(pivots.joints.size() * static_cast<size_t>(dq), 0u);
  for (size_t row = 0; row < pivots.joints.size(); ++row) {
    const int pivot = pivots.joints[row];
    if (pivot >= dq) continue;
    const std::array<double, 4>& q = out->real_double[pivot];
    for (int j = 0; j < dq; ++j) {
      // The same sum, in the same order, as Eigen's dot product of the two coefficient vectors.
      const std::array<double, 4>& r = out->real_double[j];
      const double dot = Eigen::Vector4d(r[0], r[1], r[2], r[3]).dot(Eigen::Vector4d(q[0], q[1], q[2], q[3]));
      if (dot < 0.0) out->signs[row * static_cast<size_t>(dq) + static_cast<size_t>(j)] = 0x80000000u;
    }
  }
}

}  // namespace rigbake
