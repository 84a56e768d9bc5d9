#include "formats/muscle_rig_extension.h"

#include <tiny_gltf.h>

#include <algorithm>

#include "formats/gltf_json_value.h"

namespace rigbake {
namespace {

tinygltf::Value numberArray(const double* values, int count) {
  tinygltf::Value::Array array;
  for (int k = 0; k < count; ++k) array.push_back(tinygltf::Value(values[k]));
  return tinygltf::Value(array);
}

tinygltf::Value vectorValue(const Eigen::Vector3d& v) {
  const double values[3] = {v.x(), v.y(), v.z()};
  return numberArray(values, 3);
}

tinygltf::Value keysValue(const runtime::MuscleRig<double>& rig, int begin, int count) {
  tinygltf::Value::Array keys;
  for (int k = begin; k < begin + count; ++k) {
    const double values[4] = {rig.keys[k].at, rig.keys[k].up, rig.keys[k].side, rig.keys[k].scale};
    keys.push_back(numberArray(values, 4));
  }
  return tinygltf::Value(keys);
}

}  // namespace

void addMuscleRigExtension(tinygltf::Model* model, const Skeleton& skeleton, const MuscleSet& muscles,
                           const runtime::MuscleRig<double>& rig, const MuscleRigNodes& nodes,
                           const std::vector<RigJiggle>& jiggles) {
  tinygltf::Value::Array muscle_values;
  for (size_t m = 0; m < rig.muscles.size(); ++m) {
    const runtime::RigMuscle<double>& muscle = rig.muscles[m];
    tinygltf::Value::Object item;
    item["name"] = tinygltf::Value(muscles.parts[m].fullName());
    // Only correctives say what they are, so that a rig of muscles is written as before.
    if (muscles.parts[m].kind != PartKind::kMuscle) item["kind"] = tinygltf::Value(std::string(partKindName(muscles.parts[m].kind)));
    item["skinnedNode"] = tinygltf::Value(nodes.skinned[m]);
    if (m < nodes.helpers.size() && !nodes.helpers[m].empty()) {
      tinygltf::Value::Array helpers;
      for (int node : nodes.helpers[m]) helpers.push_back(tinygltf::Value(node));
      item["helperNodes"] = tinygltf::Value(helpers);
    }
    item["originNode"] = tinygltf::Value(skeleton.nodes[muscle.origin_joint]);
    item["insertionNode"] = tinygltf::Value(skeleton.nodes[muscle.insertion_joint]);
    item["carrierNode"] = tinygltf::Value(skeleton.nodes[muscle.carrier_joint]);
    item["originLocal"] = numberArray(muscle.origin_local, 3);
    item["insertionLocal"] = numberArray(muscle.insertion_local, 3);
    item["restLength"] = tinygltf::Value(muscle.rest_length);
    item["compression"] = tinygltf::Value(muscle.compression);
    item["stretch"] = tinygltf::Value(muscle.stretch);
    item["fibreLocal"] = numberArray(muscle.fibre_local, 3);
    item["upLocal"] = numberArray(muscle.up_local, 3);
    item["twistAxisLocal"] = numberArray(muscle.twist_axis_local, 3);
    item["insertionBindInOrigin"] = numberArray(muscle.insertion_bind_in_origin, 4);
    item["driverFraction"] = tinygltf::Value(muscle.driver_fraction);
    item["driverOffset"] = numberArray(muscle.driver_offset, 2);
    item["skinnedInCarrier"] = numberArray(muscle.skinned_in_carrier, 16);
    item["ratioKeys"] = keysValue(rig, muscle.ratio_key_begin, muscle.ratio_key_count);
    if (muscle.twist_key_count > 0) item["twistKeys"] = keysValue(rig, muscle.twist_key_begin, muscle.twist_key_count);
    muscle_values.push_back(tinygltf::Value(item));
  }
  tinygltf::Value::Array jiggle_values;
  for (const RigJiggle& jiggle : jiggles) {
    tinygltf::Value::Object item;
    item["name"] = tinygltf::Value(jiggle.name);
    item["node"] = tinygltf::Value(jiggle.node);
    item["parentNode"] = tinygltf::Value(jiggle.parent_node);
    item["rootNode"] = tinygltf::Value(jiggle.root_node);
    item["stiffness"] = tinygltf::Value(jiggle.setup.params.stiffness);
    item["damping"] = tinygltf::Value(jiggle.setup.params.damping);
    item["clampMajorDeg"] = tinygltf::Value(jiggle.setup.params.clamp_major_deg);
    item["clampMinorDeg"] = tinygltf::Value(jiggle.setup.params.clamp_minor_deg);
    item["aimAxis"] = vectorValue(jiggle.setup.aim_axis);
    item["majorAxis"] = vectorValue(jiggle.setup.major_axis);
    item["rootUp"] = vectorValue(jiggle.setup.root_up);
    item["length"] = tinygltf::Value(jiggle.setup.length);
    jiggle_values.push_back(tinygltf::Value(item));
  }
  tinygltf::Value::Object root;
  root["version"] = tinygltf::Value(kMuscleRigExtensionVersion);
  root["units"] = tinygltf::Value(std::string("m"));
  root["muscles"] = tinygltf::Value(muscle_values);
  if (!jiggle_values.empty()) root["jiggles"] = tinygltf::Value(jiggle_values);
  model->extensions[kMuscleRigExtension] = tinygltf::Value(root);
  if (std::find(model->extensionsUsed.begin(), model->extensionsUsed.end(), kMuscleRigExtension) == model->extensionsUsed.end())
    model->extensionsUsed.push_back(kMuscleRigExtension);
}

namespace {

// A member of a JSON object, or null when absent or when `object` is not an object.
const tinygltf::Value* jsonMember(const tinygltf::Value& object, const std::string& key) {
  const tinygltf::Value& value = gltfMember(object, key);
  return value.Type() == tinygltf::NULL_TYPE ? nullptr : &value;
}

struct Reader {
  std::vector<std::string>* problems;
  std::string pointer;

