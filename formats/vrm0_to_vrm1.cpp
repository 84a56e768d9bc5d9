// VRM 0.x -> VRM 1.0 (formats/vrm0_to_vrm1.h).
//
// Sources: vrm-c/vrm-specification "specification/0.0/README.md" (the 0.x "VRM" extension: meta,
// humanoid.humanBones [{bone, node}], firstPerson, secondaryAnimation boneGroups and colliderGroups);
// "VRMC_vrm-1.0" README, humanoid.md, meta.md, lookAt.md and tpose.md (the avatar faces +Z; node
// transforms may rotate; scales positive and uniform); "VRMC_springBone-1.0" (colliders, colliderGroups,
// springs of joints, a joint in one spring only, no implicit tail at a leaf).
// The choices follow UniVRM's own 0.x -> 1.0 migration (vrm-c/UniVRM, Assets/VRM10/Runtime/Migration:
// MigrationVrmMeta, MigrationVrmSpringBone, MigrateVector3) where it has one:
// - 0.x stored its vectors (collider offsets, gravityDir, firstPersonBoneOffset) in Unity's
//   left-handed axes, while its nodes are in glTF's with Z negated; VRM 1.0 stores glTF axes of a
//   model facing +Z. Here the model is turned by a new root node, not by rewriting its nodes, so an
//   offset in a node's frame (a collider's; the look-at offset, which 1.0 puts in the head's frame)
//   becomes (x, y, -z) (three-vrm reads 0.x collider offsets so) and a model-space direction (gravity)
//   (-x, y, z), as UniVRM's MigrateVector3 (UniVRM turns the nodes' frames as well, hence one rule).
// - Springs: in 0.x every descendant of a listed bone swings, each toward its first child. Each bone's
//   chain follows first children down to a leaf, which gets a 7 cm tail node along its bone (0.x added
//   that tail implicitly; 1.0 does not). Every other child starts a chain of its own, so every
//   descendant is a joint of exactly one spring (UniVRM skips the other children themselves).
// - Meta: the permissions map one to one; commercial "Allow" becomes personalProfit, not corporation
//   (0.x did not say which); the 0.x licenseName has no 1.0 field (the VRM Consortium says licences
//   cannot be migrated automatically), so the 1.0 defaults stand: credit required, no redistribution,
//   modification prohibited.
#include "formats/vrm0_to_vrm1.h"

#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "formats/gltf_json_value.h"

namespace rigbake {
// A named namespace: formats/ is compiled in unity batches, where other files' helpers of the same
// names (nodeLocal) would clash.
namespace vrm0_to_vrm1 {

constexpr double kLeafTailMetres = 0.07;  // VRM 0.x's implicit tail at a leaf
constexpr const char* kTurnNodeName = "VRM0_to_VRM1_facing";

using Json = nlohmann::json;

struct Context {
  tinygltf::Model* model;
  std::string path;
  std::vector<std::string> notes;
};

[[noreturn]] void malformed(const Context& context, const std::string& pointer, const std::string& what) {
  fail(errc::GLTF_PARSE_FAILED, context.path + "#/extensions/VRM" + pointer, what);
}

int nodeIndex(const Context& context, const Json& value, const std::string& pointer) {
  if (!value.is_number_integer() || value.get<long long>() < 0 ||
      value.get<long long>() >= static_cast<long long>(context.model->nodes.size()))
    malformed(context, pointer, "is not a node index");
  return value.get<int>();
}

double number(const Json& object, const char* key, double fallback) {
  auto it = object.find(key);
  return it != object.end() && it->is_number() ? it->get<double>() : fallback;
}

std::string text(const Json& object, const char* key) {
  auto it = object.find(key);
  return it != object.end() && it->is_string() ? it->get<std::string>() : std::string();
}

Eigen::Vector3d vector3(const Json& object, const char* key, const Eigen::Vector3d& fallback) {
  auto it = object.find(key);
  if (it == object.end() || !it->is_object()) return fallback;
  return {number(*it, "x", fallback.x()), number(*it, "y", fallback.y()), number(*it, "z", fallback.z())};
}

Json array3(const Eigen::Vector3d& v) { return Json::array({v.x() + 0.0, v.y() + 0.0, v.z() + 0.0}); }

// A Unity-axes offset in a node's frame -> glTF axes in the same (unturned) node frame.
Eigen::Vector3d nodeLocalFromUnity(const Eigen::Vector3d& v) { return {v.x(), v.y(), -v.z()}; }
// A Unity-axes model-space direction -> glTF axes of the model turned to face +Z.
Eigen::Vector3d modelFromUnity(const Eigen::Vector3d& v) { return {-v.x(), v.y(), v.z()}; }

Eigen::Affine3d nodeLocal(const tinygltf::Node& node) {
  Eigen::Affine3d local = Eigen::Affine3d::Identity();
  if (node.matrix.size() == 16) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) local.matrix()(r, c) = node.matrix[c * 4 + r];
    return local;
  }
  if (node.translation.size() == 3) local.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)
    local.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]).normalized());
  if (node.scale.size() == 3) local.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
  return local;
}

