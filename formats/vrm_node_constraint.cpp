// VRMC_node_constraint export (formats/vrm_node_constraint.h).
//
// Source: vrm-c/vrm-specification "VRMC_node_constraint-1.0": a node's extension object holds
// specVersion "1.0" and one constraint (roll, aim or rotation); an aim constraint has source (a node
// index), aimAxis (PositiveX ... NegativeZ) and weight (default 1). A source must not be its
// destination nor make a circular dependency between constraints. Runtimes order constraints by
// dependency, where a constraint depends on the constraints of its source and of the source's
// ancestors, and (aim: world space) of its destination's parent and that parent's ancestors; the
// check below uses that rule, as a runtime that follows it would fail on a cycle.
#include "formats/vrm_node_constraint.h"

#include <tiny_gltf.h>

#include <map>
#include <set>

#include "core/error.h"
#include "formats/gltf_json_value.h"

namespace rigbake {
namespace {

// The source node of an existing constraint object, or -1.
int constraintSource(const tinygltf::Value& extension) {
  const tinygltf::Value& constraint = gltfMember(extension, "constraint");
  for (const char* kind : {"roll", "aim", "rotation"}) {
    const tinygltf::Value& source = gltfMember(gltfMember(constraint, kind), "source");
    if (source.IsNumber()) return source.GetNumberAsInt();
  }
  return -1;
}

}  // namespace

void addVrmAimConstraints(tinygltf::Model* model, const std::vector<VrmAimConstraint>& constraints) {
  if (model->extensions.count("VRMC_vrm") == 0)
    // addHelperAimConstraints() only asks for them in a VRM 1.0, so this is a caller's bug, not a user's input.
    fail(errc::INTERNAL, "/extensions", "node constraints can only be exported into a VRM 1.0 model");
  if (constraints.empty()) return;
  const int node_count = static_cast<int>(model->nodes.size());
  std::vector<int> parent(node_count, -1);
  for (int n = 0; n < node_count; ++n) {
    for (int child : model->nodes[n].children) {
      if (child >= 0 && child < node_count) parent[child] = n;
    }
  }
  // Every constraint of the model after the export: destination -> (source, destination's parent
  // counts). The file's own are kept as they are.
  std::map<int, int> source_of;
  for (int n = 0; n < node_count; ++n) {
    auto existing = model->nodes[n].extensions.find(kVrmNodeConstraintExtension);
    if (existing != model->nodes[n].extensions.end()) source_of[n] = constraintSource(existing->second);
  }
  for (const VrmAimConstraint& c : constraints) {
    for (int node : {c.destination, c.source}) {
      if (node < 0 || node >= node_count)
        fail(errc::GLTF_PARSE_FAILED, "/nodes/" + std::to_string(node), "a node constraint names no such node");
    }
    const std::string where = "/nodes/" + std::to_string(c.destination) + "/extensions/" + kVrmNodeConstraintExtension;
    if (c.source == c.destination) fail(errc::GLTF_PARSE_FAILED, where, "a constraint's source must not be its destination");
    if (!source_of.emplace(c.destination, c.source).second)
      fail(errc::GLTF_PARSE_FAILED, where, "the node already has a constraint");
  }
  // The constraints a constraint waits for: those on its source and the source's ancestors, and on its
  // destination's ancestors.
  auto dependencies = [&](int destination) {
    std::vector<int> out;
    const int source = source_of.at(destination);
    for (int start : {source, destination >= 0 ? parent[destination] : -1}) {
      for (int n = start; n >= 0 && n < node_count; n = parent[n]) {
        if (source_of.count(n)) out.push_back(n);
      }
    }
    return out;
  };
  for (const VrmAimConstraint& c : constraints) {
    std::set<int> seen;
    std::vector<int> stack = dependencies(c.destination);
    while (!stack.empty()) {
      const int n = stack.back();
      stack.pop_back();
      if (n == c.destination)
        fail(errc::GLTF_PARSE_FAILED, "/nodes/" + std::to_string(c.destination) + "/extensions/" + kVrmNodeConstraintExtension,
             "the constraint's source depends on the constraint itself (a circular dependency)");
      if (!seen.insert(n).second) continue;
      for (int next : dependencies(n)) stack.push_back(next);
    }
  }
  for (const VrmAimConstraint& c : constraints) {
    tinygltf::Value::Object aim;
    aim["source"] = tinygltf::Value(c.source);
    aim["aimAxis"] = tinygltf::Value(c.aim_axis);
    aim["weight"] = tinygltf::Value(c.weight);
    tinygltf::Value::Object constraint;
    constraint["aim"] = tinygltf::Value(aim);
    tinygltf::Value::Object extension;
    extension["specVersion"] = tinygltf::Value(std::string("1.0"));
    extension["constraint"] = tinygltf::Value(constraint);
    model->nodes[c.destination].extensions[kVrmNodeConstraintExtension] = tinygltf::Value(extension);
  }
  bool listed = false;
  for (const std::string& used : model->extensionsUsed) listed |= used == kVrmNodeConstraintExtension;
  if (!listed) model->extensionsUsed.push_back(kVrmNodeConstraintExtension);
}

}  // namespace rigbake