  bool fail(const std::string& where, const std::string& message) const {
    problems->push_back(pointer + where + ": " + message);
    return false;
  }
  bool numbers(const tinygltf::Value& object, const std::string& key, int count, double* out) const {
    const tinygltf::Value* value = jsonMember(object, key);
    if (!value || !value->IsArray() || static_cast<int>(value->ArrayLen()) != count)
      return fail("/" + key, "must be an array of " + std::to_string(count) + " numbers");
    for (int k = 0; k < count; ++k) {
      const tinygltf::Value& item = value->Get(k);
      if (!item.IsNumber()) return fail("/" + key + "/" + std::to_string(k), "must be a number");
      out[k] = item.GetNumberAsDouble();
    }
    return true;
  }
  bool number(const tinygltf::Value& object, const std::string& key, double* out) const {
    const tinygltf::Value* value = jsonMember(object, key);
    if (!value || !value->IsNumber()) return fail("/" + key, "must be a number");
    *out = value->GetNumberAsDouble();
    return true;
  }
  bool node(const tinygltf::Value& object, const std::string& key, const std::vector<int>& joint_of_node, int* joint,
            bool must_be_joint) const {
    const tinygltf::Value* value = jsonMember(object, key);
    if (!value || !value->IsInt()) return fail("/" + key, "must be a node index");
    const int index = value->GetNumberAsInt();
    if (index < 0 || index >= static_cast<int>(joint_of_node.size())) return fail("/" + key, "is not a node of the file");
    *joint = joint_of_node[index];
    if (must_be_joint && *joint < 0) return fail("/" + key, "is not a joint of the skeleton");
    return true;
  }
  bool keys(const tinygltf::Value& object, const std::string& key, runtime::MuscleRig<double>* rig, int* begin,
            int* count) const {
    *begin = static_cast<int>(rig->keys.size());
    *count = 0;
    const tinygltf::Value* value = jsonMember(object, key);
    if (!value) return true;
    if (!value->IsArray()) return fail("/" + key, "must be an array of [at, up, side, scale] keys");
    for (size_t k = 0; k < value->ArrayLen(); ++k) {
      const tinygltf::Value& item = value->Get(static_cast<int>(k));
      double v[4];
      if (!item.IsArray() || item.ArrayLen() != 4) return fail("/" + key + "/" + std::to_string(k), "must be [at, up, side, scale]");
      for (int c = 0; c < 4; ++c) {
        if (!item.Get(c).IsNumber()) return fail("/" + key + "/" + std::to_string(k), "must hold numbers");
        v[c] = item.Get(c).GetNumberAsDouble();
      }
      rig->keys.push_back({v[0], v[1], v[2], v[3]});
      ++*count;
    }
    return true;
  }
};

// The extension's jiggles (the runtime simulates them): nodes as joints of the loaded skeleton, a
// jiggling node that is a muscle's skinned node as that muscle. Values are kept as stored; whether the
// runtime accepts them is the validator's question (JIGGLE_WITHIN_CLAMP), not the reader's.
void readJiggles(const tinygltf::Value& extension, const std::vector<int>& joint_of_node, const std::string& pointer,
                 LoadedMuscleRig* loaded) {
  const tinygltf::Value* jiggles = jsonMember(extension, "jiggles");
  if (!jiggles) return;
  if (!jiggles->IsArray()) {
    loaded->problems.push_back(pointer + "/jiggles: must be an array");
    return;
  }
  for (size_t i = 0; i < jiggles->ArrayLen(); ++i) {
    const tinygltf::Value& item = jiggles->Get(static_cast<int>(i));
    FileJiggle jiggle;
    jiggle.pointer = pointer + "/jiggles/" + std::to_string(i);
    Reader in{&loaded->problems, jiggle.pointer};
    JiggleSetup& setup = jiggle.setup;
    const tinygltf::Value* name = jsonMember(item, "name");
    bool ok = name && name->IsString();
    if (!ok) in.fail("/name", "must be a string");
    ok = in.node(item, "node", joint_of_node, &setup.joint, true) && ok;
    // -1 stands for model space in parentNode and rootNode.
    for (auto [key, joint] : {std::pair<const char*, int*>{"parentNode", &jiggle.parent}, {"rootNode", &setup.root}}) {
      const tinygltf::Value* value = jsonMember(item, key);
      if (value && value->IsInt() && value->GetNumberAsInt() == -1)
        *joint = -1;
      else
        ok = in.node(item, key, joint_of_node, joint, true) && ok;
    }
    ok = in.number(item, "stiffness", &setup.params.stiffness) && ok;
    ok = in.number(item, "damping", &setup.params.damping) && ok;
    ok = in.number(item, "clampMajorDeg", &setup.params.clamp_major_deg) && ok;
    ok = in.number(item, "clampMinorDeg", &setup.params.clamp_minor_deg) && ok;
    ok = in.numbers(item, "aimAxis", 3, setup.aim_axis.data()) && ok;
    ok = in.numbers(item, "majorAxis", 3, setup.major_axis.data()) && ok;
    ok = in.numbers(item, "rootUp", 3, setup.root_up.data()) && ok;
    ok = in.number(item, "length", &setup.length) && ok;
    if (!ok) continue;
    setup.name = name->Get<std::string>();
    for (size_t m = 0; m < loaded->skinned_joint.size(); ++m) {
      if (loaded->skinned_joint[m] == setup.joint) jiggle.muscle = static_cast<int>(m);
    }
    setup.host = jiggle.muscle >= 0 ? JiggleHost::kMuscle : JiggleHost::kSkeletonJoint;
    setup.muscle = jiggle.muscle;
    loaded->jiggles.push_back(std::move(jiggle));
  }
}

}  // namespace

LoadedMuscleRig readMuscleRigExtension(const tinygltf::Model& model, const Character& character) {
  LoadedMuscleRig loaded;
  auto it = model.extensions.find(kMuscleRigExtension);
  if (it == model.extensions.end()) return loaded;
  loaded.present = true;
  const Skeleton& skeleton = character.skeleton;
  std::vector<int> joint_of_node(model.nodes.size(), -1);
  for (int j = 0; j < skeleton.size(); ++j) {
    if (skeleton.nodes[j] >= 0 && skeleton.nodes[j] < static_cast<int>(joint_of_node.size())) joint_of_node[skeleton.nodes[j]] = j;
  }
  Reader root{&loaded.problems, "/extensions/" + std::string(kMuscleRigExtension)};
  const tinygltf::Value& extension = it->second;
  const tinygltf::Value* version = jsonMember(extension, "version");
  if (!version || !version->IsInt() || version->GetNumberAsInt() != kMuscleRigExtensionVersion) {
    root.fail("/version", "must be " + std::to_string(kMuscleRigExtensionVersion));
    return loaded;
  }
  const tinygltf::Value* muscles = jsonMember(extension, "muscles");
  if (!muscles || !muscles->IsArray()) {
    root.fail("/muscles", "must be an array");
    return loaded;
  }
  loaded.rig.joint_count = skeleton.size();
  for (size_t m = 0; m < muscles->ArrayLen(); ++m) {
    const tinygltf::Value& item = muscles->Get(static_cast<int>(m));
    Reader in{&loaded.problems, root.pointer + "/muscles/" + std::to_string(m)};
    runtime::RigMuscle<double> muscle;
    int skinned = -1;
    const tinygltf::Value* name = jsonMember(item, "name");
    bool ok = name && name->IsString();
    if (!ok) in.fail("/name", "must be a string");
    ok = in.node(item, "skinnedNode", joint_of_node, &skinned, true) && ok;
    ok = in.node(item, "originNode", joint_of_node, &muscle.origin_joint, true) && ok;
    ok = in.node(item, "insertionNode", joint_of_node, &muscle.insertion_joint, true) && ok;
    ok = in.node(item, "carrierNode", joint_of_node, &muscle.carrier_joint, true) && ok;
    ok = in.numbers(item, "originLocal", 3, muscle.origin_local) && ok;
    ok = in.numbers(item, "insertionLocal", 3, muscle.insertion_local) && ok;
    ok = in.number(item, "restLength", &muscle.rest_length) && ok;
    ok = in.number(item, "compression", &muscle.compression) && ok;
    ok = in.number(item, "stretch", &muscle.stretch) && ok;
    ok = in.numbers(item, "fibreLocal", 3, muscle.fibre_local) && ok;
    ok = in.numbers(item, "upLocal", 3, muscle.up_local) && ok;
    ok = in.numbers(item, "twistAxisLocal", 3, muscle.twist_axis_local) && ok;
    ok = in.numbers(item, "insertionBindInOrigin", 4, muscle.insertion_bind_in_origin) && ok;
    ok = in.number(item, "driverFraction", &muscle.driver_fraction) && ok;
    ok = in.numbers(item, "driverOffset", 2, muscle.driver_offset) && ok;
    ok = in.numbers(item, "skinnedInCarrier", 16, muscle.skinned_in_carrier) && ok;
    ok = in.keys(item, "ratioKeys", &loaded.rig, &muscle.ratio_key_begin, &muscle.ratio_key_count) && ok;
    ok = in.keys(item, "twistKeys", &loaded.rig, &muscle.twist_key_begin, &muscle.twist_key_count) && ok;
    PartKind kind = PartKind::kMuscle;
    if (const tinygltf::Value* kind_value = jsonMember(item, "kind")) {
      if (!kind_value->IsString() || !parsePartKind(kind_value->Get<std::string>(), &kind))
        ok = in.fail("/kind", "must be \"muscle\" or \"corrective\"");
    }
    if (!ok) continue;
    loaded.kinds.push_back(kind);
    loaded.names.push_back(name->Get<std::string>());
    loaded.skinned_joint.push_back(skinned);
    loaded.rig.muscles.push_back(muscle);
  }
  readJiggles(extension, joint_of_node, root.pointer, &loaded);
  if (loaded.problems.empty()) {
    const std::string problem = runtime::rigProblem(loaded.rig);
    if (!problem.empty()) root.fail("/muscles", problem);
  }
  // A rig with problems stays unprepared, so that no job runs it.
  if (loaded.problems.empty()) runtime::prepareMuscleRig(&loaded.rig);
  return loaded;
}

}  // namespace rigbake