// Parent of every node (-1 for a root) and world transforms at rest, before the turn.
struct NodeFrames {
  std::vector<int> parent;
  std::vector<Eigen::Affine3d> world;
};

NodeFrames nodeFrames(const tinygltf::Model& model) {
  const int count = static_cast<int>(model.nodes.size());
  NodeFrames frames;
  frames.parent.assign(count, -1);
  for (int n = 0; n < count; ++n)
    for (int child : model.nodes[n].children)
      if (child >= 0 && child < count) frames.parent[child] = n;
  frames.world.assign(count, Eigen::Affine3d::Identity());
  std::vector<int> state(count, 0);  // 0 unvisited, 1 on the stack, 2 done: a cycle stops, not recurses forever
  std::function<void(int)> resolve = [&](int n) {
    if (state[n] != 0) return;
    state[n] = 1;
    const int p = frames.parent[n];
    if (p >= 0) resolve(p);
    frames.world[n] = (p >= 0 ? frames.world[p] : Eigen::Affine3d::Identity()) * nodeLocal(model.nodes[n]);
    state[n] = 2;
  };
  for (int n = 0; n < count; ++n) resolve(n);
  return frames;
}

// object[key], or null when `object` is no object or lacks the key.
const Json& field(const Json& object, const char* key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  auto it = object.find(key);
  return it != object.end() ? *it : kNull;
}

const Json& arrayField(const Context& context, const Json& object, const char* key, const std::string& pointer) {
  static const Json kEmpty = Json::array();
  const Json& value = field(object, key);
  if (value.is_null()) return kEmpty;
  if (!value.is_array()) malformed(context, pointer, "must be an array");
  return value;
}

Json convertHumanoid(Context* context, const Json& vrm0) {
  const Json& bones = arrayField(*context, field(vrm0, "humanoid"), "humanBones", "/humanoid/humanBones");
  Json human_bones = Json::object();
  std::vector<std::string> unknown;
  for (size_t i = 0; i < bones.size(); ++i) {
    const std::string pointer = "/humanoid/humanBones/" + std::to_string(i);
    if (!bones[i].is_object() || !bones[i].contains("bone") || !bones[i]["bone"].is_string())
      malformed(*context, pointer, "must be an object with a bone name");
    const std::string name = vrm1HumanBoneName(bones[i]["bone"].get<std::string>());
    if (name.empty()) {
      unknown.push_back(bones[i]["bone"].get<std::string>());
      continue;
    }
    if (human_bones.contains(name)) malformed(*context, pointer, "humanoid bone '" + name + "' is listed twice");
    human_bones[name] = {{"node", nodeIndex(*context, bones[i].value("node", Json()), pointer + "/node")}};
  }
  for (const std::string& name : unknown)
    context->notes.push_back("VRM 0.x humanoid bone '" + name + "' has no VRM 1.0 name and was left out");
  return {{"humanBones", human_bones}};
}

