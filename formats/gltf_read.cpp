// Loads a skinned character through tinygltf into plain rigbake data.
// glTF 2.0 specification, "Skins": jointMatrix = globalJointTransform * inverseBindMatrix, and the
// transform of the node that instantiates a skinned mesh is ignored. The bind pose in the scene is
// therefore G * inverse(inverseBindMatrix), with G = world(root joint) * IBM(root joint) at rest.
// VRM 0.x ("VRM" extension, humanoid.humanBones[] = {bone, node}) and VRM 1.0 ("VRMC_vrm",
// humanoid.humanBones = {name: {node}}) give the humanoid mapping directly.
#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "formats/gltf_json_value.h"
#include "formats/atomic_file.h"
#include "formats/gltf_accessor.h"
#include "formats/gltf_decompress.h"
#include "formats/gltf_document.h"
#include "formats/gltf_extensions.h"
#include "formats/json_reader.h"
#include "formats/fbx_to_gltf.h"
#include "formats/vrm0_to_vrm1.h"

namespace rigbake {

struct GltfDocument {
  tinygltf::Model model;
};

tinygltf::Model& modelOf(GltfDocument& document) { return document.model; }
const tinygltf::Model& modelOf(const GltfDocument& document) { return document.model; }

namespace {

// rigbake never decodes textures: it keeps the encoded bytes so that a writer can embed them as
// they were.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

std::string firstLine(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line.empty() ? "unknown parse error" : line;
}

// extensionsRequired as the file's JSON says, read without tinygltf: a file that requires an extension
// tinygltf cannot parse must still be refused for that reason, not as a parse failure.
std::vector<std::string> requiredExtensionsOf(const std::string& bytes) {
  std::string text = bytes;
  if (bytes.size() >= 20 && bytes.compare(0, 4, "glTF") == 0) {
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, sizeof(length));
    if (bytes.compare(16, 4, "JSON") != 0 || length > bytes.size() - 20) return {};
    text = bytes.substr(20, length);
  }
  const nlohmann::json json = nlohmann::json::parse(text, nullptr, false);
  std::vector<std::string> required;
  if (!json.is_object() || !json.contains("extensionsRequired") || !json["extensionsRequired"].is_array()) return {};
  for (const nlohmann::json& name : json["extensionsRequired"]) {
    if (name.is_string()) required.push_back(name.get<std::string>());
  }
  return required;
}

Trs nodeTrs(const tinygltf::Node& node) {
  Trs trs;
  if (node.matrix.size() == 16) {
    Eigen::Matrix4d m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[c * 4 + r];
    Eigen::Affine3d affine(m);
    Eigen::Matrix3d rotation, scaling;
    affine.computeRotationScaling(&rotation, &scaling);
    trs.translation = affine.translation();
    trs.rotation = Eigen::Quaterniond(rotation);
    trs.scale = scaling.diagonal();
    return trs;
  }
  if (node.translation.size() == 3) trs.translation = {node.translation[0], node.translation[1], node.translation[2]};
  if (node.rotation.size() == 4)
    trs.rotation = Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
  if (node.scale.size() == 3) trs.scale = {node.scale[0], node.scale[1], node.scale[2]};
  return trs;
}

Eigen::Affine3d nodeLocal(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    Eigen::Matrix4d m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[c * 4 + r];
    return Eigen::Affine3d(m);
  }
  return nodeTrs(node).matrix();
}

struct NodeTree {
  std::vector<int> parent;
  std::vector<Eigen::Affine3d> world;
  std::vector<int> dfs_order;  // nodes in scene traversal order, parents first
};

