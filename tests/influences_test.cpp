#include "pipeline/influences.h"
#include "pipeline/pack_influences.h"

#include <cmath>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.h"
#include "influence_fixtures.h"
#include "pipeline/deformation_error.h"

using namespace rigbake;

namespace {

// Counts broken vertices and keeps the first one's story, so a property over 30,000 vertices costs one
// assertion per mesh part instead of one per vertex.
struct Violations {
  int count = 0;
  std::string first;
  void note(bool ok, const std::function<std::string()>& what) {
    if (ok) return;
    if (count++ == 0) first = what();
  }
};

std::map<int, double> mergedWeights(const InfluenceSet& set, int v) {
  std::map<int, double> merged;
  for (int k = 0; k < set.slots_per_vertex; ++k) {
    size_t index = static_cast<size_t>(v) * set.slots_per_vertex + k;
    if (set.weights[index] != 0.0) merged[set.joints[index]] += set.weights[index];
  }
  return merged;
}

// The canonical-order contract of pipeline/influences.h, for weights of any numeric type.
template <typename Weight>
std::string canonicalProblem(const std::vector<int>& joints, const std::vector<Weight>& weights, int slots, int v,
                             int joint_count) {
  std::set<int> seen;
  for (int k = 0; k < slots; ++k) {
    size_t index = static_cast<size_t>(v) * slots + k;
    int joint = joints[index];
    if (joint < 0 || joint >= joint_count) return "joint out of range in slot " + std::to_string(k);
    if (weights[index] == 0) {
      if (joint != 0) return "zero-weight slot " + std::to_string(k) + " names joint " + std::to_string(joint);
      continue;
    }
    if (!seen.insert(joint).second) return "joint " + std::to_string(joint) + " appears twice";
    if (k > 0) {
      Weight previous = weights[index - 1];
      if (previous < weights[index]) return "slot " + std::to_string(k) + " outweighs the slot before it";
      if (previous == weights[index] && joints[index - 1] > joint) return "equal weights not in joint order";
    }
  }
  return "";
}

std::string vertexName(const std::string& part, int v) { return part + " vertex " + std::to_string(v); }

}  // namespace

TEST_CASE("checkInfluences accepts every shared asset and names each kind of problem", "[shared:asset-influences]") {
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    for (const test::PartInfluences& part : asset.parts) {
      INFO(part.name);
      CHECK(checkInfluences(part.real, asset.skeleton.size()).empty());
      CHECK(checkInfluences(part.wide, asset.skeleton.size()).empty());
    }
  }
  InfluenceSet broken;
  broken.slots_per_vertex = 2;
  broken.joints = {0, 5, 1, 2, 1, 2, 3, 1};
  broken.weights = {0.5, 0.5, std::nan(""), 1.0, -0.25, 1.25, 0.0, 0.0};
  std::vector<InfluenceIssue> issues = checkInfluences(broken, 4);
  REQUIRE(issues.size() == 4);
  CHECK((issues[0].problem == InfluenceProblem::kJointOutOfRange && issues[0].vertex == 0 && issues[0].slot == 1));
  CHECK((issues[1].problem == InfluenceProblem::kWeightNotFinite && issues[1].vertex == 1 && issues[1].slot == 0));
  CHECK((issues[2].problem == InfluenceProblem::kWeightNegative && issues[2].vertex == 2 && issues[2].slot == 0));
  CHECK((issues[3].problem == InfluenceProblem::kWeightSumZero && issues[3].vertex == 3 && issues[3].slot == -1));
  // The stages refuse what the check reports instead of producing NaN weights.
  CHECK_THROWS_AS(pruneInfluences(broken, 4), Error);
  CHECK_THROWS_AS(quantizeInfluences(broken), Error);
}

TEST_CASE("influencesFromMesh keeps the file's slots and parks zero weights on joint 0") {
  MeshPart mesh;
  mesh.skinned = true;
  mesh.influences_per_vertex = 4;
  mesh.joints = {3, 7, 9, 2};
  mesh.weights = {0.75, 0.25, 0.0, 0.0};
  InfluenceSet set = influencesFromMesh(mesh);
  CHECK(set.slots_per_vertex == 4);
  CHECK(set.vertexCount() == 1);
  CHECK(set.joints == std::vector<int>{3, 7, 0, 0});
  CHECK(set.weights == std::vector<double>{0.75, 0.25, 0.0, 0.0});
}