Json convertMeta(Context* context, const Json& vrm0) {
  const Json meta = field(vrm0, "meta").is_null() ? Json::object() : field(vrm0, "meta");
  if (!meta.is_object()) malformed(*context, "/meta", "must be an object");
  Json out = {{"name", text(meta, "title").empty() ? std::string("VRM avatar") : text(meta, "title")},
              {"authors", Json::array({text(meta, "author").empty() ? std::string("unknown") : text(meta, "author")})},
              {"licenseUrl", "https://vrm.dev/licenses/1.0/"}};
  if (!text(meta, "version").empty()) out["version"] = text(meta, "version");
  if (!text(meta, "contactInformation").empty()) out["contactInformation"] = text(meta, "contactInformation");
  if (!text(meta, "reference").empty()) out["references"] = Json::array({text(meta, "reference")});
  // 0.x names a texture, 1.0 an image.
  const int texture = static_cast<int>(number(meta, "texture", -1));
  if (texture >= 0 && texture < static_cast<int>(context->model->textures.size()) &&
      context->model->textures[texture].source >= 0)
    out["thumbnailImage"] = context->model->textures[texture].source;
  static const std::map<std::string, std::string> kAvatar = {
      {"OnlyAuthor", "onlyAuthor"}, {"ExplicitlyLicensedPerson", "onlySeparatelyLicensedPerson"}, {"Everyone", "everyone"}};
  auto avatar = kAvatar.find(text(meta, "allowedUserName"));
  out["avatarPermission"] = avatar != kAvatar.end() ? avatar->second : "onlyAuthor";
  out["allowExcessivelyViolentUsage"] = text(meta, "violentUssageName") == "Allow";  // "Ussage": the 0.x spelling
  out["allowExcessivelySexualUsage"] = text(meta, "sexualUssageName") == "Allow";
  out["commercialUsage"] = text(meta, "commercialUssageName") == "Allow" ? "personalProfit" : "personalNonProfit";
  out["allowPoliticalOrReligiousUsage"] = false;
  out["allowAntisocialOrHateUsage"] = false;
  out["creditNotation"] = "required";
  out["allowRedistribution"] = false;
  out["modification"] = "prohibited";
  const std::string other = !text(meta, "otherLicenseUrl").empty() ? text(meta, "otherLicenseUrl") : text(meta, "otherPermissionUrl");
  if (!other.empty()) out["otherLicenseUrl"] = other;
  if (!text(meta, "licenseName").empty()) {
    context->notes.push_back("VRM 0.x licenseName '" + text(meta, "licenseName") +
                             "' has no VRM 1.0 field: the 1.0 meta keeps its defaults (credit required, no "
                             "redistribution, no modification); set them for the licence the author gave");
  }
  return out;
}

// firstPerson.meshAnnotations name meshes in 0.x and nodes in 1.0: every node showing the mesh.
Json convertFirstPerson(Context* context, const Json& first_person) {
  static const std::map<std::string, std::string> kFlags = {
      {"Auto", "auto"}, {"Both", "both"}, {"ThirdPersonOnly", "thirdPersonOnly"}, {"FirstPersonOnly", "firstPersonOnly"}};
  Json annotations = Json::array();
  for (const Json& annotation : arrayField(*context, first_person, "meshAnnotations", "/firstPerson/meshAnnotations")) {
    if (!annotation.is_object()) continue;
    const int mesh = static_cast<int>(number(annotation, "mesh", -1));
    auto flag = kFlags.find(text(annotation, "firstPersonFlag"));
    for (size_t n = 0; n < context->model->nodes.size(); ++n) {
      if (context->model->nodes[n].mesh != mesh || mesh < 0) continue;
      annotations.push_back({{"node", static_cast<int>(n)}, {"type", flag != kFlags.end() ? flag->second : "auto"}});
    }
  }
  return {{"meshAnnotations", annotations}};
}

// 0.x look-at maps carry a curve; 1.0's range maps are linear (inputMaxValue = xRange, outputScale = yRange).
Json convertLookAt(const Json& first_person) {
  Json look_at = {{"type", text(first_person, "lookAtTypeName") == "BlendShape" ? "expression" : "bone"},
                  {"offsetFromHeadBone", array3(nodeLocalFromUnity(vector3(first_person, "firstPersonBoneOffset", Eigen::Vector3d::Zero())))}};
  const std::pair<const char*, const char*> maps[] = {{"lookAtHorizontalInner", "rangeMapHorizontalInner"},
                                                      {"lookAtHorizontalOuter", "rangeMapHorizontalOuter"},
                                                      {"lookAtVerticalDown", "rangeMapVerticalDown"},
                                                      {"lookAtVerticalUp", "rangeMapVerticalUp"}};
  for (const auto& [from, to] : maps) {
    auto it = first_person.find(from);
    if (it == first_person.end() || !it->is_object()) continue;
    look_at[to] = {{"inputMaxValue", number(*it, "xRange", 90.0)}, {"outputScale", number(*it, "yRange", 10.0)}};
  }
  return look_at;
}

