// Exports the muscle helper joints' aim constraints as VRMC_node_constraint 1.0 (vrm-c/vrm-specification,
// specification/VRMC_node_constraint-1.0), so VRM 1.0 runtimes aim the base and tip joints live. The
// driver's point constraint has no counterpart in that extension and is not exported (docs/extensions.md).
#pragma once

#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rigbake {

inline constexpr const char* kVrmNodeConstraintExtension = "VRMC_node_constraint";

// One aim constraint: the destination node's `aim_axis` turns, by the smallest rotation from its rest
// orientation, to point at the source node's world position.
struct VrmAimConstraint {
  int destination = -1;
  int source = -1;
  std::string aim_axis = "PositiveX";
  double weight = 1.0;
};

// Adds each constraint as its destination node's VRMC_node_constraint extension (specVersion "1.0")
// and the extension to extensionsUsed (not required: a runtime without it plays the channels). Throws
// USAGE when the model is not VRM 1.0 (VRM 0.x has no node constraints), GLTF_PARSE_FAILED when a node
// is out of range, a destination already has a constraint or is its own source, or the sources form
// a cycle (the specification forbids circular dependencies between constraints).
void addVrmAimConstraints(tinygltf::Model* model, const std::vector<VrmAimConstraint>& constraints);

}  // namespace rigbake