TEST_CASE("pruning keeps the largest weights, breaks ties by joint index and renormalizes", "[shared:asset-influences]") {
  SECTION("a hand-made vertex with four equal weights and a repeated joint") {
    InfluenceSet set;
    set.slots_per_vertex = 4;
    set.joints = {5, 2, 9, 1, 3, 7, 3, 0};
    set.weights = {0.25, 0.25, 0.25, 0.25, 0.2, 0.5, 0.3, 0.0};
    InfluenceSet pruned = pruneInfluences(set, 3);
    REQUIRE(pruned.slots_per_vertex == 3);
    CHECK(pruned.joints == std::vector<int>{1, 2, 5, 3, 7, 0});
    CHECK(pruned.weights[0] == Approx(1.0 / 3.0));
    CHECK(pruned.weights[2] == Approx(1.0 / 3.0));
    // Joint 3's two slots merge to 0.5, tying joint 7; the lower index wins a single-influence budget.
    InfluenceSet single = pruneInfluences(set, 1);
    CHECK(single.joints == std::vector<int>{1, 3});
    CHECK(single.weights == std::vector<double>{1.0, 1.0});
    // A larger budget pads with zero slots on joint 0.
    InfluenceSet padded = pruneInfluences(set, 10);
    CHECK(padded.joints[4] == 0);
    CHECK(padded.weights[4] == 0.0);
    CHECK(padded.joints[10] == 3);
    CHECK(padded.weights[10] == Approx(0.5));
    CHECK(padded.weights[11] == Approx(0.5));
    CHECK(padded.weights[12] == 0.0);
  }

  SECTION("every vertex of every shared asset, as stored and widened, at 4, 7 and 10") {
    for (const test::AssetInfluences& asset : test::assetInfluences()) {
      // Vertices the widened data really prunes, per budget: the property must not hold vacuously.
      std::map<int, int> pruned_vertices;
      for (const test::PartInfluences& part : asset.parts) {
        for (const InfluenceSet* input : {&part.real, &part.wide}) {
          for (int budget : kPackedInfluenceCounts) {
            INFO(part.name << (input == &part.wide ? " (widened)" : "") << " N=" << budget);
            InfluenceSet pruned = pruneInfluences(*input, budget);
            REQUIRE(pruned.slots_per_vertex == budget);
            REQUIRE(pruned.vertexCount() == input->vertexCount());
            Violations violations;
            for (int v = 0; v < input->vertexCount(); ++v) {
              std::map<int, double> merged = mergedWeights(*input, v);
              // Independent of the implementation: a joint survives when fewer than `budget` joints
              // beat it (heavier, or as heavy with a lower index).
              std::map<int, double> expected;
              double kept_sum = 0.0;
              for (const auto& [joint, weight] : merged) {
                int beaten_by = 0;
                for (const auto& [other, other_weight] : merged) {
                  if (other_weight > weight || (other_weight == weight && other < joint)) ++beaten_by;
                }
                if (beaten_by < budget) {
                  expected[joint] = weight;
                  kept_sum += weight;
                }
              }
              if (merged.size() > static_cast<size_t>(budget)) ++pruned_vertices[budget];
              std::map<int, double> actual = mergedWeights(pruned, v);
              violations.note(actual.size() == expected.size(),
                              [&] { return vertexName(part.name, v) + ": wrong number of kept joints"; });
              double sum = 0.0;
              for (const auto& [joint, weight] : actual) {
                sum += weight;
                auto it = expected.find(joint);
                violations.note(it != expected.end() && std::abs(weight - it->second / kept_sum) < 1e-12, [&] {
                  return vertexName(part.name, v) + ": joint " + std::to_string(joint) + " kept wrongly";
                });
              }
              violations.note(std::abs(sum - 1.0) < 1e-12,
                              [&] { return vertexName(part.name, v) + ": weights do not sum to 1"; });
              std::string problem =
                  canonicalProblem(pruned.joints, pruned.weights, budget, v, asset.skeleton.size());
              violations.note(problem.empty(), [&] { return vertexName(part.name, v) + ": " + problem; });
            }
            INFO(violations.first);
            CHECK(violations.count == 0);
          }
        }
      }
      INFO(asset.asset);
      for (int budget : kPackedInfluenceCounts) CHECK(pruned_vertices[budget] > 0);
    }
  }
}