NodeTree buildNodeTree(const tinygltf::Model& model, const std::string& where) {
  const int n = static_cast<int>(model.nodes.size());
  NodeTree tree;
  tree.parent.assign(n, -1);
  tree.world.assign(n, Eigen::Affine3d::Identity());
  for (int i = 0; i < n; ++i) {
    for (int child : model.nodes[i].children) {
      if (child < 0 || child >= n || tree.parent[child] != -1 || child == i)
        fail(errc::GLTF_PARSE_FAILED, where, "/nodes/" + std::to_string(i) + " has an invalid child " + std::to_string(child));
      tree.parent[child] = i;
    }
  }
  std::vector<char> visited(n, 0);
  std::function<void(int)> visit = [&](int node) {
    if (visited[node]) fail(errc::GLTF_PARSE_FAILED, where, "the node hierarchy has a cycle at /nodes/" + std::to_string(node));
    visited[node] = 1;
    tree.world[node] = (tree.parent[node] >= 0 ? tree.world[tree.parent[node]] : Eigen::Affine3d::Identity()) *
                       nodeLocal(model.nodes[node]);
    tree.dfs_order.push_back(node);
    for (int child : model.nodes[node].children) visit(child);
  };
  for (int i = 0; i < n; ++i) {
    if (tree.parent[i] == -1) visit(i);
  }
  for (int i = 0; i < n; ++i) {
    if (!visited[i]) fail(errc::GLTF_PARSE_FAILED, where, "the node hierarchy has a cycle at /nodes/" + std::to_string(i));
  }
  return tree;
}