struct SpringExtension {
  Json colliders = Json::array();
  Json collider_groups = Json::array();
  Json springs = Json::array();
  int joints = 0;  // joints that swing (tails left out)
  int tails = 0;
};

// 0.x collider group index -> 1.0 index; -1 for a group with no collider (1.0 needs at least one).
std::vector<int> convertColliders(Context* context, const Json& secondary, SpringExtension* out) {
  const Json& groups = arrayField(*context, secondary, "colliderGroups", "/secondaryAnimation/colliderGroups");
  std::vector<int> index_of;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::string pointer = "/secondaryAnimation/colliderGroups/" + std::to_string(g);
    if (!groups[g].is_object()) malformed(*context, pointer, "must be an object");
    const int node = nodeIndex(*context, groups[g].value("node", Json()), pointer + "/node");
    Json members = Json::array();
    for (const Json& collider : arrayField(*context, groups[g], "colliders", pointer + "/colliders")) {
      if (!collider.is_object()) continue;
      members.push_back(out->colliders.size());
      const Eigen::Vector3d offset = nodeLocalFromUnity(vector3(collider, "offset", Eigen::Vector3d::Zero()));
      out->colliders.push_back(
          {{"node", node}, {"shape", {{"sphere", {{"offset", array3(offset)}, {"radius", number(collider, "radius", 0.0)}}}}}});
    }
    if (members.empty()) {
      index_of.push_back(-1);
      context->notes.push_back("VRM 0.x collider group " + std::to_string(g) + " has no collider and was left out");
      continue;
    }
    index_of.push_back(static_cast<int>(out->collider_groups.size()));
    out->collider_groups.push_back({{"name", context->model->nodes[node].name}, {"colliders", members}});
  }
  return index_of;
}

int addTailNodeAt(tinygltf::Model* model, int parent, const Eigen::Vector3d& local) {
  tinygltf::Node tail;
  tail.name = model->nodes[parent].name + "_end";
  tail.translation = {local.x(), local.y(), local.z()};
  model->nodes.push_back(tail);
  const int index = static_cast<int>(model->nodes.size()) - 1;
  model->nodes[parent].children.push_back(index);
  return index;
}

int addTailNode(tinygltf::Model* model, const NodeFrames& frames, int leaf) {
  const int parent = frames.parent[leaf];
  Eigen::Vector3d along = Eigen::Vector3d::Zero();
  if (parent >= 0) along = frames.world[leaf].translation() - frames.world[parent].translation();
  if (along.norm() < 1e-9) along = Eigen::Vector3d::UnitY();  // a bone of no length: straight up, as at rest
  return addTailNodeAt(model, leaf, frames.world[leaf].linear().inverse() * (kLeafTailMetres * along.normalized()));
}