TEST_CASE("0.001 quantization sums to exactly 1000 by largest remainder on every vertex", "[shared:asset-influences]") {
  SECTION("hand-made vertices") {
    InfluenceSet set;
    set.slots_per_vertex = 4;
    // Equal thirds: the spare unit goes to the lowest joint index.
    // 0.9996 / 0.0004: the small weight rounds to nothing and its slot falls back to joint 0.
    // 2 : 1 : 1 need not be normalized first.
    set.joints = {8, 3, 5, 0, 4, 6, 0, 0, 9, 2, 7, 0};
    set.weights = {1.0 / 3, 1.0 / 3, 1.0 / 3, 0.0, 0.9996, 0.0004, 0.0, 0.0, 2.0, 1.0, 1.0, 0.0};
    QuantizedInfluences q = quantizeInfluences(set);
    CHECK(q.full_scale == 1000);
    CHECK(q.joints == std::vector<int>{3, 5, 8, 0, 4, 0, 0, 0, 9, 2, 7, 0});
    CHECK(q.weights == std::vector<std::uint16_t>{334, 333, 333, 0, 1000, 0, 0, 0, 500, 250, 250, 0});
    InfluenceSet back = dequantizeInfluences(q);
    CHECK(back.weights[0] == 0.334);
  }

  SECTION("every vertex of every shared asset, as stored and widened, at 4, 7 and 10") {
    for (const test::AssetInfluences& asset : test::assetInfluences()) {
      // Vertices the widened data really prunes, per budget: the property must not hold vacuously.
      std::map<int, int> pruned_vertices;
      for (const test::PartInfluences& part : asset.parts) {
        for (const InfluenceSet* input : {&part.real, &part.wide}) {
          for (int budget : kPackedInfluenceCounts) {
            INFO(part.name << (input == &part.wide ? " (widened)" : "") << " N=" << budget);
            InfluenceSet pruned = pruneInfluences(*input, budget);
            QuantizedInfluences q = quantizeInfluences(pruned);
            REQUIRE(q.slots_per_vertex == budget);
            const InfluenceSet dequantized = dequantizeInfluences(q);
            Violations violations;
            for (int v = 0; v < q.vertexCount(); ++v) {
              int sum = 0;
              for (int k = 0; k < budget; ++k) sum += q.weights[static_cast<size_t>(v) * budget + k];
              violations.note(sum == 1000, [&] { return vertexName(part.name, v) + ": sum " + std::to_string(sum); });
              std::string problem = canonicalProblem(q.joints, q.weights, budget, v, asset.skeleton.size());
              violations.note(problem.empty(), [&] { return vertexName(part.name, v) + ": " + problem; });
              // Largest remainder: every share is rounded down or up, never further, and a rounded-up
              // share never has a smaller remainder than a rounded-down one.
              std::map<int, double> exact = mergedWeights(pruned, v);
              std::map<int, double> got = mergedWeights(dequantized, v);
              double smallest_up = 2.0, largest_down = -1.0;
              for (const auto& [joint, weight] : exact) {
                double share = weight * 1000.0;
                double units = got.count(joint) ? std::round(got[joint] * 1000.0) : 0.0;
                double floor_share = std::floor(share + 1e-9);
                double remainder = share - std::floor(share);
                violations.note(units == floor_share || units == floor_share + 1.0 ||
                                    std::abs(units - share) < 1e-9,
                                [&] { return vertexName(part.name, v) + ": share moved by a unit or more"; });
                if (units > share + 1e-9) smallest_up = std::min(smallest_up, remainder);
                if (units < share - 1e-9) largest_down = std::max(largest_down, remainder);
              }
              violations.note(smallest_up >= largest_down - 1e-9,
                              [&] { return vertexName(part.name, v) + ": a smaller remainder got the unit"; });
              for (const auto& entry : got) {
                violations.note(exact.count(entry.first) == 1,
                                [&] { return vertexName(part.name, v) + ": quantization invented a joint"; });
              }
            }
            INFO(violations.first);
            CHECK(violations.count == 0);
          }
        }
      }
    }
  }
}

