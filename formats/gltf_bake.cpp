#include "formats/gltf_bake.h"

#include <tiny_gltf.h>

#include <cstring>
#include <limits>
#include <set>

#include "core/error.h"
#include "formats/gltf_buffer.h"
#include "formats/gltf_write.h"
#include "formats/muscle_rig_extension.h"
#include "formats/vrm_node_constraint.h"
#include "formats/vrm_spring.h"
#include "pipeline/muscle_joint.h"

namespace rigbake {
namespace {

int gltfType(const std::string& type) {
  if (type == "SCALAR") return TINYGLTF_TYPE_SCALAR;
  if (type == "VEC2") return TINYGLTF_TYPE_VEC2;
  if (type == "VEC3") return TINYGLTF_TYPE_VEC3;
  return TINYGLTF_TYPE_VEC4;
}

std::vector<double> vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
std::vector<double> quat(const Eigen::Quaterniond& q) { return {q.x(), q.y(), q.z(), q.w()}; }

void appendMatrix(std::vector<float>* out, const Eigen::Matrix4d& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out->push_back(static_cast<float>(m(r, c)));
}

struct TrsKeys {
  std::vector<float> translations, rotations, scales;
};

TrsKeys trsKeys(const std::vector<Trs>& keys) {
  TrsKeys out;
  Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
  for (size_t t = 0; t < keys.size(); ++t) {
    Eigen::Quaterniond q = keys[t].rotation.normalized();
    // Keep consecutive keys in one hemisphere so that interpolation takes the short way.
    if (t > 0 && q.dot(previous) < 0) q.coeffs() = -q.coeffs();
    previous = q;
    for (int c = 0; c < 3; ++c) out.translations.push_back(static_cast<float>(keys[t].translation[c]));
    for (double c : quat(q)) out.rotations.push_back(static_cast<float>(c));
    for (int c = 0; c < 3; ++c) out.scales.push_back(static_cast<float>(keys[t].scale[c]));
  }
  return out;
}

tinygltf::Value numbers(const std::vector<double>& values) {
  tinygltf::Value::Array array;
  for (double v : values) array.push_back(tinygltf::Value(v));
  return tinygltf::Value(array);
}

// A skeleton joint's jiggle replaces that joint's channels in the clip: an existing channel's sampler
// is pointed at the jiggled keys (so no sampler is left unused), a missing path gets a new channel.
// The jiggle angles go into the animation's extras for the validation report's plots, since the
// animated (un-jiggled) direction they are measured from is no longer in the file.
void writeJiggles(const BakedClip& clip, const Skeleton& skeleton, int input, GltfBufferAppender* data,
                  tinygltf::Animation* animation) {
  if (clip.jiggles.empty()) return;
  tinygltf::Value::Array report;
  for (const JiggleTrack& track : clip.jiggles) {
    if (track.host == JiggleHost::kSkeletonJoint) {
      const int node = skeleton.nodes[track.joint];
      const TrsKeys keys = trsKeys(track.local);
      const std::pair<const char*, const std::vector<float>*> paths[] = {
          {"translation", &keys.translations}, {"rotation", &keys.rotations}, {"scale", &keys.scales}};
      for (const auto& [path, values] : paths) {
        const bool rotation = std::string(path) == "rotation";
        const int output = data->addFloats(*values, rotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, rotation ? 4 : 3);
        bool replaced = false;
        for (tinygltf::AnimationChannel& channel : animation->channels) {
          if (channel.target_node != node || channel.target_path != path) continue;
          tinygltf::AnimationSampler& sampler = animation->samplers[channel.sampler];
          sampler.input = input;
          sampler.output = output;
          sampler.interpolation = "LINEAR";
          replaced = true;
        }
        if (replaced) continue;
        addLinearChannel(input, output, node, path, animation);
      }
    }
    tinygltf::Value::Object entry;
    entry["joint"] = tinygltf::Value(track.name);
    entry["host"] = tinygltf::Value(std::string(track.host == JiggleHost::kMuscle ? "muscle" : "joint"));
    entry["angle_deg"] = numbers(track.angle_deg);
    entry["clamp_deg"] = numbers(track.clamp_deg);
    report.push_back(tinygltf::Value(entry));
  }
  tinygltf::Value::Object extras = animation->extras.IsObject() ? animation->extras.Get<tinygltf::Value::Object>()
                                                                 : tinygltf::Value::Object{};
  tinygltf::Value::Object rigbake;
  rigbake["times"] = numbers(clip.times);
  rigbake["jiggle"] = tinygltf::Value(report);
  extras["rigbake"] = tinygltf::Value(rigbake);
  animation->extras = tinygltf::Value(extras);
}

// bakedModel(), and the node of each of bake.joints in it (-1 for a joint not written).
tinygltf::Model bakedModelAndNodes(const GltfDocument& document, const Character& character, const BakeResult& bake,
                                   std::vector<int>* nodes_of_joints) {
  tinygltf::Model model = modelOf(document);
  const Skeleton& skeleton = character.skeleton;
  GltfBufferAppender data(&model);

  // Joint nodes, children of their attach joints: the skinned joints always, the helpers (base, tip,
  // driver) when asked for. node_of_joint[k] is -1 for a joint not written.
  std::vector<int> node_of_joint(bake.joints.size(), -1);
  for (size_t k = 0; k < bake.joints.size(); ++k) {
    const BakedJoint& joint = bake.joints[k];
    if (joint.role != MuscleJointRole::kSkinned && !bake.helper_joints) continue;
    tinygltf::Node node;
    node.name = joint.name;
    node.translation = vec(joint.rest_local.translation);
    node.rotation = quat(joint.rest_local.rotation.normalized());
    // A helper (base, tip, driver) is an unscaled frame, but under a scaled armature node (Quaternius
    // Cyberpunk's x100) its local transform must undo that scale, or its rest world in the file is
    // scaled too (found by the Blender add-on's test). Elsewhere its scale is 1 and is left out.
    const bool scaled = (joint.rest_local.scale - Eigen::Vector3d::Ones()).cwiseAbs().maxCoeff() > 1e-6;
    if (joint.role == MuscleJointRole::kSkinned || scaled) node.scale = vec(joint.rest_local.scale);
    const MusclePart& part = bake.muscles.parts[joint.muscle];
    static const char* kRoleNames[] = {"base", "tip", "driver", "skinned"};
    tinygltf::Value::Object description;
    description["muscle"] = tinygltf::Value(part.fullName());
    description["role"] = tinygltf::Value(std::string(kRoleNames[static_cast<int>(joint.role)]));
    description["origin_joint"] = tinygltf::Value(skeleton.names[part.origin.joint]);
    description["insertion_joint"] = tinygltf::Value(skeleton.names[part.insertion.joint]);
    description["carrier_joint"] = tinygltf::Value(skeleton.names[muscleCarrierJoint(part)]);
    if (part.kind != PartKind::kMuscle) description["kind"] = tinygltf::Value(std::string(partKindName(part.kind)));
    description["compression"] = tinygltf::Value(part.compression);
    description["stretch"] = tinygltf::Value(part.stretch);
    tinygltf::Value::Object extras;
    extras["rigbake"] = tinygltf::Value(description);
    node.extras = tinygltf::Value(extras);
    node_of_joint[k] = static_cast<int>(model.nodes.size());
    model.nodes.push_back(node);
    model.nodes[skeleton.nodes[joint.parent]].children.push_back(node_of_joint[k]);
  }

  // Skins: every skin gets every muscle's skinned joint, with its inverse bind matrix in the skin's
  // bind space.
  for (size_t s = 0; s < model.skins.size(); ++s) {
    tinygltf::Skin& skin = model.skins[s];
    std::vector<float> inverse_binds;
    if (skin.inverseBindMatrices >= 0) {
      const tinygltf::Accessor& old = model.accessors[skin.inverseBindMatrices];
      const tinygltf::BufferView& view = model.bufferViews[old.bufferView];
      const unsigned char* base = model.buffers[view.buffer].data.data() + view.byteOffset + old.byteOffset;
      const size_t stride = view.byteStride ? view.byteStride : 64;
      for (size_t k = 0; k < skin.joints.size(); ++k) {
        float matrix[16];
        std::memcpy(matrix, base + stride * k, sizeof(matrix));
        inverse_binds.insert(inverse_binds.end(), matrix, matrix + 16);
      }
    } else {
      for (size_t k = 0; k < skin.joints.size(); ++k) appendMatrix(&inverse_binds, Eigen::Matrix4d::Identity());
    }
    const Eigen::Affine3d placement = character.skin_placement[s];
    for (int k : bake.skinned_joint_of_muscle) {
      skin.joints.push_back(node_of_joint[k]);
      appendMatrix(&inverse_binds, (placement.inverse() * bake.joints[k].bind_world).inverse().matrix());
    }
    skin.inverseBindMatrices = data.addFloats(inverse_binds, TINYGLTF_TYPE_MAT4, 16);
  }

  // Influences.
  std::set<std::pair<int, int>> rewritten;
  for (const BakedPart& part : bake.parts) {
    const MeshPart& mesh = character.meshes[part.mesh_part];
    if (!rewritten.insert({mesh.gltf_mesh, mesh.gltf_primitive}).second) continue;
    tinygltf::Primitive& primitive = model.meshes[mesh.gltf_mesh].primitives[mesh.gltf_primitive];
    for (auto it = primitive.attributes.begin(); it != primitive.attributes.end();) {
      if (it->first.rfind("JOINTS_", 0) == 0 || it->first.rfind("WEIGHTS_", 0) == 0) it = primitive.attributes.erase(it);
      else ++it;
    }
    for (const auto* attributes : {&part.standard, &part.packed_attributes}) {
      for (const VertexAttributeData& attribute : *attributes) {
        primitive.attributes[attribute.semantic] =
            data.addAccessor(attribute.bytes.data(), attribute.bytes.size(), attribute.accessor.component_type,
                             gltfType(attribute.accessor.type), attribute.accessor.count, attribute.accessor.normalized,
                             TINYGLTF_TARGET_ARRAY_BUFFER);
      }
    }
  }

  // Animation: one LINEAR sampler per written joint and path, on the clip's sample times; none for the
  // muscles when the runtime evaluates them.
  const bool sampled = bake.motion != MuscleMotion::kRuntime;
  for (const BakedClip& clip : bake.clips) {
    if (!sampled || clip.times.empty() || clip.measure_only) continue;
    tinygltf::Animation& animation = model.animations[clip.gltf_animation];
    std::vector<float> times(clip.times.begin(), clip.times.end());
    const int input = data.addFloats(times, TINYGLTF_TYPE_SCALAR, 1, true);
    for (size_t k = 0; k < bake.joints.size(); ++k) {
      const BakedJoint& joint = bake.joints[k];
      if (node_of_joint[k] < 0) continue;
      std::vector<Trs> keys;
      for (size_t t = 0; t < clip.times.size(); ++t) keys.push_back(clip.local[t][k]);
      const TrsKeys trs_keys = trsKeys(keys);
      const std::vector<float>& translations = trs_keys.translations;
      const std::vector<float>& rotations = trs_keys.rotations;
      const std::vector<float>& scales = trs_keys.scales;
      auto addChannel = [&](const std::vector<float>& values, int type, int components, const char* path) {
        addLinearChannel(input, data.addFloats(values, type, components), node_of_joint[k], path, &animation);
      };
      addChannel(translations, TINYGLTF_TYPE_VEC3, 3, "translation");
      addChannel(rotations, TINYGLTF_TYPE_VEC4, 4, "rotation");
      if (joint.role == MuscleJointRole::kSkinned) addChannel(scales, TINYGLTF_TYPE_VEC3, 3, "scale");
    }
    writeJiggles(clip, skeleton, input, &data, &animation);
  }

  if (bake.motion != MuscleMotion::kSampled) {
    MuscleRigNodes nodes;
    for (size_t m = 0; m < bake.muscles.parts.size(); ++m) {
      nodes.skinned.push_back(node_of_joint[bake.skinned_joint_of_muscle[m]]);
      std::vector<int> helpers;
      if (bake.helper_joints) {
        for (size_t k = 0; k < bake.joints.size(); ++k) {
          if (bake.joints[k].muscle == static_cast<int>(m) && bake.joints[k].role != MuscleJointRole::kSkinned)
            helpers.push_back(node_of_joint[k]);
        }
      }
      nodes.helpers.push_back(helpers);
    }
    std::vector<RigJiggle> jiggles;
    for (const JiggleSetup& setup : bake.jiggles) {
      RigJiggle jiggle;
      jiggle.name = setup.name;
      jiggle.setup = setup;
      if (setup.host == JiggleHost::kMuscle) {
        jiggle.node = nodes.skinned[setup.muscle];
        jiggle.parent_node = skeleton.nodes[muscleCarrierJoint(bake.muscles.parts[setup.muscle])];
      } else {
        jiggle.node = skeleton.nodes[setup.joint];
        const int parent = skeleton.parents[setup.joint];
        jiggle.parent_node = parent >= 0 ? skeleton.nodes[parent] : -1;
      }
      jiggle.root_node = skeleton.nodes[setup.root];
      jiggles.push_back(jiggle);
    }
    addMuscleRigExtension(&model, skeleton, bake.muscles, buildMuscleRig(bake.muscles, skeleton), nodes, jiggles);
  }
  *nodes_of_joints = node_of_joint;
  return model;
}

long long animationBytes(const tinygltf::Model& model) {
  std::set<int> views;
  for (const tinygltf::Animation& animation : model.animations) {
    for (const tinygltf::AnimationSampler& sampler : animation.samplers) {
      for (int accessor : {sampler.input, sampler.output}) {
        if (accessor >= 0 && accessor < static_cast<int>(model.accessors.size()) && model.accessors[accessor].bufferView >= 0)
          views.insert(model.accessors[accessor].bufferView);
      }
    }
  }
  long long bytes = 0;
  for (int view : views) {
    if (view < static_cast<int>(model.bufferViews.size())) bytes += static_cast<long long>(model.bufferViews[view].byteLength);
  }
  return bytes;
}

int nodeNamed(const tinygltf::Model& model, const std::string& name) {
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    if (model.nodes[n].name == name) return static_cast<int>(n);
  }
  return -1;
}

// The helper joints' aim constraints as VRMC_node_constraint (VRM 1.0 only): each base aims its X at
// its tip, as the rig aims it (docs/muscle-model.md). The tip's X aims at the base's position, but the
// tip cannot name the base as its source: the base's constraint already depends on the tip, and the
// specification forbids circular dependencies between constraints (a runtime that orders them by
// dependency stops on one). Its source is a plain node at the base's position instead, a child of the
// origin joint like the base, where the base stays at every pose (the rig moves the origin locator
// rigidly with that joint). Returns the number of muscles whose joints got constraints.
int addHelperAimConstraints(tinygltf::Model* model, const Character& character, const BakeResult& bake,
                            const std::vector<int>& node_of_joint) {
  if (!bake.helper_joints || model->extensions.count("VRMC_vrm") == 0) return 0;
  std::vector<VrmAimConstraint> constraints;
  int muscles = 0;
  for (size_t m = 0; m < bake.muscles.parts.size(); ++m) {
    int base_joint = -1, tip_joint = -1;
    for (size_t k = 0; k < bake.joints.size(); ++k) {
      if (bake.joints[k].muscle != static_cast<int>(m)) continue;
      if (bake.joints[k].role == MuscleJointRole::kBase) base_joint = static_cast<int>(k);
      if (bake.joints[k].role == MuscleJointRole::kTip) tip_joint = static_cast<int>(k);
    }
    if (base_joint < 0 || tip_joint < 0) continue;
    const BakedJoint* base = &bake.joints[base_joint];
    const BakedJoint* tip = &bake.joints[tip_joint];
    const int base_node = node_of_joint[base_joint];
    const int tip_node = node_of_joint[tip_joint];
    if (base_node < 0 || tip_node < 0) fail(errc::GLTF_PARSE_FAILED, "/nodes", "the baked model lacks " + base->name + " or " + tip->name);
    tinygltf::Node target;
    target.name = tip->name + "Target";
    target.translation = vec(base->rest_local.translation);
    const int target_node = static_cast<int>(model->nodes.size());
    model->nodes.push_back(target);
    model->nodes[character.skeleton.nodes[base->parent]].children.push_back(target_node);
    constraints.push_back({base_node, tip_node, "PositiveX", 1.0});
    constraints.push_back({tip_node, target_node, "PositiveX", 1.0});
    ++muscles;
  }
  addVrmAimConstraints(model, constraints);
  return muscles;
}

}  // namespace