Skeleton buildSkeleton(const tinygltf::Model& model, const NodeTree& tree, const std::string& where,
                       std::vector<int>* joint_of_node, std::vector<Eigen::Affine3d>* skin_placement) {
  const int node_count = static_cast<int>(model.nodes.size());
  // Each skin's bind space is mapped to the scene by G = world(root joint at rest) * IBM(root joint):
  // the skinned vertex at rest is sum_j w_j * world_j * IBM_j * v, which is G * v wherever the rest
  // pose is the bind pose. The root joint is used because files whose rest pose is an animation frame
  // (RobotExpressive, the Quaternius exports) still keep their root at the bind pose.
  std::vector<Eigen::Affine3d> skin_to_world(model.skins.size(), Eigen::Affine3d::Identity());
  for (size_t s = 0; s < model.skins.size(); ++s) {
    const tinygltf::Skin& skin = model.skins[s];
    if (skin.joints.empty() || skin.inverseBindMatrices < 0) continue;
    std::vector<char> in_skin(node_count, 0);
    for (int node : skin.joints) {
      if (node >= 0 && node < node_count) in_skin[node] = 1;
    }
    for (size_t k = 0; k < skin.joints.size(); ++k) {
      int node = skin.joints[k];
      if (node < 0 || node >= node_count) break;  // reported below
      int ancestor = tree.parent[node];
      while (ancestor >= 0 && !in_skin[ancestor]) ancestor = tree.parent[ancestor];
      if (ancestor >= 0) continue;
      AccessorData ibm = readAccessor(model, skin.inverseBindMatrices, where);
      if (ibm.components != 16 || ibm.count <= static_cast<int>(k)) break;  // reported below
      Eigen::Matrix4d inverse_bind;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) inverse_bind(r, c) = ibm.values[k * 16 + c * 4 + r];
      skin_to_world[s] = tree.world[node] * Eigen::Affine3d(inverse_bind);
      break;
    }
  }
  // Bind pose of each joint node, from the first skin that lists it.
  std::vector<char> is_joint(node_count, 0);
  std::vector<Eigen::Affine3d> bind(node_count, Eigen::Affine3d::Identity());
  for (size_t s = 0; s < model.skins.size(); ++s) {
    const tinygltf::Skin& skin = model.skins[s];
    std::string skin_where = "/skins/" + std::to_string(s);
    AccessorData ibm;
    if (skin.inverseBindMatrices >= 0) {
      ibm = readAccessor(model, skin.inverseBindMatrices, where);
      if (ibm.components != 16 || ibm.count < static_cast<int>(skin.joints.size()))
        fail(errc::GLTF_SKIN_INVALID, where, skin_where + "/inverseBindMatrices must hold one MAT4 per joint");
    }
    for (size_t k = 0; k < skin.joints.size(); ++k) {
      int node = skin.joints[k];
      if (node < 0 || node >= node_count)
        fail(errc::GLTF_SKIN_INVALID, where, skin_where + "/joints/" + std::to_string(k) + " is not a node");
      if (is_joint[node]) continue;
      is_joint[node] = 1;
      Eigen::Matrix4d inverse_bind = Eigen::Matrix4d::Identity();
      if (skin.inverseBindMatrices >= 0) {
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) inverse_bind(r, c) = ibm.values[k * 16 + c * 4 + r];
      }
      if (std::abs(inverse_bind.determinant()) < 1e-30)
        fail(errc::GLTF_SKIN_INVALID, where, skin_where + "/inverseBindMatrices/" + std::to_string(k) + " is singular");
      bind[node] = skin_to_world[s] * Eigen::Affine3d(inverse_bind.inverse());
      // A zero scale on a node above the skin (or a huge one) collapses or overflows the bind transform;
      // the pose code splits it into a rotation and a scale and needs every axis to have a length.
      if (!bind[node].matrix().allFinite() || !(std::abs(bind[node].linear().determinant()) >= 1e-30))
        fail(errc::GLTF_SKIN_INVALID, where, skin_where + "/joints/" + std::to_string(k) +
                                             ": its bind transform (inverse bind matrix and the nodes above the skin) is degenerate");
    }
  }
  *skin_placement = skin_to_world;
  Skeleton skeleton;
  joint_of_node->assign(node_count, -1);
  for (int node : tree.dfs_order) {
    if (!is_joint[node]) continue;
    int joint = skeleton.size();
    (*joint_of_node)[node] = joint;
    int ancestor = tree.parent[node];
    while (ancestor >= 0 && !is_joint[ancestor]) ancestor = tree.parent[ancestor];
    skeleton.names.push_back(model.nodes[node].name.empty() ? "node" + std::to_string(node) : model.nodes[node].name);
    skeleton.parents.push_back(ancestor >= 0 ? (*joint_of_node)[ancestor] : -1);
    skeleton.nodes.push_back(node);
    skeleton.bind_world.push_back(bind[node]);
    skeleton.rest_local.push_back(nodeTrs(model.nodes[node]));
    // Root joints compose into their parent node; joints under a non-joint node inside the skeleton
    // (rare) are treated the same way, with that node's rest world transform.
    int direct_parent = tree.parent[node];
    Eigen::Affine3d parent_world = direct_parent >= 0 ? tree.world[direct_parent] : Eigen::Affine3d::Identity();
    if (ancestor >= 0 && direct_parent != ancestor) {
      // Fold the non-joint nodes between the joint and its joint ancestor into the local transform.
      Eigen::Affine3d between = tree.world[ancestor].inverse() * parent_world;
      Eigen::Affine3d local = between * skeleton.rest_local.back().matrix();
      Eigen::Matrix3d rotation, scaling;
      local.computeRotationScaling(&rotation, &scaling);
      skeleton.rest_local.back() = Trs{local.translation(), Eigen::Quaterniond(rotation), scaling.diagonal()};
    }
    skeleton.root_parent_world.push_back(ancestor >= 0 ? Eigen::Affine3d::Identity() : parent_world);
  }
  return skeleton;
}

std::vector<std::array<int, 3>> readTriangles(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                                              int vertex_count, const std::string& where) {
  std::vector<int> indices;
  if (primitive.indices >= 0) {
    AccessorData data = readAccessor(model, primitive.indices, where);
    indices.reserve(data.values.size());
    for (double v : data.values) {
      if (v < 0 || v >= vertex_count) fail(errc::GLTF_ACCESSOR_INVALID, where, "a triangle index is out of range");
      indices.push_back(static_cast<int>(v));
    }
  } else {
    for (int i = 0; i < vertex_count; ++i) indices.push_back(i);
  }
  std::vector<std::array<int, 3>> triangles;
  int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
  // At its final size: grown by push_back the mesh's triangles kept up to twice their bytes for the
  // whole bake.
  triangles.reserve(mode == TINYGLTF_MODE_TRIANGLES ? indices.size() / 3 : indices.size());
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    for (size_t i = 0; i + 2 < indices.size(); i += 3) triangles.push_back({indices[i], indices[i + 1], indices[i + 2]});
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < indices.size(); ++i) {
      if (i % 2 == 0) triangles.push_back({indices[i], indices[i + 1], indices[i + 2]});
      else triangles.push_back({indices[i + 1], indices[i], indices[i + 2]});
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < indices.size(); ++i) triangles.push_back({indices[0], indices[i], indices[i + 1]});
  }
  return triangles;
}