TEST_CASE("glTF JOINTS_n/WEIGHTS_n sum to exactly 255 or 65535 with legal joints on every vertex", "[shared:asset-influences]") {
  SECTION("the worked example of docs/packed-influences.md") {
    QuantizedInfluences q;
    q.slots_per_vertex = 7;
    q.joints = {12, 3, 13, 4, 11, 2, 14};
    q.weights = {412, 250, 141, 97, 60, 28, 12};
    QuantizedInfluences q16 = requantizeInfluences(q, kUnsignedShortScale);
    CHECK(q16.joints == q.joints);
    CHECK(q16.weights == std::vector<std::uint16_t>{27000, 16384, 9241, 6357, 3932, 1835, 786});
    QuantizedInfluences q8 = requantizeInfluences(q, kUnsignedByteScale);
    CHECK(q8.weights == std::vector<std::uint16_t>{105, 64, 36, 25, 15, 7, 3});
    std::vector<VertexAttributeData> attributes = standardSkinAttributes(q, 15, WeightStorage::kUnsignedShort);
    REQUIRE(attributes.size() == 4);
    CHECK(attributes[0].semantic == "JOINTS_0");
    CHECK(attributes[0].bytes == std::vector<std::uint8_t>{12, 3, 13, 4});
    CHECK(attributes[2].bytes == std::vector<std::uint8_t>{11, 2, 14, 0});
    CHECK(attributes[3].semantic == "WEIGHTS_1");
    // 3932 = 0x0F5C, 1835 = 0x072B, 786 = 0x0312, then the empty eighth slot.
    CHECK(attributes[3].bytes == std::vector<std::uint8_t>{0x5C, 0x0F, 0x2B, 0x07, 0x12, 0x03, 0x00, 0x00});
    // A skin of more than 256 joints needs 16-bit JOINTS_n.
    std::vector<VertexAttributeData> wide_joints = standardSkinAttributes(q, 300, WeightStorage::kUnsignedByte);
    CHECK(wide_joints[0].accessor.component_type == kGltfUnsignedShort);
    CHECK(wide_joints[0].bytes == std::vector<std::uint8_t>{12, 0, 3, 0, 13, 0, 4, 0});
    CHECK(wide_joints[1].accessor.component_type == kGltfUnsignedByte);
    CHECK(wide_joints[1].bytes == std::vector<std::uint8_t>{105, 64, 36, 25});
    CHECK_THROWS_AS(standardSkinAttributes(q, 14, WeightStorage::kUnsignedShort), Error);
  }

  SECTION("every vertex of every shared asset, as stored and widened, at 4, 7 and 10") {
    double largest_u16_difference = 0.0;
    for (const test::AssetInfluences& asset : test::assetInfluences()) {
      const int joint_count = asset.skeleton.size();
      for (const test::PartInfluences& part : asset.parts) {
        for (const InfluenceSet* input : {&part.real, &part.wide}) {
          for (int budget : kPackedInfluenceCounts) {
            QuantizedInfluences q = quantizeInfluences(pruneInfluences(*input, budget));
            for (WeightStorage storage : {WeightStorage::kUnsignedByte, WeightStorage::kUnsignedShort}) {
              const bool bytes = storage == WeightStorage::kUnsignedByte;
              const int full_scale = bytes ? 255 : 65535;
              INFO(part.name << (input == &part.wide ? " (widened)" : "") << " N=" << budget << " scale "
                             << full_scale);
              std::vector<VertexAttributeData> attributes = standardSkinAttributes(q, joint_count, storage);
              const int sets = (budget + 3) / 4;
              REQUIRE(attributes.size() == static_cast<size_t>(2 * sets));
              const int vertices = q.vertexCount();
              for (int s = 0; s < sets; ++s) {
                const VertexAttributeData& joints = attributes[2 * s];
                const VertexAttributeData& weights = attributes[2 * s + 1];
                CHECK(joints.semantic == "JOINTS_" + std::to_string(s));
                CHECK(weights.semantic == "WEIGHTS_" + std::to_string(s));
                CHECK(joints.accessor.component_type == kGltfUnsignedByte);  // every asset has < 256 joints
                CHECK(joints.accessor.type == "VEC4");
                CHECK_FALSE(joints.accessor.normalized);
                CHECK(joints.accessor.count == vertices);
                CHECK(joints.bytes.size() == static_cast<size_t>(vertices) * 4);
                CHECK(weights.accessor.component_type == (bytes ? kGltfUnsignedByte : kGltfUnsignedShort));
                CHECK(weights.accessor.type == "VEC4");
                CHECK(weights.accessor.normalized);
                CHECK(weights.accessor.count == vertices);
                CHECK(weights.bytes.size() == static_cast<size_t>(vertices) * (bytes ? 4 : 8));
              }
              // Decode the bytes as a glTF reader would and check what the validator checks.
              const int slots = 4 * sets;
              std::vector<int> all_joints(static_cast<size_t>(vertices) * slots);
              std::vector<int> all_weights(static_cast<size_t>(vertices) * slots);
              for (int v = 0; v < vertices; ++v) {
                for (int k = 0; k < slots; ++k) {
                  const std::vector<std::uint8_t>& jb = attributes[2 * (k / 4)].bytes;
                  const std::vector<std::uint8_t>& wb = attributes[2 * (k / 4) + 1].bytes;
                  size_t element = static_cast<size_t>(v) * 4 + k % 4;
                  all_joints[static_cast<size_t>(v) * slots + k] = jb[element];
                  all_weights[static_cast<size_t>(v) * slots + k] =
                      bytes ? wb[element] : wb[2 * element] | (wb[2 * element + 1] << 8);
                }
              }
              Violations violations;
              for (int v = 0; v < vertices; ++v) {
                int sum = 0;
                for (int k = 0; k < slots; ++k) sum += all_weights[static_cast<size_t>(v) * slots + k];
                violations.note(sum == full_scale,
                                [&] { return vertexName(part.name, v) + ": sum " + std::to_string(sum); });
                std::string problem = canonicalProblem(all_joints, all_weights, slots, v, joint_count);
                violations.note(problem.empty(), [&] { return vertexName(part.name, v) + ": " + problem; });
              }
              INFO(violations.first);
              CHECK(violations.count == 0);
              if (!bytes) {
                // 0.001 steps are 65.535 u16 units: every weight survives, within one unit.
                QuantizedInfluences q16 = requantizeInfluences(q, kUnsignedShortScale);
                double difference = maxWeightDifference(dequantizeInfluences(q), dequantizeInfluences(q16));
                CHECK(difference < 1.0 / 65535.0);
                largest_u16_difference = std::max(largest_u16_difference, difference);
                for (int v = 0; v < vertices; ++v) {
                  int nonzero_milli = 0, nonzero_u16 = 0;
                  for (int k = 0; k < budget; ++k) {
                    nonzero_milli += q.weights[static_cast<size_t>(v) * budget + k] > 0;
                    nonzero_u16 += q16.weights[static_cast<size_t>(v) * budget + k] > 0;
                  }
                  violations.note(nonzero_milli == nonzero_u16,
                                  [&] { return vertexName(part.name, v) + ": u16 lost an influence"; });
                }
                INFO(violations.first);
                CHECK(violations.count == 0);
              }
            }
          }
        }
      }
    }
    // Requantizing really happens (not a copy): the largest difference is a visible fraction of a unit.
    if (!test::assetInfluences().empty()) CHECK(largest_u16_difference > 0.25 / 65535.0);
  }
}

