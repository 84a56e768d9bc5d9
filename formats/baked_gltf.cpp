// Decoding a baked glTF for validation. Skinning attributes follow glTF 2.0 3.7.3.3 (JOINTS_n as
// UNSIGNED_BYTE/UNSIGNED_SHORT VEC4, WEIGHTS_n as FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT VEC4);
// the packed carrier is section 5 of docs/packed-influences.md: 32-bit weight words carried as
// UNSIGNED_SHORT pairs (low half first) and index records cut into VEC4/VEC2 pieces, so concatenating
// every piece's little-endian bytes in attribute order gives the layout-1 record back.
#include "formats/baked_gltf.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/error.h"
#include "formats/gltf_accessor.h"
#include "formats/gltf_json_value.h"
#include "formats/muscle_rig_extension.h"

namespace rigbake {
namespace {

std::string primitivePointer(int mesh, int primitive) {
  return "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(primitive);
}

// Reads an accessor, or records why it cannot be read and returns false.
bool tryRead(const tinygltf::Model& model, int accessor, const std::string& pointer, AccessorData* data,
             std::vector<FileIssue>* issues) {
  try {
    *data = readAccessor(model, accessor, pointer);
    return true;
  } catch (const Error& e) {
    issues->push_back({pointer, e.what()});
    return false;
  }
}

int componentBytes(int component_type) {
  if (component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) return 1;
  if (component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) return 2;
  return 0;
}

void readStandardInfluences(const tinygltf::Model& model, const tinygltf::Primitive& primitive, int vertex_count,
                            FileSkinAttributes* skin, std::vector<FileIssue>* issues) {
  int sets = 0;
  while (primitive.attributes.count("JOINTS_" + std::to_string(sets)) &&
         primitive.attributes.count("WEIGHTS_" + std::to_string(sets)))
    ++sets;
  for (const auto& [semantic, accessor] : primitive.attributes) {
    for (const char* prefix : {"JOINTS_", "WEIGHTS_"}) {
      if (semantic.rfind(prefix, 0) != 0) continue;
      const std::string number = semantic.substr(std::string(prefix).size());
      const bool numbered = !number.empty() && number.size() < 6 &&
                            number.find_first_not_of("0123456789") == std::string::npos;
      if (numbered && std::stoi(number) >= sets)
        issues->push_back({skin->pointer + "/attributes/" + semantic, semantic + " has no matching JOINTS_n/WEIGHTS_n partner"});
    }
    (void)accessor;
  }
  skin->slots = 4 * sets;
  skin->joints.assign(static_cast<size_t>(vertex_count) * skin->slots, 0);
  skin->weights.assign(static_cast<size_t>(vertex_count) * skin->slots, 0.0);
  for (int set = 0; set < sets; ++set) {
    const std::string joints_name = "JOINTS_" + std::to_string(set), weights_name = "WEIGHTS_" + std::to_string(set);
    const int joints_index = primitive.attributes.at(joints_name), weights_index = primitive.attributes.at(weights_name);
    const std::string joints_pointer = skin->pointer + "/attributes/" + joints_name;
    const std::string weights_pointer = skin->pointer + "/attributes/" + weights_name;
    if (joints_index >= 0 && joints_index < static_cast<int>(model.accessors.size())) {
      const tinygltf::Accessor& a = model.accessors[joints_index];
      if (componentBytes(a.componentType) == 0 || a.normalized)
        issues->push_back({joints_pointer, joints_name + " must be UNSIGNED_BYTE or UNSIGNED_SHORT, not normalized"});
    }
    if (weights_index >= 0 && weights_index < static_cast<int>(model.accessors.size())) {
      const tinygltf::Accessor& a = model.accessors[weights_index];
      const bool float_weights = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && !a.normalized;
      const bool normalized_weights = componentBytes(a.componentType) != 0 && a.normalized;
      if (!float_weights && !normalized_weights)
        issues->push_back({weights_pointer, weights_name + " must be FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT"});
    }
    AccessorData joints, weights;
    if (!tryRead(model, joints_index, joints_pointer, &joints, issues) ||
        !tryRead(model, weights_index, weights_pointer, &weights, issues))
      continue;
    if (joints.components != 4 || joints.count != vertex_count) {
      issues->push_back({joints_pointer, joints_name + " must be VEC4 with one element per vertex (" +
                                             std::to_string(vertex_count) + ")"});
      continue;
    }
    if (weights.components != 4 || weights.count != vertex_count) {
      issues->push_back({weights_pointer, weights_name + " must be VEC4 with one element per vertex (" +
                                              std::to_string(vertex_count) + ")"});
      continue;
    }
    for (int v = 0; v < vertex_count; ++v) {
      for (int k = 0; k < 4; ++k) {
        const size_t slot = static_cast<size_t>(v) * skin->slots + set * 4 + k;
        skin->joints[slot] = static_cast<int>(joints.values[v * 4 + k]);
        skin->weights[slot] = weights.values[v * 4 + k];
      }
    }
  }
}

// Concatenates the little-endian bytes of PREFIX0, PREFIX1, ... per vertex. Returns the bytes per
// vertex (0 when there is no such attribute) and the common component size in *component_size.
int readCarrier(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& prefix,
                const std::string& pointer, int vertex_count, std::vector<std::uint8_t>* bytes, int* component_size,
                std::vector<FileIssue>* issues) {
  std::vector<AccessorData> pieces;
  int stride = 0;
  *component_size = 0;
  for (int i = 0;; ++i) {
    auto it = primitive.attributes.find(prefix + std::to_string(i));
    if (it == primitive.attributes.end()) break;
    const std::string where = pointer + "/attributes/" + it->first;
    if (it->second < 0 || it->second >= static_cast<int>(model.accessors.size())) {
      issues->push_back({where, it->first + " refers to a missing accessor"});
      return -1;
    }
    const tinygltf::Accessor& accessor = model.accessors[it->second];
    const int size = componentBytes(accessor.componentType);
    if (size == 0 || accessor.normalized || (*component_size != 0 && size != *component_size)) {
      issues->push_back({where, it->first + " must be UNSIGNED_BYTE or UNSIGNED_SHORT like its siblings, not normalized"});
      return -1;
    }
    *component_size = size;
    AccessorData data;
    if (!tryRead(model, it->second, where, &data, issues)) return -1;
    if (data.count != vertex_count) {
      issues->push_back({where, it->first + " has " + std::to_string(data.count) + " elements for " +
                                    std::to_string(vertex_count) + " vertices"});
      return -1;
    }
    stride += data.components * size;
    pieces.push_back(std::move(data));
  }
  bytes->clear();
  bytes->reserve(static_cast<size_t>(stride) * vertex_count);
  for (int v = 0; v < vertex_count; ++v) {
    for (const AccessorData& piece : pieces) {
      for (int c = 0; c < piece.components; ++c) {
        const auto value = static_cast<std::uint32_t>(piece.values[static_cast<size_t>(v) * piece.components + c]);
        for (int b = 0; b < *component_size; ++b) bytes->push_back(static_cast<std::uint8_t>((value >> (8 * b)) & 0xffu));
      }
    }
  }
  return stride;
}

void readPackedInfluences(const tinygltf::Model& model, const tinygltf::Primitive& primitive, int vertex_count,
                          FileSkinAttributes* skin, std::vector<FileIssue>* issues) {
  std::vector<std::uint8_t> weight_bytes, index_bytes;
  int weight_component = 0, index_component = 0;
  const int weight_stride = readCarrier(model, primitive, "_RIGBAKE_PACKED_WEIGHTS_", skin->pointer, vertex_count,
                                        &weight_bytes, &weight_component, issues);
  const int index_stride = readCarrier(model, primitive, "_RIGBAKE_PACKED_JOINTS_", skin->pointer, vertex_count,
                                       &index_bytes, &index_component, issues);
  if (weight_stride <= 0 && index_stride <= 0) return;
  const std::string where = skin->pointer + "/attributes/_RIGBAKE_PACKED_WEIGHTS_0";
  if (weight_stride <= 0 || index_stride <= 0) {
    if (weight_stride == 0 || index_stride == 0)
      issues->push_back({where, "packed weights and packed joints must both be present"});
    return;
  }
  // W words per vertex hold N - 1 = 3W weights.
  const int words = weight_stride / 4;
  const int influences = 3 * words + 1;
  if (weight_component != 2 || weight_stride % 4 != 0 || !isPackedInfluenceCount(influences) ||
      index_stride != packedIndexStride(influences, index_component)) {
    issues->push_back({where, "packed attributes do not form layout version 1 (" + std::to_string(weight_stride) +
                                  " weight bytes and " + std::to_string(index_stride) + " index bytes per vertex)"});
    return;
  }
  PackedInfluences packed;
  packed.influences = influences;
  packed.index_bytes = index_component;
  packed.joint_count = skin->skin_joint_count;
  packed.vertex_count = vertex_count;
  packed.weight_words.resize(static_cast<size_t>(words) * vertex_count);
  for (size_t w = 0; w < packed.weight_words.size(); ++w) {
    std::uint32_t word = 0;
    for (int b = 0; b < 4; ++b) word |= static_cast<std::uint32_t>(weight_bytes[w * 4 + b]) << (8 * b);
    packed.weight_words[w] = word;
  }
  packed.indices = std::move(index_bytes);
  const std::string problem = packedInfluencesProblem(packed);
  // An index out of range is JOINT_INDEX_IN_RANGE's to report; every other problem is structural.
  if (!problem.empty() && problem.find("names joint") == std::string::npos) {
    issues->push_back({where, "packed influences break layout version 1: " + problem});
    return;
  }
  skin->has_packed = true;
  skin->packed = std::move(packed);
}

std::vector<double> numbersOf(const tinygltf::Value& array) {
  std::vector<double> values;
  if (!array.IsArray()) return values;
  for (size_t i = 0; i < array.ArrayLen(); ++i) {
    const tinygltf::Value& item = array.Get(static_cast<int>(i));
    values.push_back(item.IsNumber() || item.IsInt() ? item.GetNumberAsDouble() : std::nan(""));
  }
  return values;
}

// The jiggle angles the bake recorded per clip (formats/gltf_bake.cpp writeJiggles).
void readJiggles(const tinygltf::Model& model, BakedFileData* data) {
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Value& block = gltfMember(model.animations[a].extras, "rigbake");
    const tinygltf::Value& jiggles = gltfMember(block, "jiggle");
    if (!jiggles.IsArray()) continue;
    ClipJiggles clip;
    clip.clip = model.animations[a].name.empty() ? "animation" + std::to_string(a) : model.animations[a].name;
    clip.pointer = "/animations/" + std::to_string(a) + "/extras/rigbake";
    clip.times = numbersOf(gltfMember(block, "times"));
    for (size_t j = 0; j < jiggles.ArrayLen(); ++j) {
      const tinygltf::Value& entry = jiggles.Get(static_cast<int>(j));
      JiggleSeries series;
      const tinygltf::Value& joint = gltfMember(entry, "joint");
      const tinygltf::Value& host = gltfMember(entry, "host");
      series.joint = joint.IsString() ? joint.Get<std::string>() : "";
      series.host = host.IsString() ? host.Get<std::string>() : "";
      series.angle_deg = numbersOf(gltfMember(entry, "angle_deg"));
      series.clamp_deg = numbersOf(gltfMember(entry, "clamp_deg"));
      if (series.joint.empty() || series.angle_deg.size() != clip.times.size() ||
          series.clamp_deg.size() != clip.times.size()) {
        data->structure.push_back({clip.pointer + "/jiggle/" + std::to_string(j),
                                   "needs a joint name and one angle_deg and clamp_deg per entry of times"});
        continue;
      }
      clip.jiggles.push_back(std::move(series));
    }
    data->jiggles.push_back(std::move(clip));
  }
}

void readMuscleNodes(const tinygltf::Model& model, const Character& character, BakedFileData* data) {
  static const std::map<std::string, std::string> kSuffix = {
      {"base", "_muscleBase"}, {"tip", "_muscleTip"}, {"driver", "_muscleDriver"}, {"skinned", "_muscleSkinned"}};
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tinygltf::Value& block = gltfMember(model.nodes[n].extras, "rigbake");
    if (!block.IsObject()) continue;
    const std::string pointer = "/nodes/" + std::to_string(n) + "/extras/rigbake";
    FileMuscleNode node;
    node.node = static_cast<int>(n);
    node.name = model.nodes[n].name;
    auto text = [&](const char* key, std::string* out) {
      const tinygltf::Value& value = gltfMember(block, key);
      if (value.IsString()) *out = value.Get<std::string>();
      else data->structure.push_back({pointer + "/" + key, std::string(key) + " must be a string"});
    };
    auto number = [&](const char* key, double* out) {
      const tinygltf::Value& value = gltfMember(block, key);
      if (value.IsNumber() || value.IsInt()) *out = value.GetNumberAsDouble();
      else data->structure.push_back({pointer + "/" + key, std::string(key) + " must be a number"});
    };
    text("muscle", &node.muscle);
    text("role", &node.role);
    text("origin_joint", &node.origin_joint);
    text("insertion_joint", &node.insertion_joint);
    // carrier_joint: the joint a skinned node takes its weight from (bakes before it was written have none).
    if (gltfMember(block, "carrier_joint").IsString()) node.carrier_joint = gltfMember(block, "carrier_joint").Get<std::string>();
    number("compression", &node.compression);
    number("stretch", &node.stretch);
    auto suffix = kSuffix.find(node.role);
    if (suffix == kSuffix.end()) {
      data->structure.push_back({pointer + "/role", "role '" + node.role + "' is not base, tip, driver or skinned"});
    } else if (node.name != node.muscle + suffix->second) {
      data->structure.push_back({"/nodes/" + std::to_string(n) + "/name",
                                 "'" + node.name + "' should be '" + node.muscle + suffix->second + "'"});
    }
    for (const std::string* joint : {&node.origin_joint, &node.insertion_joint, &node.carrier_joint}) {
      if (!joint->empty() && character.skeleton.find(*joint) < 0)
        data->structure.push_back({pointer, "attach joint '" + *joint + "' is not a joint of the skeleton"});
    }
    if (!(node.compression > 0.0 && node.compression <= 1.0 && node.stretch >= 1.0))
      data->structure.push_back({pointer, "needs 0 < compression <= 1 <= stretch"});
    data->muscle_nodes.push_back(node);
  }