void convertBoneGroup(Context* context, const NodeFrames& frames, const Json& group, const std::string& pointer,
                      const std::vector<int>& collider_group_of, std::set<int>* used, SpringExtension* out) {
  if (!group.is_object()) malformed(*context, pointer, "must be an object");
  const Eigen::Vector3d gravity = modelFromUnity(vector3(group, "gravityDir", Eigen::Vector3d(0.0, -1.0, 0.0)));
  Json joint_settings = {{"hitRadius", number(group, "hitRadius", 0.0)},
                         {"stiffness", number(group, "stiffiness", 1.0)},  // "stiffiness": the 0.x spelling
                         {"gravityPower", number(group, "gravityPower", 0.0)},
                         {"gravityDir", array3(gravity)},
                         {"dragForce", number(group, "dragForce", 0.4)}};
  Json groups = Json::array();
  for (const Json& g : arrayField(*context, group, "colliderGroups", pointer + "/colliderGroups")) {
    const int index = g.is_number_integer() ? g.get<int>() : -1;
    if (index < 0 || index >= static_cast<int>(collider_group_of.size()))
      malformed(*context, pointer + "/colliderGroups", "names no collider group");
    if (collider_group_of[index] >= 0) groups.push_back(collider_group_of[index]);
  }
  const int center = static_cast<int>(number(group, "center", -1));
  std::vector<int> starts;
  const Json& bones = arrayField(*context, group, "bones", pointer + "/bones");
  for (size_t b = 0; b < bones.size(); ++b) starts.push_back(nodeIndex(*context, bones[b], pointer + "/bones/" + std::to_string(b)));
  // Each start runs down first children; the other children of every joint become starts of their own.
  for (size_t s = 0; s < starts.size(); ++s) {
    Json joints = Json::array();
    int node = starts[s];
    while (node >= 0 && !used->count(node)) {
      used->insert(node);
      Json joint = joint_settings;
      joint["node"] = node;
      joints.push_back(joint);
      ++out->joints;
      const std::vector<int>& children = context->model->nodes[node].children;
      for (size_t c = 1; c < children.size(); ++c) starts.push_back(children[c]);
      if (children.empty()) {
        joints.push_back({{"node", addTailNode(context->model, frames, node)}});
        ++out->tails;
        node = -1;
      } else {
        node = children[0];
      }
    }
    // A chain that ran into another spring's joint (0.x groups whose bones overlap) ends in a tail node of
    // its own at that joint's place: 1.0 lets no joint belong to two springs.
    if (node >= 0 && !joints.empty()) {
      joints.push_back({{"node", addTailNodeAt(context->model, joints.back()["node"].get<int>(),
                                               nodeLocal(context->model->nodes[node]).translation())}});
      ++out->tails;
    }
    if (joints.size() < 2) continue;  // the start was already a joint of another spring
    Json spring = {{"name", text(group, "comment")}, {"joints", joints}};
    if (!groups.empty()) spring["colliderGroups"] = groups;
    if (center >= 0 && center < static_cast<int>(context->model->nodes.size())) spring["center"] = center;
    out->springs.push_back(spring);
  }
}

SpringExtension convertSprings(Context* context, const Json& vrm0) {
  SpringExtension out;
  const Json& secondary = field(vrm0, "secondaryAnimation");
  if (!secondary.is_object()) return out;
  const NodeFrames frames = nodeFrames(*context->model);
  const std::vector<int> collider_group_of = convertColliders(context, secondary, &out);
  std::set<int> used;
  const Json& groups = arrayField(*context, secondary, "boneGroups", "/secondaryAnimation/boneGroups");
  for (size_t g = 0; g < groups.size(); ++g)
    convertBoneGroup(context, frames, groups[g], "/secondaryAnimation/boneGroups/" + std::to_string(g), collider_group_of, &used, &out);
  return out;
}

// A new root node turned 180 degrees about Y holds every scene's roots: the 0.x avatar faced -Z. A
// skinned mesh's own node stays a root: its transform does not move the skin (the joints do), and the
// Khronos validator warns of a skinned mesh below a root (NODE_SKINNED_MESH_NON_ROOT).
void turnToFacePlusZ(tinygltf::Model* model) {
  tinygltf::Node turn;
  turn.name = kTurnNodeName;
  turn.rotation = {0.0, 1.0, 0.0, 0.0};
  const int index = static_cast<int>(model->nodes.size());
  std::set<int> wrapped;
  for (tinygltf::Scene& scene : model->scenes) {
    std::vector<int> roots = {index};
    for (int root : scene.nodes) {
      const bool known = root >= 0 && root < index;
      if (known && model->nodes[root].skin >= 0 && model->nodes[root].mesh >= 0 && model->nodes[root].children.empty()) {
        roots.push_back(root);
      } else if (wrapped.insert(root).second) {
        turn.children.push_back(root);
      }
    }
    scene.nodes = roots;
  }
  model->nodes.push_back(turn);
}

void listExtension(std::vector<std::string>* list, const std::string& name, bool present) {
  std::vector<std::string> kept;
  for (const std::string& entry : *list)
    if (entry != "VRM" && entry != name) kept.push_back(entry);
  if (present) kept.push_back(name);
  *list = kept;
}

