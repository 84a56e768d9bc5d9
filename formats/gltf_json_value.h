// Conversions between nlohmann::json and tinygltf::Value, for extensions and extras that rigbake
// builds as JSON (VRM humanoid maps, spring bones) or reads back.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace tinygltf {
class Value;
}

namespace rigbake {

// Empty objects and arrays are kept: tinygltf 2.7 would write them as `null`, which the writer
// (formats/gltf_write.cpp) mends for every value of the model.
tinygltf::Value toGltfValue(const nlohmann::json& json);
nlohmann::json toJsonValue(const tinygltf::Value& value);

// object[key], or a null Value when `object` is not an object or lacks the key: tinygltf's own
// Value::Get(key) asserts that it is an object, and input files may put anything there.
const tinygltf::Value& gltfMember(const tinygltf::Value& object, const std::string& key);

}  // namespace rigbake