void readMeshes(const tinygltf::Model& model, const NodeTree& tree, const Skeleton& skeleton,
                const std::vector<int>& joint_of_node, const std::vector<Eigen::Affine3d>& skin_placement,
                const std::string& where, Character* character) {
  for (int node_index : tree.dfs_order) {
    const tinygltf::Node& node = model.nodes[node_index];
    if (node.mesh < 0) continue;
    if (node.mesh >= static_cast<int>(model.meshes.size()))
      fail(errc::GLTF_PARSE_FAILED, where, "/nodes/" + std::to_string(node_index) + " refers to a missing mesh");
    const tinygltf::Mesh& mesh = model.meshes[node.mesh];
    const tinygltf::Skin* skin =
        node.skin >= 0 && node.skin < static_cast<int>(model.skins.size()) ? &model.skins[node.skin] : nullptr;
    int rigid_joint = -1;
    if (!skin) {
      for (int a = node_index; a >= 0 && rigid_joint < 0; a = tree.parent[a]) rigid_joint = joint_of_node[a];
    }
    // Rigid parts follow their joint from the rest pose to the bind pose.
    Eigen::Affine3d to_world = tree.world[node_index];
    if (rigid_joint >= 0) {
      to_world = skeleton.bind_world[rigid_joint] * tree.world[skeleton.nodes[rigid_joint]].inverse() * tree.world[node_index];
    }
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& primitive = mesh.primitives[p];
      int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
        continue;
      auto position_it = primitive.attributes.find("POSITION");
      if (position_it == primitive.attributes.end()) continue;
      MeshPart part;
      part.name = mesh.name.empty() ? node.name : mesh.name;
      part.gltf_mesh = node.mesh;
      part.gltf_primitive = static_cast<int>(p);
      part.gltf_node = node_index;
      part.skinned = skin != nullptr;
      if (skin) {
        part.gltf_skin = node.skin;
        for (int joint_node : skin->joints) part.skin_joints.push_back(joint_of_node[joint_node]);
      }
      part.rigid_joint = rigid_joint;
      AccessorData positions = readAccessor(model, position_it->second, where);
      if (positions.components != 3) fail(errc::GLTF_ACCESSOR_INVALID, where, "POSITION must be VEC3");
      Eigen::Affine3d placement = to_world;
      if (skin) {
        // Skinned vertices live in bind space (glTF ignores the mesh node's own transform).
        placement = skin_placement[node.skin];
      }
      part.positions.resize(positions.count);
      for (int v = 0; v < positions.count; ++v) {
        Eigen::Vector3d local(positions.values[v * 3], positions.values[v * 3 + 1], positions.values[v * 3 + 2]);
        part.positions[v] = placement * local;
      }
      part.triangles = readTriangles(model, primitive, positions.count, where);
      if (skin) {
        for (int set = 0;; ++set) {
          auto joints_it = primitive.attributes.find("JOINTS_" + std::to_string(set));
          auto weights_it = primitive.attributes.find("WEIGHTS_" + std::to_string(set));
          if (joints_it == primitive.attributes.end() || weights_it == primitive.attributes.end()) break;
          part.influences_per_vertex += 4;
        }
        const int slots = part.influences_per_vertex;
        part.joints.assign(static_cast<size_t>(positions.count) * slots, 0);
        part.weights.assign(static_cast<size_t>(positions.count) * slots, 0.0);
        for (int set = 0; set * 4 < slots; ++set) {
          AccessorData joints = readAccessor(model, primitive.attributes.at("JOINTS_" + std::to_string(set)), where);
          AccessorData weights = readAccessor(model, primitive.attributes.at("WEIGHTS_" + std::to_string(set)), where);
          if (joints.components != 4 || weights.components != 4 || joints.count != positions.count ||
              weights.count != positions.count)
            fail(errc::GLTF_ACCESSOR_INVALID, where, "JOINTS_/WEIGHTS_ must be VEC4 with one element per vertex");
          for (int v = 0; v < positions.count; ++v) {
            for (int k = 0; k < 4; ++k) {
              double weight = weights.values[v * 4 + k];
              int skin_joint = static_cast<int>(joints.values[v * 4 + k]);
              size_t slot = static_cast<size_t>(v) * slots + set * 4 + k;
              if (weight == 0.0) continue;
              if (skin_joint < 0 || skin_joint >= static_cast<int>(skin->joints.size()))
                fail(errc::GLTF_ACCESSOR_INVALID, where, "a JOINTS_ index is outside the skin's joint list");
              part.joints[slot] = joint_of_node[skin->joints[skin_joint]];
              part.weights[slot] = weight;
            }
          }
        }
      }
      character->meshes.push_back(std::move(part));
    }
  }
}