tinygltf::Model bakedModel(const GltfDocument& document, const Character& character, const BakeResult& bake) {
  std::vector<int> node_of_joint;
  return bakedModelAndNodes(document, character, bake, &node_of_joint);
}

bool isVrmDocument(const GltfDocument& document) {
  const tinygltf::Model& model = modelOf(document);
  return model.extensions.count("VRMC_vrm") > 0 || model.extensions.count("VRM") > 0;
}

BakedFile writeBakedFile(const GltfDocument& document, const Character& character, const BakeResult& bake,
                         bool binary, const std::vector<JiggleSetup>& springs) {
  std::vector<int> node_of_joint;
  tinygltf::Model model = bakedModelAndNodes(document, character, bake, &node_of_joint);
  BakedFile file;
  file.vrm = isVrmDocument(document);
  file.input_animation_bytes = animationBytes(modelOf(document));
  if (file.vrm && !springs.empty()) {
    std::vector<VrmSpring> vrm_springs = vrmSpringsForSkeleton(character.skeleton, springs);
    for (const JiggleSetup& setup : springs) {
      if (setup.host != JiggleHost::kMuscle) continue;
      const int joint = bake.skinned_joint_of_muscle[setup.muscle];
      vrm_springs.push_back(vrmSpringFor(setup, nodeNamed(model, bake.joints[joint].name), bake.joints[joint].rest_local.scale));
    }
    addVrmSpringBones(&model, vrm_springs);
  }
  file.vrm_constrained_muscles = addHelperAimConstraints(&model, character, bake, node_of_joint);
  file.animation_bytes = animationBytes(model);
  file.bytes = serializeGltf(std::move(model), binary);
  return file;
}

}  // namespace rigbake