std::vector<std::string> convertVrm0(tinygltf::Model* model, const std::string& path) {
  Context context{model, path, {}};
  const Json vrm0 = toJsonValue(model->extensions.at("VRM"));
  if (!vrm0.is_object()) malformed(context, "", "must be an object");
  Json vrm1 = {{"specVersion", "1.0"}, {"meta", convertMeta(&context, vrm0)}, {"humanoid", convertHumanoid(&context, vrm0)}};
  const Json& first_person = field(vrm0, "firstPerson");
  if (first_person.is_object() && !first_person.empty()) {
    vrm1["firstPerson"] = convertFirstPerson(&context, first_person);
    vrm1["lookAt"] = convertLookAt(first_person);
  }
  const SpringExtension springs = convertSprings(&context, vrm0);
  const Json& shapes = field(field(vrm0, "blendShapeMaster"), "blendShapeGroups");
  const size_t blend_shape_groups = shapes.is_array() ? shapes.size() : 0;
  if (blend_shape_groups > 0)
    context.notes.push_back(std::to_string(blend_shape_groups) + " VRM 0.x blend shape groups were not converted (no VRM 1.0 expressions are written)");
  int mtoon = 0;
  for (const Json& material : arrayField(context, vrm0, "materialProperties", "/materialProperties"))
    mtoon += material.is_object() && text(material, "shader") != "VRM_USE_GLTFSHADER";
  if (mtoon > 0)
    context.notes.push_back(std::to_string(mtoon) + " VRM 0.x material properties (MToon) were not converted: those materials render as their glTF materials");

  turnToFacePlusZ(model);
  model->extensions.erase("VRM");
  model->extensions["VRMC_vrm"] = toGltfValue(vrm1);
  const bool any_spring = !springs.springs.empty() || !springs.colliders.empty();
  if (any_spring) {
    Json extension = {{"specVersion", "1.0"}, {"colliders", springs.colliders}, {"colliderGroups", springs.collider_groups},
                      {"springs", springs.springs}};
    model->extensions["VRMC_springBone"] = toGltfValue(extension);
  }
  listExtension(&model->extensionsUsed, "VRMC_vrm", true);
  if (any_spring) listExtension(&model->extensionsUsed, "VRMC_springBone", true);
  listExtension(&model->extensionsRequired, "VRMC_vrm", false);
  context.notes.insert(context.notes.begin(),
                       "converted VRM 0.x to VRM 1.0: " + std::to_string(vrm1["humanoid"]["humanBones"].size()) + " humanoid bones, " +
                           std::to_string(springs.springs.size()) + " springs (" + std::to_string(springs.joints) + " joints, " +
                           std::to_string(springs.tails) + " 7 cm leaf tails added), " + std::to_string(springs.colliders.size()) +
                           " colliders in " + std::to_string(springs.collider_groups.size()) +
                           " groups; turned 180 degrees about Y to face +Z");
  return context.notes;
}

}  // namespace vrm0_to_vrm1

std::string vrm1HumanBoneName(const std::string& vrm0_name) {
  static const char* const kSame[] = {
      "hips", "spine", "chest", "upperChest", "neck", "head", "leftEye", "rightEye", "jaw",
      "leftUpperLeg", "leftLowerLeg", "leftFoot", "leftToes", "rightUpperLeg", "rightLowerLeg", "rightFoot", "rightToes",
      "leftShoulder", "leftUpperArm", "leftLowerArm", "leftHand", "rightShoulder", "rightUpperArm", "rightLowerArm", "rightHand"};
  for (const char* name : kSame)
    if (vrm0_name == name) return vrm0_name;
  for (const char* side : {"left", "right"}) {
    const std::string s = side;
    if (vrm0_name == s + "ThumbProximal") return s + "ThumbMetacarpal";
    if (vrm0_name == s + "ThumbIntermediate") return s + "ThumbProximal";
    if (vrm0_name == s + "ThumbDistal") return s + "ThumbDistal";
    for (const char* finger : {"Index", "Middle", "Ring", "Little"})
      for (const char* segment : {"Proximal", "Intermediate", "Distal"})
        if (vrm0_name == s + finger + segment) return vrm0_name;
  }
  return "";
}

std::vector<std::string> convertVrm0ToVrm1(tinygltf::Model* model, const std::string& path) {
  try {
    return vrm0_to_vrm1::convertVrm0(model, path);
  } catch (const nlohmann::json::exception& error) {
    // A member of an unexpected type deep inside the 0.x extension.
    fail(errc::GLTF_PARSE_FAILED, path + "#/extensions/VRM", std::string("malformed VRM 0.x extension: ") + error.what());
  }
}

}  // namespace rigbake