Interpolation interpolationOf(const std::string& name) {
  if (name == "STEP") return Interpolation::kStep;
  if (name == "CUBICSPLINE") return Interpolation::kCubicSpline;
  return Interpolation::kLinear;
}

void readClips(const tinygltf::Model& model, const std::vector<int>& joint_of_node, const std::string& where,
               Character* character) {
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Animation& animation = model.animations[a];
    Clip clip;
    clip.name = animation.name.empty() ? "animation" + std::to_string(a) : animation.name;
    clip.gltf_animation = static_cast<int>(a);
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
      if (channel.target_node < 0 || channel.target_node >= static_cast<int>(joint_of_node.size())) continue;
      int joint = joint_of_node[channel.target_node];
      if (joint < 0) continue;
      Track track;
      track.joint = joint;
      if (channel.target_path == "translation") track.path = AnimatedPath::kTranslation;
      else if (channel.target_path == "rotation") track.path = AnimatedPath::kRotation;
      else if (channel.target_path == "scale") track.path = AnimatedPath::kScale;
      else continue;
      if (channel.sampler < 0 || channel.sampler >= static_cast<int>(animation.samplers.size()))
        fail(errc::GLTF_PARSE_FAILED, where, "/animations/" + std::to_string(a) + " has a channel without a sampler");
      const tinygltf::AnimationSampler& sampler = animation.samplers[channel.sampler];
      track.interpolation = interpolationOf(sampler.interpolation);
      AccessorData input = readAccessor(model, sampler.input, where);
      AccessorData output = readAccessor(model, sampler.output, where);
      int width = track.path == AnimatedPath::kRotation ? 4 : 3;
      int per_key = track.interpolation == Interpolation::kCubicSpline ? 3 : 1;
      if (input.components != 1 || output.components != width || output.count != input.count * per_key)
        fail(errc::GLTF_ACCESSOR_INVALID, where,
             "/animations/" + std::to_string(a) + " sampler " + std::to_string(channel.sampler) +
                 " has input/output counts that do not match");
      track.times = input.values;
      track.values = output.values;
      if (!track.times.empty()) clip.duration = std::max(clip.duration, track.times.back());
      clip.tracks.push_back(std::move(track));
    }
    character->clips.push_back(std::move(clip));
  }
}