TEST_CASE("the deformation error helper measures linear-blend skinning") {
  std::vector<Eigen::Vector3d> positions = {{1.0, 2.0, 3.0}, {-4.0, 0.5, 2.0}};
  InfluenceSet reference;
  reference.slots_per_vertex = 2;
  reference.joints = {0, 1, 1, 0};
  reference.weights = {0.5, 0.5, 1.0, 0.0};
  InfluenceSet approximation = reference;
  approximation.weights = {0.6, 0.4, 1.0, 0.0};
  std::vector<Eigen::Affine3d> identity(2, Eigen::Affine3d::Identity());
  DeformationError at_bind = skinningDeformationError(positions, reference, approximation, identity);
  CHECK(at_bind.max_displacement == 0.0);
  CHECK(at_bind.rms_displacement == 0.0);
  CHECK(at_bind.max_vertex == -1);
  std::vector<Eigen::Affine3d> moved = identity;
  moved[0] = Eigen::Translation3d(1.0, 0.0, 0.0);
  moved[1] = Eigen::Translation3d(0.0, 1.0, 0.0);
  DeformationError error = skinningDeformationError(positions, reference, approximation, moved);
  // Vertex 0 moves by 0.5 (1,0,0) + 0.5 (0,1,0) against 0.6 (1,0,0) + 0.4 (0,1,0): 0.1 * sqrt(2) apart.
  CHECK(error.max_displacement == Approx(0.1 * std::sqrt(2.0)).epsilon(1e-12));
  CHECK(error.max_vertex == 0);
  CHECK(error.rms_displacement == Approx(0.1).epsilon(1e-12));
  CHECK(error.vertex_count == 2);
  DeformationError both = combineDeformationErrors(at_bind, error);
  CHECK(both.max_vertex == 2);
  CHECK(both.vertex_count == 4);
  CHECK(both.rms_displacement == Approx(0.1 / std::sqrt(2.0)).epsilon(1e-12));
  CHECK(maxWeightDifference(reference, approximation) == Approx(0.1));
  InfluenceSet out_of_range = approximation;
  out_of_range.joints[0] = 2;
  CHECK_THROWS_AS(skinningDeformationError(positions, reference, out_of_range, moved), Error);
}