  // Each muscle has its skinned joint, in every skin, and either all three helpers (base, tip, driver)
  // or none (bake --helper-joints). Without the RIGBAKE_muscle_rig extension nothing evaluates the
  // muscles at run time, so every clip must animate every muscle joint; with it, a joint that has
  // channels has all of them (muscle-motion "both").
  std::map<std::string, std::set<std::string>> roles;
  for (const FileMuscleNode& node : data->muscle_nodes) {
    if (!roles[node.muscle].insert(node.role).second)
      data->structure.push_back({"/nodes/" + std::to_string(node.node), node.muscle + " has two " + node.role + " joints"});
  }
  for (const auto& [muscle, present] : roles) {
    if (!present.count("skinned")) data->structure.push_back({"/nodes", muscle + " has no skinned joint node"});
    const int helpers = static_cast<int>(present.count("base") + present.count("tip") + present.count("driver"));
    if (helpers != 0 && helpers != 3)
      data->structure.push_back({"/nodes", muscle + " has " + std::to_string(helpers) + " of its 3 helper joints (base, tip, driver)"});
  }
  const bool runtime = model.extensions.count(kMuscleRigExtension) > 0;
  for (const FileMuscleNode& node : data->muscle_nodes) {
    if (node.role == "skinned") {
      for (size_t s = 0; s < model.skins.size(); ++s) {
        const auto& joints = model.skins[s].joints;
        if (std::find(joints.begin(), joints.end(), node.node) == joints.end())
          data->structure.push_back({"/skins/" + std::to_string(s) + "/joints", node.name + " is not in this skin"});
      }
    }
    for (size_t a = 0; a < model.animations.size(); ++a) {
      const tinygltf::Animation& animation = model.animations[a];
      if (animation.channels.empty()) continue;
      std::set<std::string> paths;
      for (const tinygltf::AnimationChannel& channel : animation.channels) {
        if (channel.target_node == node.node) paths.insert(channel.target_path);
      }
      if (runtime && paths.empty()) continue;
      std::vector<std::string> needed = {"translation", "rotation"};
      if (node.role == "skinned") needed.push_back("scale");
      for (const std::string& path : needed) {
        if (!paths.count(path))
          data->structure.push_back({"/animations/" + std::to_string(a) + "/channels",
                                     "no " + path + " channel for " + node.name});
      }
    }
  }
}