void readVrmHumanoid(const tinygltf::Model& model, const std::vector<int>& joint_of_node, Character* character) {
  auto jointOf = [&](int node) { return node >= 0 && node < static_cast<int>(joint_of_node.size()) ? joint_of_node[node] : -1; };
  auto vrm1 = model.extensions.find("VRMC_vrm");
  if (vrm1 != model.extensions.end()) {
    character->vrm_version = "1.0";
    const tinygltf::Value& bones = gltfMember(gltfMember(vrm1->second, "humanoid"), "humanBones");
    if (bones.IsObject()) {
      for (const std::string& key : bones.Keys()) {
        const tinygltf::Value& node = gltfMember(bones.Get(key), "node");
        if (node.IsNumber() || node.IsInt()) {
          int joint = jointOf(node.GetNumberAsInt());
          if (joint >= 0) character->vrm_humanoid[key] = joint;
        }
      }
    }
    return;
  }
  auto vrm0 = model.extensions.find("VRM");
  if (vrm0 != model.extensions.end()) {
    character->vrm_version = "0.x";
    const tinygltf::Value& bones = gltfMember(gltfMember(vrm0->second, "humanoid"), "humanBones");
    if (bones.IsArray()) {
      for (size_t i = 0; i < bones.ArrayLen(); ++i) {
        const tinygltf::Value& bone = bones.Get(static_cast<int>(i));
        const tinygltf::Value& name = gltfMember(bone, "bone");
        const tinygltf::Value& node = gltfMember(bone, "node");
        if (name.IsString() && (node.IsNumber() || node.IsInt())) {
          int joint = jointOf(node.GetNumberAsInt());
          if (joint >= 0) character->vrm_humanoid[name.Get<std::string>()] = joint;
        }
      }
    }
  }
}

// tinygltf grows its lists by push_back, to up to twice their size; the model lives through the
// whole bake (the writer starts from it), so they are cut to size: heap peak 12.27 -> 11.79 MB on
// Quaternius Cyberpunk (22 clips, 530 accessors).
void shrinkModelLists(tinygltf::Model* model) {
  model->accessors.shrink_to_fit();
  model->bufferViews.shrink_to_fit();
  model->nodes.shrink_to_fit();
  model->meshes.shrink_to_fit();
  for (tinygltf::Animation& animation : model->animations) {
    animation.channels.shrink_to_fit();
    animation.samplers.shrink_to_fit();
  }
  model->animations.shrink_to_fit();
}

// What is wrong with a GLB's container (glTF 2.0, "GLB File Format Specification": a 12-byte header
// of magic, version and total length, then a JSON chunk and an optional BIN chunk, each an 8-byte
// header of length and type before its data), or "" when it holds together. tinygltf says only
// "Invalid glTF binary." for all of these; a cut-off download is the usual cause, so the lengths are
// named.
std::string glbContainerProblem(const std::string& bytes) {
  auto word = [&](size_t at) {
    uint32_t value = 0;
    std::memcpy(&value, bytes.data() + at, sizeof(value));
    return value;
  };
  const size_t size = bytes.size();
  if (size < 12) return "truncated GLB: " + std::to_string(size) + " bytes, shorter than its 12-byte header";
  if (word(4) != 2) return "GLB version " + std::to_string(word(4)) + " (rigbake reads glTF 2.0, GLB version 2)";
  const size_t length = word(8);
  if (length > size)
    return "truncated GLB: its header gives " + std::to_string(length) + " bytes, the file has " + std::to_string(size);
  if (length < 20) return "GLB of " + std::to_string(length) + " bytes has no room for its JSON chunk";
  if (bytes.compare(16, 4, "JSON") != 0) return "the GLB's first chunk is not JSON";
  const size_t json_end = 20 + static_cast<size_t>(word(12));
  if (json_end > length)
    return "truncated GLB: its JSON chunk ends at byte " + std::to_string(json_end) + " of " + std::to_string(length);
  if (json_end + 8 <= length) {
    const size_t bin_end = json_end + 8 + static_cast<size_t>(word(json_end));
    if (bin_end > length)
      return "truncated GLB: its second chunk ends at byte " + std::to_string(bin_end) + " of " + std::to_string(length);
  }
  return "";
}