namespace {

struct QuantizationFigures {
  DeformationError bind;
  DeformationError posed;
  DeformationError posed_u16;   // 0.001 weights against their 1/65535 requantization
  DeformationError posed_prune;  // full-precision input against the pruned, quantized weights
};

// Quantization error of one asset at one budget, over all its skinned parts. The reference is the
// pruned full-precision weights, so at budgets the data does not exceed only quantization is measured.
QuantizationFigures measureQuantization(const test::AssetInfluences& asset, bool widened, int budget) {
  std::vector<Eigen::Affine3d> identity(asset.skeleton.size(), Eigen::Affine3d::Identity());
  std::vector<Eigen::Affine3d> pose = test::randomPoseSkinMatrices(asset.skeleton, 7001u, 30.0);
  QuantizationFigures figures;
  for (const test::PartInfluences& part : asset.parts) {
    const InfluenceSet& input = widened ? part.wide : part.real;
    InfluenceSet full = pruneInfluences(input, input.slots_per_vertex);
    InfluenceSet pruned = pruneInfluences(input, budget);
    QuantizedInfluences q = quantizeInfluences(pruned);
    InfluenceSet quantized = dequantizeInfluences(q);
    InfluenceSet quantized16 = dequantizeInfluences(requantizeInfluences(q, kUnsignedShortScale));
    figures.bind = combineDeformationErrors(
        figures.bind, skinningDeformationError(part.positions, pruned, quantized, identity));
    figures.posed =
        combineDeformationErrors(figures.posed, skinningDeformationError(part.positions, pruned, quantized, pose));
    figures.posed_u16 = combineDeformationErrors(
        figures.posed_u16, skinningDeformationError(part.positions, quantized, quantized16, pose));
    figures.posed_prune = combineDeformationErrors(
        figures.posed_prune, skinningDeformationError(part.positions, full, quantized, pose));
  }
  return figures;
}

}  // namespace

TEST_CASE("0.001 weights move no vertex of a shared asset by 0.1 mm per metre of character height", "[shared:asset-influences]") {
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    const double tolerance = 1e-4 * asset.height;  // 0.1 mm for every metre of height
    for (int budget : kPackedInfluenceCounts) {
      INFO(asset.asset << " N=" << budget << " height " << asset.height);
      QuantizationFigures figures = measureQuantization(asset, false, budget);
      // At the bind pose every skin matrix is the identity: no weight change can move a vertex.
      CHECK(figures.bind.max_displacement == 0.0);
      INFO("posed max " << figures.posed.max_displacement * 1000.0 << " mm");
      CHECK(figures.posed.max_displacement > 0.0);
      CHECK(figures.posed.max_displacement < tolerance);
      // The 1/65535 glTF weights sit well inside the 0.001 ones.
      CHECK(figures.posed_u16.max_displacement < 0.1 * tolerance);
    }
  }
}

