// SampleCharacter -> tinygltf::Model.
// glTF 2.0 specification: POSITION accessors and animation sampler inputs must carry min/max;
// JOINTS_0 may be UNSIGNED_BYTE; vertex attribute views are 4-byte aligned; an UNSIGNED_SHORT index
// buffer may not use 65535 (primitive restart), so it is only used up to 65535 vertices.
// VRM 0.x: vrm-specification/specification/0.0/README.md (extension "VRM": exporterVersion, meta,
// humanoid.humanBones [{bone, node}], firstPerson, blendShapeMaster, secondaryAnimation,
// materialProperties). VRM 1.0: specification/VRMC_vrm-1.0 (extension "VRMC_vrm": specVersion "1.0",
// meta with the required name, authors and licenseUrl, humanoid.humanBones {name: {node}}).
#include "formats/sample_gltf.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <limits>
#include <nlohmann/json.hpp>

#include "formats/gltf_buffer.h"
#include "formats/gltf_json_value.h"
#include "formats/gltf_write.h"

namespace rigbake {

namespace {

constexpr const char* kGenerator = "rigbake " RIGBAKE_VERSION;

nlohmann::json vrm0Extension(const SampleCharacter& character, int body_mesh) {
  nlohmann::json bones = nlohmann::json::array();
  for (const auto& [bone, joint] : character.humanoid_bones)
    bones.push_back({{"bone", bone}, {"node", joint}, {"useDefaultValues", true}});
  int head = -1;
  for (const auto& [bone, joint] : character.humanoid_bones) {
    if (bone == "head") head = joint;
  }
  // A linear look-at curve over 90 degrees, UniVRM's default.
  nlohmann::json look_at_map = {{"curve", {0, 0, 0, 1, 1, 1, 1, 0}}, {"xRange", 90}, {"yRange", 10}};
  return {
      {"exporterVersion", kGenerator},
      {"specVersion", "0.0"},
      {"meta",
       {{"title", character.name},
        {"version", RIGBAKE_VERSION},
        {"author", "rigbake"},
        {"contactInformation", ""},
        {"reference", ""},
        {"allowedUserName", "Everyone"},
        {"violentUssageName", "Disallow"},
        {"sexualUssageName", "Disallow"},
        {"commercialUssageName", "Allow"},
        {"otherPermissionUrl", ""},
        {"licenseName", "CC0"},
        {"otherLicenseUrl", ""}}},
      {"humanoid",
       {{"humanBones", bones},
        {"armStretch", 0.05},
        {"legStretch", 0.05},
        {"upperArmTwist", 0.5},
        {"lowerArmTwist", 0.5},
        {"upperLegTwist", 0.5},
        {"lowerLegTwist", 0.5},
        {"feetSpacing", 0},
        {"hasTranslationDoF", false}}},
      {"firstPerson",
       {{"firstPersonBone", head},
        {"firstPersonBoneOffset", {{"x", 0}, {"y", 0.06}, {"z", 0}}},
        {"meshAnnotations", {{{"mesh", body_mesh}, {"firstPersonFlag", "Auto"}}}},
        {"lookAtTypeName", "Bone"},
        {"lookAtHorizontalInner", look_at_map},
        {"lookAtHorizontalOuter", look_at_map},
        {"lookAtVerticalDown", look_at_map},
        {"lookAtVerticalUp", look_at_map}}},
      {"blendShapeMaster", {{"blendShapeGroups", nlohmann::json::array()}}},
      {"secondaryAnimation", {{"boneGroups", nlohmann::json::array()}, {"colliderGroups", nlohmann::json::array()}}},
      // "VRM_USE_GLTFSHADER": the glTF material is used as it is.
      {"materialProperties",
       {{{"name", "Skin"},
         {"shader", "VRM_USE_GLTFSHADER"},
         {"renderQueue", 2000},
         {"floatProperties", nlohmann::json::object()},
         {"vectorProperties", nlohmann::json::object()},
         {"textureProperties", nlohmann::json::object()},
         {"keywordMap", nlohmann::json::object()},
         {"tagMap", nlohmann::json::object()}}}},
  };
}

nlohmann::json vrm1Extension(const SampleCharacter& character) {
  nlohmann::json bones = nlohmann::json::object();
  for (const auto& [bone, joint] : character.humanoid_bones) bones[bone] = {{"node", joint}};
  return {
      {"specVersion", "1.0"},
      {"meta",
       {{"name", character.name},
        {"version", RIGBAKE_VERSION},
        {"authors", {"rigbake"}},
        {"licenseUrl", "https://vrm.dev/licenses/1.0/"},
        {"avatarPermission", "everyone"},
        {"commercialUsage", "corporation"},
        {"creditNotation", "unnecessary"},
        {"allowRedistribution", true},
        {"modification", "allowModificationRedistribution"}}},
      {"humanoid", {{"humanBones", bones}}},
  };
}

}  // namespace

tinygltf::Model sampleToGltf(const SampleCharacter& character) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = kGenerator;
  GltfBufferAppender buffer(&model);
  const int joint_count = static_cast<int>(character.joints.size());
  const SampleMesh& mesh = character.mesh;
  const size_t vertex_count = mesh.positions.size();

