// VRM spring bone export (formats/vrm_spring.h).
//
// Sources: vrm-c/vrm-specification "VRMC_springBone-1.0" (springs[].joints[] with node, hitRadius,
// stiffness, gravityPower, gravityDir, dragForce; a joint in one chain only; the Verlet reference
// update nextTail = currentTail + (currentTail - prevTail)(1 - dragForce) + deltaTime * stiffness *
// restDirection + deltaTime * gravityDir * gravityPower), and the VRM 0.x "secondaryAnimation"
// boneGroups (comment, stiffiness [sic], gravityPower, gravityDir {x,y,z}, dragForce, center,
// hitRadius, bones, colliderGroups) as UniVRM writes them.
#include "formats/vrm_spring.h"

#include <tiny_gltf.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "formats/gltf_json_value.h"

namespace rigbake {
namespace {

// glTF numbers are floats; rounding to 6 significant digits keeps the JSON short and deterministic.
double rounded(double value) {
  if (value == 0.0) return 0.0;
  const double scale = std::pow(10.0, 5 - static_cast<int>(std::floor(std::log10(std::abs(value)))));
  return std::round(value * scale) / scale;
}

int addTail(tinygltf::Model* model, const VrmSpring& spring) {
  tinygltf::Node tail;
  tail.name = model->nodes[spring.head_node].name + "_jiggleTail";
  tail.translation = {spring.tail_local.x(), spring.tail_local.y(), spring.tail_local.z()};
  model->nodes.push_back(tail);
  const int index = static_cast<int>(model->nodes.size()) - 1;
  model->nodes[spring.head_node].children.push_back(index);
  return index;
}

}  // namespace

VrmSpring vrmSpringFor(const JiggleSetup& setup, int head_node, const Eigen::Vector3d& head_scale) {
  const SpringConstants spring = springConstants(setup.params);
  VrmSpring out;
  out.name = setup.name;
  out.head_node = head_node;
  out.tail_local = (setup.length * setup.aim_axis).cwiseQuotient(head_scale);
  // Per VRM frame of length dt the stiffness term moves the tail by dt * stiffness along the rest
  // direction; for a small swing angle theta its tangential part is dt * stiffness * theta, an
  // acceleration stiffness * theta / dt of a tail displaced by L * theta: k = stiffness / (L dt).
  out.stiffness = rounded(spring.k * setup.length * kVrmReferenceFrameTime);
  // Verlet keeps (1 - dragForce) of the velocity per frame; the spring keeps exp(-beta dt).
  out.drag_force = rounded(1.0 - std::exp(-spring.beta * kVrmReferenceFrameTime));
  out.hit_radius = rounded(kVrmHitRadiusFraction * setup.length);
  return out;
}

std::vector<VrmSpring> vrmSpringsForSkeleton(const Skeleton& skeleton, const std::vector<JiggleSetup>& setups) {
  std::vector<VrmSpring> springs;
  for (const JiggleSetup& setup : setups) {
    if (setup.host != JiggleHost::kSkeletonJoint) continue;
    springs.push_back(vrmSpringFor(setup, skeleton.nodes[setup.joint], skeleton.rest_local[setup.joint].scale));
  }
  return springs;
}

void addVrmSpringBones(tinygltf::Model* model, const std::vector<VrmSpring>& springs) {
  const bool vrm1 = model->extensions.count("VRMC_vrm") > 0;
  const bool vrm0 = model->extensions.count("VRM") > 0;
  // writeBakedFile() only asks for springs of a VRM, so this is a caller's bug, not a user's input.
  if (!vrm1 && !vrm0) fail(errc::INTERNAL, "/extensions", "spring bones can only be exported into a VRM (0.x or 1.0) model");
  for (const VrmSpring& spring : springs) {
    if (spring.head_node < 0 || spring.head_node >= static_cast<int>(model->nodes.size()))
      fail(errc::GLTF_PARSE_FAILED, "/nodes/" + std::to_string(spring.head_node), "spring '" + spring.name + "' has no such node");
  }
  if (vrm1) {
    nlohmann::json extension = model->extensions.count("VRMC_springBone")
                                   ? toJsonValue(model->extensions["VRMC_springBone"])
                                   : nlohmann::json{{"specVersion", "1.0"}};
    if (!extension.is_object()) fail(errc::GLTF_PARSE_FAILED, "/extensions/VRMC_springBone", "must be an object");
    if (!extension.contains("springs")) extension["springs"] = nlohmann::json::array();
    for (const VrmSpring& spring : springs) {
      const int tail = addTail(model, spring);
      nlohmann::json head = {{"node", spring.head_node},
                             {"hitRadius", spring.hit_radius},
                             {"stiffness", spring.stiffness},
                             {"gravityPower", spring.gravity_power},
                             {"gravityDir", {spring.gravity_dir.x(), spring.gravity_dir.y(), spring.gravity_dir.z()}},
                             {"dragForce", spring.drag_force}};
      extension["springs"].push_back({{"name", spring.name}, {"joints", {head, {{"node", tail}}}}});
    }
    model->extensions["VRMC_springBone"] = toGltfValue(extension);
    bool listed = false;
    for (const std::string& used : model->extensionsUsed) listed |= used == "VRMC_springBone";
    if (!listed) model->extensionsUsed.push_back("VRMC_springBone");
    return;
  }
  nlohmann::json extension = toJsonValue(model->extensions["VRM"]);
  if (!extension.is_object()) fail(errc::GLTF_PARSE_FAILED, "/extensions/VRM", "must be an object");
  nlohmann::json& secondary = extension["secondaryAnimation"];
  if (secondary.is_null()) secondary = nlohmann::json::object();
  if (!secondary.is_object()) fail(errc::GLTF_PARSE_FAILED, "/extensions/VRM/secondaryAnimation", "must be an object");
  if (!secondary.contains("boneGroups")) secondary["boneGroups"] = nlohmann::json::array();
  if (!secondary.contains("colliderGroups")) secondary["colliderGroups"] = nlohmann::json::array();
  for (const VrmSpring& spring : springs) {
    addTail(model, spring);
    // VRM 0.x sways every descendant of a listed bone, and adds its own 7 cm tail to a leaf; the
    // tail node gives the leaf the jiggle's own length instead.
    secondary["boneGroups"].push_back(
        {{"comment", spring.name},
         {"stiffiness", spring.stiffness},
         {"gravityPower", spring.gravity_power},
         {"gravityDir", {{"x", spring.gravity_dir.x()}, {"y", spring.gravity_dir.y()}, {"z", spring.gravity_dir.z()}}},
         {"dragForce", spring.drag_force},
         {"center", -1},
         {"hitRadius", spring.hit_radius},
         {"bones", {spring.head_node}},
         {"colliderGroups", nlohmann::json::array()}});
  }
  model->extensions["VRM"] = toGltfValue(extension);
}

}  // namespace rigbake