// The Character of a model, whether a glTF file held it or formats/fbx_to_gltf.cpp built it.
LoadedCharacter characterOf(std::shared_ptr<GltfDocument> document, const std::string& path) {
  const tinygltf::Model& model = document->model;
  if (model.skins.empty()) fail(errc::GLTF_NO_SKIN, path, "the file has no skin (a skinned character is needed)");

  NodeTree tree = buildNodeTree(model, path);
  std::vector<int> joint_of_node;
  std::vector<Eigen::Affine3d> skin_placement;
  LoadedCharacter loaded;
  Character& character = loaded.character;
  character.source = path;
  character.skeleton = buildSkeleton(model, tree, path, &joint_of_node, &skin_placement);
  readMeshes(model, tree, character.skeleton, joint_of_node, skin_placement, path, &character);
  character.skin_placement = skin_placement;
  readClips(model, joint_of_node, path, &character);
  readVrmHumanoid(model, joint_of_node, &character);
  loaded.document = std::move(document);
  return loaded;
}

// Makes the model the VRM version asked for (LoadOptions), returning what the conversion says.
std::vector<std::string> applyVrmTarget(tinygltf::Model* model, VrmTarget target, const std::string& path) {
  if (target == VrmTarget::kAsIs) return {};
  const bool vrm0 = model->extensions.count("VRM") > 0, vrm1 = model->extensions.count("VRMC_vrm") > 0;
  // The target in words, not as a flag: bake's --vrm and build's manifest key "vrm" both ask for it.
  const char* version = target == VrmTarget::kVrm1 ? "VRM 1.0" : "VRM 0.x";
  if (!vrm0 && !vrm1)
    fail(errc::VRM_CONVERSION_UNSUPPORTED, path,
         std::string("is not a VRM (no VRM or VRMC_vrm extension), so there is no avatar to write as ") + version);
  if (target == VrmTarget::kVrm0 && vrm1)
    fail(errc::VRM_CONVERSION_UNSUPPORTED, path, "is a VRM 1.0 asked to be VRM 0.x; rigbake converts VRM 0.x to 1.0, not back");
  if (target == VrmTarget::kVrm1 && vrm0 && !vrm1) return convertVrm0ToVrm1(model, path);
  return {};
}

}  // namespace

LoadedCharacter loadCharacter(const std::string& path, const LoadOptions& options) {
  if (isFbxPath(path)) {
    auto document = std::make_shared<GltfDocument>();
    FbxConversion conversion = convertFbxToGltf(path, &document->model);
    shrinkModelLists(&document->model);
    applyVrmTarget(&document->model, options.vrm, path);  // an FBX is no VRM: refused
    LoadedCharacter loaded = characterOf(std::move(document), path);
    loaded.notes = std::move(conversion.notes);
    return loaded;
  }
  std::string bytes = readFile(path);
  if (bytes.compare(0, 4, "glTF") == 0) {
    const std::string problem = glbContainerProblem(bytes);
    if (!problem.empty()) fail(errc::GLTF_PARSE_FAILED, path, problem);
  }
  prepareCompressedGltf(&bytes);
  auto document = std::make_shared<GltfDocument>();
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keepImageBytes, nullptr);
  std::string err, warn;
  bool ok = false;
  if (bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0) {
    ok = loader.LoadBinaryFromMemory(&document->model, &err, &warn,
                                     reinterpret_cast<const unsigned char*>(bytes.data()),
                                     static_cast<unsigned int>(bytes.size()), directoryOf(path));
  } else {
    size_t first = bytes.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
    if (first == std::string::npos || bytes[first] != '{')
      fail(errc::GLTF_PARSE_FAILED, path, "not a glTF file (neither GLB magic 'glTF' nor a JSON object)");
    ok = loader.LoadASCIIFromString(&document->model, &err, &warn, bytes.data(),
                                    static_cast<unsigned int>(bytes.size()), directoryOf(path));
  }
  if (!ok) {
    requireHonouredExtensions(requiredExtensionsOf(bytes), path);
    fail(errc::GLTF_PARSE_FAILED, path, firstLine(err));
  }
  requireHonouredExtensions(document->model.extensionsRequired, path);
  decompressGltf(&document->model, path);
  shrinkModelLists(&document->model);
  std::vector<std::string> notes = applyVrmTarget(&document->model, options.vrm, path);
  LoadedCharacter loaded = characterOf(std::move(document), path);
  loaded.notes = std::move(notes);
  return loaded;
}

}  // namespace rigbake