// Every node that is a muscle joint by name or by extras, and how many animations move it: what
// RIG_EXTENSION_MISSING weighs when a tool dropped the extension (issue 31).
void readMuscleJoints(const tinygltf::Model& model, BakedFileData* data) {
  static const char* kSuffixes[] = {"_muscleSkinned", "_muscleBase", "_muscleTip", "_muscleDriver"};
  auto endsWith = [](const std::string& text, const std::string& suffix) {
    return text.size() > suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  data->animations = static_cast<int>(model.animations.size());
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const std::string& name = model.nodes[n].name;
    bool muscle = gltfMember(model.nodes[n].extras, "rigbake").IsObject();
    for (const char* suffix : kSuffixes) muscle = muscle || endsWith(name, suffix);
    if (!muscle) continue;
    FileMuscleJoint joint;
    joint.node = static_cast<int>(n);
    joint.name = name;
    for (const tinygltf::Animation& animation : model.animations) {
      bool moves = false;
      for (const tinygltf::AnimationChannel& channel : animation.channels) moves = moves || channel.target_node == joint.node;
      joint.animations_moving_it += moves ? 1 : 0;
    }
    data->muscle_joints.push_back(std::move(joint));
  }
}

void readAnimationSamplers(const tinygltf::Model& model, BakedFileData* data) {
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Animation& animation = model.animations[a];
    for (size_t s = 0; s < animation.samplers.size(); ++s) {
      const tinygltf::AnimationSampler& sampler = animation.samplers[s];
      const std::string pointer = "/animations/" + std::to_string(a) + "/samplers/" + std::to_string(s);
      AccessorData input;
      if (!tryRead(model, sampler.input, pointer + "/input", &input, &data->structure)) continue;
      for (int i = 1; i < input.count; ++i) {
        if (!(input.values[i] > input.values[i - 1])) {
          data->structure.push_back({pointer + "/input", "key times must increase strictly (key " + std::to_string(i) + ")"});
          break;
        }
      }
    }
  }
}

}  // namespace