TEST_CASE("every vertex's quantization error stays within the bound largest remainder guarantees", "[shared:asset-influences]") {
  // With d_k = w_quantized - w_exact summing to 0, the displacement sum_k d_k M_k p is the positive part
  // minus the negative part, each sum|d|/2 times a convex combination of the points M_k p: at most
  // sum|d| / 2 times the largest distance between two of them. Largest remainder keeps every |d_k|
  // below 0.001. This holds for any pose, so it also covers the widened data, whose many small weights
  // and far-apart joints make the absolute error larger (see the figures test).
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    std::vector<Eigen::Affine3d> pose = test::randomPoseSkinMatrices(asset.skeleton, 7001u, 30.0);
    for (const test::PartInfluences& part : asset.parts) {
      for (const InfluenceSet* input : {&part.real, &part.wide}) {
        for (int budget : kPackedInfluenceCounts) {
          INFO(part.name << (input == &part.wide ? " (widened)" : "") << " N=" << budget);
          InfluenceSet pruned = pruneInfluences(*input, budget);
          InfluenceSet quantized = dequantizeInfluences(quantizeInfluences(pruned));
          std::vector<double> displacement = skinningDisplacements(part.positions, pruned, quantized, pose);
          Violations violations;
          for (int v = 0; v < pruned.vertexCount(); ++v) {
            std::map<int, double> difference = mergedWeights(quantized, v);
            for (const auto& [joint, weight] : mergedWeights(pruned, v)) difference[joint] -= weight;
            double total = 0.0, diameter = 0.0;
            for (const auto& [joint, d] : difference) {
              violations.note(std::abs(d) < 1e-3, [&] { return vertexName(part.name, v) + ": a weight moved 0.001"; });
              total += std::abs(d);
              for (const auto& other : difference) {
                Eigen::Vector3d a = pose[joint] * part.positions[v], b = pose[other.first] * part.positions[v];
                diameter = std::max(diameter, (a - b).norm());
              }
            }
            violations.note(displacement[v] <= 0.5 * total * diameter + 1e-12, [&] {
              return vertexName(part.name, v) + ": displacement " + std::to_string(displacement[v]) +
                     " above its bound";
            });
          }
          INFO(violations.first);
          CHECK(violations.count == 0);
        }
      }
    }
  }
}

// Prints the figures docs/packed-influences.md quotes: `rigbake_tests "[.figures]"`.
TEST_CASE("deformation error figures", "[.figures]") {
  std::cout << std::fixed << std::setprecision(4);
  std::cout << "asset | data | N | height m | quantization max mm | rms mm | u16 extra max mm | prune+quantize "
               "max mm | rms mm\n";
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    for (bool widened : {false, true}) {
      for (int budget : kPackedInfluenceCounts) {
        QuantizationFigures f = measureQuantization(asset, widened, budget);
        std::cout << asset.asset << " | " << (widened ? "widened" : "file") << " | " << budget << " | "
                  << asset.height << " | " << f.posed.max_displacement * 1000 << " | "
                  << f.posed.rms_displacement * 1000 << " | " << f.posed_u16.max_displacement * 1000 << " | "
                  << f.posed_prune.max_displacement * 1000 << " | " << f.posed_prune.rms_displacement * 1000
                  << "\n";
        CHECK(f.bind.max_displacement == 0.0);
      }
    }
  }
  double largest = 0.0;
  for (const test::AssetInfluences& asset : test::assetInfluences()) {
    for (const test::PartInfluences& part : asset.parts) {
      for (const InfluenceSet* input : {&part.real, &part.wide}) {
        for (int budget : kPackedInfluenceCounts) {
          QuantizedInfluences q = quantizeInfluences(pruneInfluences(*input, budget));
          InfluenceSet q16 = dequantizeInfluences(requantizeInfluences(q, kUnsignedShortScale));
          largest = std::max(largest, maxWeightDifference(dequantizeInfluences(q), q16));
        }
      }
    }
  }
  std::cout << std::setprecision(9) << "largest |w16/65535 - w/1000| over every weight: " << largest << " ("
            << largest * 65535.0 << " of a 1/65535 unit)\n";
  CHECK(largest < 1.0 / 65535.0);
}
