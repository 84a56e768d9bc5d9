#include "formats/gltf_json_value.h"

#include <tiny_gltf.h>

namespace rigbake {

tinygltf::Value toGltfValue(const nlohmann::json& json) {
  switch (json.type()) {
    case nlohmann::json::value_t::boolean: return tinygltf::Value(json.get<bool>());
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: return tinygltf::Value(json.get<int>());
    case nlohmann::json::value_t::number_float: return tinygltf::Value(json.get<double>());
    case nlohmann::json::value_t::string: return tinygltf::Value(json.get<std::string>());
    case nlohmann::json::value_t::array: {
      tinygltf::Value::Array array;
      for (const auto& item : json) array.push_back(toGltfValue(item));
      return tinygltf::Value(std::move(array));
    }
    case nlohmann::json::value_t::object: {
      tinygltf::Value::Object object;
      for (const auto& [key, item] : json.items()) object[key] = toGltfValue(item);
      return tinygltf::Value(std::move(object));
    }
    default: return tinygltf::Value();
  }
}

nlohmann::json toJsonValue(const tinygltf::Value& value) {
  if (value.IsBool()) return value.Get<bool>();
  if (value.IsInt()) return value.Get<int>();
  if (value.IsReal()) return value.Get<double>();
  if (value.IsString()) return value.Get<std::string>();
  if (value.IsArray()) {
    nlohmann::json array = nlohmann::json::array();
    for (size_t i = 0; i < value.ArrayLen(); ++i) array.push_back(toJsonValue(value.Get(static_cast<int>(i))));
    return array;
  }
  if (value.IsObject()) {
    nlohmann::json object = nlohmann::json::object();
    for (const std::string& key : value.Keys()) object[key] = toJsonValue(value.Get(key));
    return object;
  }
  return nullptr;
}

const tinygltf::Value& gltfMember(const tinygltf::Value& object, const std::string& key) {
  static const tinygltf::Value kNull;
  if (!object.IsObject() || !object.Has(key)) return kNull;
  return object.Get(key);
}

}  // namespace rigbake