BakedFileData readBakedFileData(const LoadedCharacter& loaded) {
  const tinygltf::Model& model = modelOf(*loaded.document);
  const Character& character = loaded.character;
  BakedFileData data;
  for (size_t s = 0; s < model.skins.size(); ++s) {
    const tinygltf::Skin& skin = model.skins[s];
    if (skin.inverseBindMatrices < 0) continue;
    AccessorData ibm;
    const std::string pointer = "/skins/" + std::to_string(s) + "/inverseBindMatrices";
    if (tryRead(model, skin.inverseBindMatrices, pointer, &ibm, &data.structure) && ibm.count != static_cast<int>(skin.joints.size()))
      data.structure.push_back({pointer, std::to_string(ibm.count) + " matrices for " +
                                             std::to_string(skin.joints.size()) + " joints"});
  }
  readMuscleNodes(model, character, &data);
  readMuscleJoints(model, &data);
  readJiggles(model, &data);
  data.rig = readMuscleRigExtension(model, character);
  for (const std::string& problem : data.rig.problems) {
    const size_t colon = problem.find(": ");
    data.structure.push_back({problem.substr(0, colon), problem.substr(colon + 2)});
  }
  const bool baked = !data.muscle_nodes.empty();
  for (size_t p = 0; p < character.meshes.size(); ++p) {
    const MeshPart& part = character.meshes[p];
    if (!part.skinned) continue;
    const tinygltf::Primitive& primitive = model.meshes[part.gltf_mesh].primitives[part.gltf_primitive];
    FileSkinAttributes skin;
    skin.mesh_part = static_cast<int>(p);
    skin.pointer = primitivePointer(part.gltf_mesh, part.gltf_primitive);
    skin.skin_joint_count = static_cast<int>(part.skin_joints.size());
    const int vertex_count = static_cast<int>(part.positions.size());
    readStandardInfluences(model, primitive, vertex_count, &skin, &data.structure);
    readPackedInfluences(model, primitive, vertex_count, &skin, &data.structure);
    for (const auto& [semantic, accessor] : primitive.attributes) skin.carries_packed |= semantic.rfind("_RIGBAKE_PACKED_", 0) == 0;
    if (baked && !skin.has_packed && !primitive.attributes.count("_RIGBAKE_PACKED_WEIGHTS_0"))
      data.structure.push_back({skin.pointer + "/attributes", "a baked primitive has no _RIGBAKE_PACKED_* attributes"});
    if (skin.slots == 0) {
      data.structure.push_back({skin.pointer + "/attributes", "a skinned primitive has no JOINTS_0/WEIGHTS_0"});
      continue;
    }
    data.skins.push_back(std::move(skin));
  }
  readAnimationSamplers(model, &data);
  return data;
}

}  // namespace rigbake
