#include "formats/gltf_bake.h"

#include <tiny_gltf.h>

#include <cstring>
#include <limits>
#include <set>

#include "anatomy/error.h"

namespace rigbake {
namespace {

// New binary data goes into one extra buffer; writeGltf merges every buffer into the GLB's one.
class BufferAppender {
 public:
  explicit BufferAppender(tinygltf::Model* model) : model_(model) {
    buffer_ = static_cast<int>(model->buffers.size());
    model->buffers.emplace_back();
  }

  int addAccessor(const void* data, size_t bytes, int component_type, int type, int count, bool normalized,
                  int target, const std::vector<double>& min = {}, const std::vector<double>& max = {}) {
    std::vector<unsigned char>& buffer = model_->buffers[buffer_].data;
    while (buffer.size() % 4 != 0) buffer.push_back(0);
    tinygltf::BufferView view;
    view.buffer = buffer_;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    view.target = target;
    const unsigned char* begin = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), begin, begin + bytes);
    model_->bufferViews.push_back(view);
    tinygltf::Accessor accessor;
    accessor.bufferView = static_cast<int>(model_->bufferViews.size()) - 1;
    accessor.componentType = component_type;
    accessor.type = type;
    accessor.count = count;
    accessor.normalized = normalized;
    accessor.minValues = min;
    accessor.maxValues = max;
    model_->accessors.push_back(accessor);
    return static_cast<int>(model_->accessors.size()) - 1;
  }

  int addFloats(const std::vector<float>& values, int type, int components, bool with_bounds = false) {
    std::vector<double> min, max;
    const int count = static_cast<int>(values.size()) / components;
    if (with_bounds) {
      min.assign(components, std::numeric_limits<double>::max());
      max.assign(components, std::numeric_limits<double>::lowest());
      for (int i = 0; i < count; ++i) {
        for (int c = 0; c < components; ++c) {
          min[c] = std::min(min[c], static_cast<double>(values[i * components + c]));
          max[c] = std::max(max[c], static_cast<double>(values[i * components + c]));
        }
      }
    }
    return addAccessor(values.data(), values.size() * sizeof(float), TINYGLTF_COMPONENT_TYPE_FLOAT, type, count, false, 0,
                       min, max);
  }

 private:
  tinygltf::Model* model_;
  int buffer_ = -1;
};

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

}  // namespace

tinygltf::Model bakedModel(const GltfDocument& document, const Character& character, const MuscleSet& muscles,
                           const BakeResult& bake) {
  tinygltf::Model model = modelOf(document);
  const Skeleton& skeleton = character.skeleton;
  BufferAppender data(&model);

  // Joint nodes, children of their attach joints.
  const int first_node = static_cast<int>(model.nodes.size());
  for (const BakedJoint& joint : bake.joints) {
    tinygltf::Node node;
    node.name = joint.name;
    node.translation = vec(joint.rest_local.translation);
    node.rotation = quat(joint.rest_local.rotation.normalized());
    if (joint.role == MuscleJointRole::kSkinned) node.scale = vec(joint.rest_local.scale);
    // What an engine needs to rebuild the constraints at run time instead of playing the samples.
    const MusclePart& part = muscles.parts[joint.muscle];
    static const char* kRoleNames[] = {"base", "tip", "driver", "skinned"};
    tinygltf::Value::Object description;
    description["muscle"] = tinygltf::Value(part.fullName());
    description["role"] = tinygltf::Value(std::string(kRoleNames[static_cast<int>(joint.role)]));
    description["origin_joint"] = tinygltf::Value(skeleton.names[part.origin.joint]);
    description["insertion_joint"] = tinygltf::Value(skeleton.names[part.insertion.joint]);
    description["compression"] = tinygltf::Value(part.compression);
    description["stretch"] = tinygltf::Value(part.stretch);
    tinygltf::Value::Object extras;
    extras["rigbake"] = tinygltf::Value(description);
    node.extras = tinygltf::Value(extras);
    model.nodes.push_back(node);
    model.nodes[skeleton.nodes[joint.parent]].children.push_back(static_cast<int>(model.nodes.size()) - 1);
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
      skin.joints.push_back(first_node + k);
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

  // Animation: one LINEAR sampler per joint and path, on the clip's sample times.
  for (const BakedClip& clip : bake.clips) {
    if (clip.times.empty()) continue;
    tinygltf::Animation& animation = model.animations[clip.gltf_animation];
    std::vector<float> times(clip.times.begin(), clip.times.end());
    const int input = data.addFloats(times, TINYGLTF_TYPE_SCALAR, 1, true);
    for (size_t k = 0; k < bake.joints.size(); ++k) {
      const BakedJoint& joint = bake.joints[k];
      std::vector<float> translations, rotations, scales;
      Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
      for (size_t t = 0; t < clip.times.size(); ++t) {
        const Trs& trs = clip.local[t][k];
        Eigen::Quaterniond q = trs.rotation.normalized();
        // Keep consecutive keys in one hemisphere so that interpolation takes the short way.
        if (t > 0 && q.dot(previous) < 0) q.coeffs() = -q.coeffs();
        previous = q;
        for (int c = 0; c < 3; ++c) translations.push_back(static_cast<float>(trs.translation[c]));
        for (double c : quat(q)) rotations.push_back(static_cast<float>(c));
        for (int c = 0; c < 3; ++c) scales.push_back(static_cast<float>(trs.scale[c]));
      }
      auto addChannel = [&](const std::vector<float>& values, int type, int components, const char* path) {
        tinygltf::AnimationSampler sampler;
        sampler.input = input;
        sampler.output = data.addFloats(values, type, components);
        sampler.interpolation = "LINEAR";
        animation.samplers.push_back(sampler);
        tinygltf::AnimationChannel channel;
        channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
        channel.target_node = first_node + static_cast<int>(k);
        channel.target_path = path;
        animation.channels.push_back(channel);
      };
      addChannel(translations, TINYGLTF_TYPE_VEC3, 3, "translation");
      addChannel(rotations, TINYGLTF_TYPE_VEC4, 4, "rotation");
      if (joint.role == MuscleJointRole::kSkinned) addChannel(scales, TINYGLTF_TYPE_VEC3, 3, "scale");
    }
  }
  return model;
}

}  // namespace rigbake