  // Joints: node j is joint j.
  for (int j = 0; j < joint_count; ++j) {
    const SampleJoint& joint = character.joints[j];
    tinygltf::Node node;
    node.name = joint.name;
    // + 0.0 turns a -0 into 0, so that mirrored or turned zeros do not print as "-0.0".
    const Eigen::Vector3d& t = joint.local.translation;
    if (!t.isZero(0.0)) node.translation = {t.x() + 0.0, t.y() + 0.0, t.z() + 0.0};
    const Eigen::Quaterniond& q = joint.local.rotation;
    if (q.vec().norm() != 0.0) node.rotation = {q.x() + 0.0, q.y() + 0.0, q.z() + 0.0, q.w() + 0.0};
    model.nodes.push_back(node);
  }
  std::vector<int> roots;
  for (int j = 0; j < joint_count; ++j) {
    int parent = character.joints[j].parent;
    if (parent < 0) roots.push_back(j);
    else model.nodes[parent].children.push_back(j);
  }

  // Vertex data.
  std::vector<float> positions, normals, weights;
  for (size_t v = 0; v < vertex_count; ++v) {
    for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(mesh.positions[v][k]));
    Eigen::Vector3f n = mesh.normals[v].cast<float>().normalized();
    for (int k = 0; k < 3; ++k) normals.push_back(n[k]);
    for (int k = 0; k < 4; ++k) weights.push_back(mesh.weights[v][k]);
  }
  std::vector<double> min, max;
  floatBounds(positions, 3, &min, &max);
  tinygltf::Primitive primitive;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.material = 0;
  primitive.attributes["POSITION"] = buffer.add(positions, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                                vertex_count, TINYGLTF_TARGET_ARRAY_BUFFER, min, max);
  primitive.attributes["NORMAL"] = buffer.add(normals, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                              vertex_count, TINYGLTF_TARGET_ARRAY_BUFFER);
  if (joint_count <= 256) {
    std::vector<uint8_t> joints;
    for (const auto& slots : mesh.joints)
      for (int joint : slots) joints.push_back(static_cast<uint8_t>(joint));
    primitive.attributes["JOINTS_0"] = buffer.add(joints, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4,
                                                  vertex_count, TINYGLTF_TARGET_ARRAY_BUFFER);
  } else {
    std::vector<uint16_t> joints;
    for (const auto& slots : mesh.joints)
      for (int joint : slots) joints.push_back(static_cast<uint16_t>(joint));
    primitive.attributes["JOINTS_0"] = buffer.add(joints, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4,
                                                  vertex_count, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  primitive.attributes["WEIGHTS_0"] = buffer.add(weights, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4,
                                                 vertex_count, TINYGLTF_TARGET_ARRAY_BUFFER);
  const size_t index_count = mesh.triangles.size() * 3;
  if (vertex_count <= 65535) {
    std::vector<uint16_t> indices;
    for (const auto& t : mesh.triangles)
      for (int i : t) indices.push_back(static_cast<uint16_t>(i));
    primitive.indices = buffer.add(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, index_count,
                                   TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  } else {
    std::vector<uint32_t> indices;
    for (const auto& t : mesh.triangles)
      for (int i : t) indices.push_back(static_cast<uint32_t>(i));
    primitive.indices = buffer.add(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, index_count,
                                   TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  }
  tinygltf::Mesh gltf_mesh;
  gltf_mesh.name = "Body";
  gltf_mesh.primitives.push_back(primitive);
  model.meshes.push_back(gltf_mesh);

  tinygltf::Material material;
  material.name = "Skin";
  material.pbrMetallicRoughness.baseColorFactor = {0.80, 0.62, 0.52, 1.0};
  material.pbrMetallicRoughness.metallicFactor = 0.0;
  material.pbrMetallicRoughness.roughnessFactor = 0.7;
  model.materials.push_back(material);

  // Skin: inverse bind matrices, column-major.
  std::vector<Eigen::Affine3d> bind_world = sampleBindWorld(character);
  std::vector<float> inverse_binds;
  for (const Eigen::Affine3d& world : bind_world) {
    Eigen::Matrix4d inverse = world.inverse(Eigen::Affine).matrix();
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) inverse_binds.push_back(static_cast<float>(inverse(r, c) + 0.0));
  }
  tinygltf::Skin skin;
  skin.name = "Armature";
  for (int j = 0; j < joint_count; ++j) skin.joints.push_back(j);
  skin.skeleton = roots.front();
  skin.inverseBindMatrices = buffer.add(inverse_binds, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4,
                                        bind_world.size(), 0);
  model.skins.push_back(skin);

  tinygltf::Node body;
  body.name = "Body";
  body.mesh = 0;
  body.skin = 0;
  model.nodes.push_back(body);
  const int body_node = static_cast<int>(model.nodes.size()) - 1;

  // Clips: one input accessor per distinct key time list, one output per track.
  for (const SampleClip& clip : character.clips) {
    tinygltf::Animation animation;
    animation.name = clip.name;
    int input = -1;
    std::vector<double> input_times;
    for (const SampleTrack& track : clip.tracks) {
      if (input < 0 || track.times != input_times) {
        std::vector<float> times(track.times.begin(), track.times.end());
        std::vector<double> t_min, t_max;
        floatBounds(times, 1, &t_min, &t_max);
        input = buffer.add(times, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, times.size(), 0, t_min, t_max);
        input_times = track.times;
      }
      std::vector<float> values;
      for (const Eigen::Quaterniond& q : track.rotations) {
        Eigen::Quaterniond unit = q.normalized();
        for (double c : {unit.x(), unit.y(), unit.z(), unit.w()}) values.push_back(static_cast<float>(c + 0.0));
      }
      tinygltf::AnimationSampler sampler;
      sampler.input = input;
      sampler.output = buffer.add(values, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, track.rotations.size(), 0);
      sampler.interpolation = "LINEAR";
      animation.samplers.push_back(sampler);
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
      channel.target_node = track.joint;
      channel.target_path = "rotation";
      animation.channels.push_back(channel);
    }
    model.animations.push_back(animation);
  }

  tinygltf::Scene scene;
  scene.name = "Scene";
  scene.nodes = roots;
  scene.nodes.push_back(body_node);
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  if (character.vrm == SampleVrm::kVrm0) {
    model.extensionsUsed.push_back("VRM");
    model.extensions["VRM"] = toGltfValue(vrm0Extension(character, 0));
  } else if (character.vrm == SampleVrm::kVrm1) {
    model.extensionsUsed.push_back("VRMC_vrm");
    model.extensions["VRMC_vrm"] = toGltfValue(vrm1Extension(character));
  }
  return model;
}

void writeSampleGltf(const SampleCharacter& character, const std::string& path) {
  writeGltf(sampleToGltf(character), path);
}

}  // namespace rigbake
