// Decoding compressed glTF on load.
//
// EXT_meshopt_compression (KhronosGroup/glTF, extensions/2.0/Vendor/EXT_meshopt_compression): a
// buffer view's extension object gives a source range in a buffer, a byteStride, a count and a mode
// (ATTRIBUTES, TRIANGLES, INDICES), optionally a filter (NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL);
// the decoded bytes (count * byteStride) are what the view holds. The view's own buffer may be a
// "fallback" buffer with no data. meshoptimizer's meshopt_decodeVertexBuffer / IndexBuffer /
// IndexSequence and meshopt_decodeFilterOct / Quat / Exp implement exactly these modes and filters;
// they are safe on untrusted input (garbage out, never out-of-bounds).
//
// KHR_draco_mesh_compression (KhronosGroup/glTF, extensions/2.0/Khronos/KHR_draco_mesh_compression):
// a primitive's extension names a buffer view holding a Draco mesh and, per attribute semantic, the
// Draco attribute's unique id. The primitive's accessors keep count, type, componentType and bounds
// but have no buffer view; the decoded mesh gives one value per Draco point for each attribute, and
// its faces are the triangle list (indices) over those points.
//
// Why libraries and not our own decoders: both bitstreams are specified by their reference
// implementations (meshoptimizer's vertex codec, Draco's edgebreaker and prediction schemes) and
// Debian ships both, maintained and fuzzed upstream; a hand-written decoder would be thousands of
// lines for no gain.
#include "formats/gltf_decompress.h"

#include <draco/compression/decode.h>
#include <meshoptimizer.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "formats/gltf_accessor.h"
#include "formats/gltf_json_value.h"

namespace rigbake {
namespace {

constexpr const char* kMeshopt = "EXT_meshopt_compression";
constexpr const char* kDraco = "KHR_draco_mesh_compression";
// Where prepareCompressedGltf keeps a Draco primitive's indices accessor while tinygltf parses.
constexpr const char* kParkedIndices = "rigbake_parked_indices";
// More decoded bytes than any character needs; a count that asks for more is damage, not data.
constexpr double kMaxDecodedBytes = 1 << 30;

// ---- Before tinygltf: the JSON ----

bool isGlb(const std::string& bytes) { return bytes.size() >= 20 && bytes.compare(0, 4, "glTF") == 0; }

// The JSON chunk of a GLB, or "" when the container is malformed (tinygltf then says why).
std::string glbJsonText(const std::string& bytes) {
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, sizeof(length));
  if (bytes.compare(16, 4, "JSON") != 0 || length > bytes.size() - 20) return "";
  return bytes.substr(20, length);
}

std::string glbWithJson(const std::string& bytes, const std::string& json) {
  uint32_t old_length = 0;
  std::memcpy(&old_length, bytes.data() + 12, sizeof(old_length));
  std::string padded = json;
  while (padded.size() % 4) padded += ' ';
  const std::string chunks_after = bytes.substr(20 + old_length);
  const uint32_t length = static_cast<uint32_t>(padded.size());
  const uint32_t total = static_cast<uint32_t>(20 + padded.size() + chunks_after.size());
  std::string out = bytes.substr(0, 8);
  out.append(reinterpret_cast<const char*>(&total), sizeof(total));
  out.append(reinterpret_cast<const char*>(&length), sizeof(length));
  out += "JSON";
  out += padded;
  out += chunks_after;
  return out;
}

bool parkDracoIndices(nlohmann::json* gltf) {
  bool changed = false;
  if (!gltf->contains("meshes") || !(*gltf)["meshes"].is_array()) return false;
  for (nlohmann::json& mesh : (*gltf)["meshes"]) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (nlohmann::json& primitive : mesh["primitives"]) {
      if (!primitive.is_object() || !primitive.contains("indices") || !primitive.contains("extensions")) continue;
      nlohmann::json& extensions = primitive["extensions"];
      if (!extensions.is_object() || !extensions.contains(kDraco) || !extensions[kDraco].is_object()) continue;
      extensions[kDraco][kParkedIndices] = primitive["indices"];
      primitive.erase("indices");
      changed = true;
    }
  }
  return changed;
}

bool isDatalessFallback(const nlohmann::json& buffer) {
  if (!buffer.is_object() || buffer.contains("uri") || !buffer.contains("extensions")) return false;
  const nlohmann::json& extensions = buffer["extensions"];
  return extensions.is_object() && extensions.contains(kMeshopt) && extensions[kMeshopt].is_object() &&
         extensions[kMeshopt].value("fallback", false) == true;
}

const nlohmann::json* meshoptOf(const nlohmann::json& view) {
  if (!view.is_object() || !view.contains("extensions") || !view["extensions"].is_object()) return nullptr;
  const nlohmann::json& extensions = view["extensions"];
  if (!extensions.contains(kMeshopt) || !extensions[kMeshopt].is_object()) return nullptr;
  return &extensions[kMeshopt];
}

// Drops fallback buffers without data when only compressed views use them; those views then point
// at their compressed bytes until decompressGltf replaces them with the decoded ones.
bool dropDatalessFallbacks(nlohmann::json* gltf) {
  if (!gltf->contains("buffers") || !(*gltf)["buffers"].is_array()) return false;
  nlohmann::json& buffers = (*gltf)["buffers"];
  nlohmann::json no_views = nlohmann::json::array();
  nlohmann::json& views =
      gltf->contains("bufferViews") && (*gltf)["bufferViews"].is_array() ? (*gltf)["bufferViews"] : no_views;
  std::vector<char> dropped(buffers.size(), 0);
  for (size_t b = 0; b < buffers.size(); ++b) dropped[b] = isDatalessFallback(buffers[b]);
  for (const nlohmann::json& view : views) {
    if (!view.is_object() || !view.contains("buffer") || !view["buffer"].is_number_integer()) continue;
    const int64_t buffer = view["buffer"].get<int64_t>();
    const nlohmann::json* meshopt = meshoptOf(view);
    const bool movable = meshopt && meshopt->contains("buffer") && (*meshopt)["buffer"].is_number_integer() &&
                         meshopt->contains("byteLength") && (*meshopt)["byteLength"].is_number_integer();
    if (buffer >= 0 && buffer < static_cast<int64_t>(buffers.size()) && !movable) dropped[buffer] = 0;
  }
  if (std::find(dropped.begin(), dropped.end(), 1) == dropped.end()) return false;
  std::vector<int64_t> new_index(buffers.size(), -1);
  int64_t next = 0;
  for (size_t b = 0; b < buffers.size(); ++b) {
    if (!dropped[b]) new_index[b] = next++;
  }
  auto renumber = [&](nlohmann::json& reference) {
    if (!reference.is_number_integer()) return;
    const int64_t old = reference.get<int64_t>();
    if (old >= 0 && old < static_cast<int64_t>(new_index.size()) && new_index[old] >= 0) reference = new_index[old];
  };
  for (nlohmann::json& view : views) {
    if (!view.is_object() || !view.contains("buffer") || !view["buffer"].is_number_integer()) continue;
    const int64_t buffer = view["buffer"].get<int64_t>();
    if (meshoptOf(view)) {
      nlohmann::json& meshopt = view["extensions"][kMeshopt];
      if (buffer >= 0 && buffer < static_cast<int64_t>(dropped.size()) && dropped[buffer]) {
        view["buffer"] = meshopt["buffer"];
        view["byteOffset"] = meshopt.value("byteOffset", 0);
        view["byteLength"] = meshopt["byteLength"];
      }
      renumber(meshopt["buffer"]);
    }
    renumber(view["buffer"]);
  }
  nlohmann::json kept = nlohmann::json::array();
  for (size_t b = 0; b < buffers.size(); ++b) {
    if (!dropped[b]) kept.push_back(buffers[b]);
  }
  buffers = kept;
  return true;
}

// ---- After tinygltf: the model ----


int componentBytes(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// A non-negative integer member of an extension object, or `fallback` when absent; -1 when present
// but not a non-negative integer.
double integerMember(const tinygltf::Value& object, const char* key, double fallback) {
  const tinygltf::Value& value = gltfMember(object, key);
  if (value.Type() == tinygltf::NULL_TYPE) return fallback;
  if (!value.IsNumber() && !value.IsInt()) return -1;
  const double number = value.GetNumberAsDouble();
  return number >= 0 && std::floor(number) == number ? number : -1;
}

std::string stringMember(const tinygltf::Value& object, const char* key, const std::string& fallback) {
  const tinygltf::Value& value = gltfMember(object, key);
  return value.IsString() ? value.Get<std::string>() : fallback;
}

// Decoded bytes collect in one buffer appended to the model; every piece starts 4-byte aligned, which
// is the largest component size and the vertex attribute alignment glTF asks for.
class DecodedBuffer {
 public:
  explicit DecodedBuffer(tinygltf::Model* model) : model_(model) {}
  int index() {
    if (index_ < 0) {
      model_->buffers.emplace_back();
      index_ = static_cast<int>(model_->buffers.size()) - 1;
    }
    return index_;
  }
  size_t append(const std::vector<unsigned char>& bytes) {
    std::vector<unsigned char>& data = model_->buffers[index()].data;
    while (data.size() % 4) data.push_back(0);
    const size_t offset = data.size();
    data.insert(data.end(), bytes.begin(), bytes.end());
    return offset;
  }

 private:
  tinygltf::Model* model_;
  int index_ = -1;
};

void decodeMeshoptView(tinygltf::Model* model, int view_index, DecodedBuffer* decoded, const std::string& where) {
  tinygltf::BufferView& view = model->bufferViews[view_index];
  const std::string pointer = "/bufferViews/" + std::to_string(view_index) + "/extensions/" + kMeshopt;
  const tinygltf::Value& extension = view.extensions.at(kMeshopt);
  const double buffer = integerMember(extension, "buffer", -1);
  const double offset = integerMember(extension, "byteOffset", 0);
  const double length = integerMember(extension, "byteLength", -1);
  const double stride = integerMember(extension, "byteStride", -1);
  const double count = integerMember(extension, "count", -1);
  const std::string mode = stringMember(extension, "mode", "");
  const std::string filter = stringMember(extension, "filter", "NONE");
  if (buffer < 0 || offset < 0 || length < 0 || stride <= 0 || count < 0)
    fail(errc::GLTF_PARSE_FAILED, where,
         pointer + " needs buffer, byteLength, byteStride and count as non-negative integers");
  if (buffer >= static_cast<double>(model->buffers.size()))
    fail(errc::GLTF_PARSE_FAILED, where, pointer + "/buffer is not a buffer");
  const std::vector<unsigned char>& source = model->buffers[static_cast<size_t>(buffer)].data;
  if (offset + length > static_cast<double>(source.size()))
    fail(errc::GLTF_PARSE_FAILED, where, pointer + " reads past the end of its buffer (file truncated?)");
  if (count * stride > kMaxDecodedBytes)
    fail(errc::GLTF_PARSE_FAILED, where, pointer + " asks for an implausible decoded size");
  const size_t n = static_cast<size_t>(count), size = static_cast<size_t>(stride);
  const unsigned char* bytes = source.data() + static_cast<size_t>(offset);
  std::vector<unsigned char> out(n * size);
  int status = 0;
  if (mode == "ATTRIBUTES") {
    if (size % 4 != 0 || size > 256)
      fail(errc::GLTF_PARSE_FAILED, where,
           pointer + ": ATTRIBUTES needs a byteStride that is a multiple of 4, at most 256");
    status = meshopt_decodeVertexBuffer(out.data(), n, size, bytes, static_cast<size_t>(length));
  } else if (mode == "TRIANGLES" || mode == "INDICES") {
    if (size != 2 && size != 4)
      fail(errc::GLTF_PARSE_FAILED, where, pointer + ": " + mode + " needs a byteStride of 2 or 4");
    if (mode == "TRIANGLES" && n % 3 != 0)
      fail(errc::GLTF_PARSE_FAILED, where, pointer + ": TRIANGLES needs a count that is a multiple of 3");
    status = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out.data(), n, size, bytes, static_cast<size_t>(length))
                                 : meshopt_decodeIndexSequence(out.data(), n, size, bytes, static_cast<size_t>(length));
  } else {
    fail(errc::GLTF_PARSE_FAILED, where, pointer + "/mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES");
  }
  if (status != 0)
    fail(errc::GLTF_PARSE_FAILED, where,
         pointer + ": the compressed data does not decode (meshoptimizer " +
             std::to_string(MESHOPTIMIZER_VERSION / 1000) + "." + std::to_string(MESHOPTIMIZER_VERSION % 1000 / 10) +
             " error " + std::to_string(status) + "; damaged, or written in a newer codec version)");
  if (filter != "NONE" && mode != "ATTRIBUTES")
    fail(errc::GLTF_PARSE_FAILED, where, pointer + "/filter " + filter + " applies to ATTRIBUTES only");
  if (filter == "OCTAHEDRAL") {
    if (size != 4 && size != 8) fail(errc::GLTF_PARSE_FAILED, where, pointer + ": OCTAHEDRAL needs a byteStride of 4 or 8");
    meshopt_decodeFilterOct(out.data(), n, size);
  } else if (filter == "QUATERNION") {
    if (size != 8) fail(errc::GLTF_PARSE_FAILED, where, pointer + ": QUATERNION needs a byteStride of 8");
    meshopt_decodeFilterQuat(out.data(), n, size);
  } else if (filter == "EXPONENTIAL") {
    meshopt_decodeFilterExp(out.data(), n, size);
  } else if (filter != "NONE") {
    fail(errc::GLTF_PARSE_FAILED, where,
         pointer + "/filter '" + filter + "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
  }
  view.buffer = decoded->index();
  view.byteOffset = decoded->append(out);
  view.byteLength = out.size();
  view.extensions.erase(kMeshopt);
}

struct ComponentBounds {
  std::vector<double> min, max;
};

template <typename T>
void appendConverted(const draco::PointAttribute& attribute, draco::PointIndex point, int components,
                     std::vector<unsigned char>* out, ComponentBounds* bounds, bool* ok) {
  T values[16] = {};
  *ok = *ok && attribute.ConvertValue<T>(attribute.mapped_index(point), static_cast<int8_t>(components), values);
  const unsigned char* bytes = reinterpret_cast<const unsigned char*>(values);
  out->insert(out->end(), bytes, bytes + sizeof(T) * components);
  for (int c = 0; c < components; ++c) {
    bounds->min[c] = std::min(bounds->min[c], static_cast<double>(values[c]));
    bounds->max[c] = std::max(bounds->max[c], static_cast<double>(values[c]));
  }
}

// One Draco attribute in the accessor's own component type, one element per point, each element
// padded to 4 bytes (the vertex attribute alignment). Returns the element stride; `bounds` gets the
// stored values' range.
size_t convertAttribute(const draco::Mesh& mesh, const draco::PointAttribute& attribute,
                        const tinygltf::Accessor& accessor, std::vector<unsigned char>* out, ComponentBounds* bounds,
                        bool* ok) {
  const int components = accessorComponentCount(accessor.type);
  const size_t element = static_cast<size_t>(componentBytes(accessor.componentType)) * components;
  const size_t stride = (element + 3) / 4 * 4;
  bounds->min.assign(components, std::numeric_limits<double>::infinity());
  bounds->max.assign(components, -std::numeric_limits<double>::infinity());
  out->reserve(stride * mesh.num_points());
  for (draco::PointIndex point(0); point < mesh.num_points(); ++point) {
    switch (accessor.componentType) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: appendConverted<int8_t>(attribute, point, components, out, bounds, ok); break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        appendConverted<uint8_t>(attribute, point, components, out, bounds, ok);
        break;
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        appendConverted<int16_t>(attribute, point, components, out, bounds, ok);
        break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        appendConverted<uint16_t>(attribute, point, components, out, bounds, ok);
        break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        appendConverted<uint32_t>(attribute, point, components, out, bounds, ok);
        break;
      default: appendConverted<float>(attribute, point, components, out, bounds, ok); break;
    }
    out->resize(out->size() + stride - element, 0);
  }
  return stride;
}

std::vector<unsigned char> convertIndices(const draco::Mesh& mesh, int component_type, bool* ok) {
  const int size = componentBytes(component_type);
  const uint64_t limit = size == 1 ? 0xffu : size == 2 ? 0xffffu : 0xffffffffu;
  std::vector<unsigned char> out;
  out.reserve(static_cast<size_t>(mesh.num_faces()) * 3 * size);
  for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t index = mesh.face(f)[k].value();
      *ok = *ok && index <= limit;
      for (int b = 0; b < size; ++b) out.push_back(static_cast<unsigned char>(index >> (8 * b)));
    }
  }
  return out;
}

struct DracoState {
  std::map<int, std::unique_ptr<draco::Mesh>> meshes;  // by payload buffer view
  std::map<int, bool> payload_reused;                  // the payload view already holds decoded data
  std::vector<char> accessor_done;
};

// Puts decoded bytes in a view: the primitive's payload view the first time (so no view is left
// unused and no index changes), a new view after that.
int viewFor(tinygltf::Model* model, int payload, const std::vector<unsigned char>& bytes, size_t stride, int target,
            DecodedBuffer* decoded, DracoState* state) {
  int index = payload;
  if (state->payload_reused[payload]) {
    model->bufferViews.emplace_back();
    index = static_cast<int>(model->bufferViews.size()) - 1;
  }
  state->payload_reused[payload] = true;
  tinygltf::BufferView& view = model->bufferViews[index];
  view.buffer = decoded->index();
  view.byteOffset = decoded->append(bytes);
  view.byteLength = bytes.size();
  view.byteStride = stride;
  view.target = target;
  return index;
}

void decodeDracoPrimitive(tinygltf::Model* model, int mesh_index, int primitive_index, DecodedBuffer* decoded,
                          DracoState* state, const std::string& where) {
  tinygltf::Primitive& primitive = model->meshes[mesh_index].primitives[primitive_index];
  const std::string pointer = "/meshes/" + std::to_string(mesh_index) + "/primitives/" +
                              std::to_string(primitive_index) + "/extensions/" + kDraco;
  const tinygltf::Value extension = primitive.extensions.at(kDraco);
  const tinygltf::Value& parked = gltfMember(extension, kParkedIndices);
  if (parked.IsNumber() || parked.IsInt()) primitive.indices = parked.GetNumberAsInt();
  const double payload_number = integerMember(extension, "bufferView", -1);
  const tinygltf::Value& ids = gltfMember(extension, "attributes");
  if (payload_number < 0 || payload_number >= static_cast<double>(model->bufferViews.size()) || !ids.IsObject())
    fail(errc::GLTF_PARSE_FAILED, where, pointer + " needs a bufferView and an attributes object");
  const int payload = static_cast<int>(payload_number);
  const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP)
    fail(errc::GLTF_PARSE_FAILED, where, pointer + " is on a primitive that is not TRIANGLES or TRIANGLE_STRIP");

  if (!state->meshes.count(payload)) {
    const tinygltf::BufferView& view = model->bufferViews[payload];
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model->buffers.size()) ||
        view.byteOffset + view.byteLength > model->buffers[view.buffer].data.size())
      fail(errc::GLTF_PARSE_FAILED, where, pointer + "/bufferView lies outside its buffer (file truncated?)");
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(model->buffers[view.buffer].data.data() + view.byteOffset),
                view.byteLength);
    draco::Decoder decoder;
    auto result = decoder.DecodeMeshFromBuffer(&buffer);
    if (!result.ok())
      fail(errc::GLTF_PARSE_FAILED, where,
           pointer + ": Draco cannot decode bufferView " + std::to_string(payload) + " (" +
               result.status().error_msg_string() + ")");
    state->meshes[payload] = std::move(result).value();
  }
  const draco::Mesh& mesh = *state->meshes.at(payload);

  for (const auto& [semantic, accessor_index] : primitive.attributes) {
    const tinygltf::Value& id = gltfMember(ids, semantic);
    if (!id.IsNumber() && !id.IsInt()) continue;  // an attribute stored outside the Draco mesh
    if (accessor_index < 0 || accessor_index >= static_cast<int>(model->accessors.size()))
      fail(errc::GLTF_ACCESSOR_INVALID, where, pointer + ": attribute " + semantic + " has no accessor");
    if (state->accessor_done[accessor_index]) continue;
    const draco::PointAttribute* attribute = mesh.GetAttributeByUniqueId(static_cast<uint32_t>(id.GetNumberAsInt()));
    tinygltf::Accessor& accessor = model->accessors[accessor_index];
    if (!attribute)
      fail(errc::GLTF_PARSE_FAILED, where, pointer + "/attributes/" + semantic + " names no attribute of the Draco mesh");
    const int components = accessorComponentCount(accessor.type);
    if (components == 0 || components > 16 || componentBytes(accessor.componentType) == 0 ||
        attribute->num_components() != components || accessor.count != mesh.num_points())
      fail(errc::GLTF_ACCESSOR_INVALID, where,
           "/accessors/" + std::to_string(accessor_index) + " (" + semantic + ") does not fit the Draco mesh's " +
               std::to_string(mesh.num_points()) + " points of " + std::to_string(attribute->num_components()) +
               " components");
    std::vector<unsigned char> bytes;
    ComponentBounds bounds;
    bool ok = true;
    const size_t stride = convertAttribute(mesh, *attribute, accessor, &bytes, &bounds, &ok);
    if (!ok)
      fail(errc::GLTF_ACCESSOR_INVALID, where,
           "/accessors/" + std::to_string(accessor_index) + " (" + semantic +
               "): Draco values do not fit its component type");
    const size_t element = static_cast<size_t>(componentBytes(accessor.componentType)) * components;
    accessor.bufferView =
        viewFor(model, payload, bytes, stride == element ? 0 : stride, TINYGLTF_TARGET_ARRAY_BUFFER, decoded, state);
    accessor.byteOffset = 0;
    // The bounds an encoder wrote are those of its input; Draco's quantization moves values, and glTF
    // wants the bounds of the values stored (ACCESSOR_MAX_MISMATCH otherwise).
    if (!accessor.minValues.empty() && mesh.num_points() > 0) accessor.minValues = bounds.min;
    if (!accessor.maxValues.empty() && mesh.num_points() > 0) accessor.maxValues = bounds.max;
    state->accessor_done[accessor_index] = 1;
  }

  if (primitive.indices < 0) {
    tinygltf::Accessor indices;
    indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indices.type = TINYGLTF_TYPE_SCALAR;
    indices.count = static_cast<size_t>(mesh.num_faces()) * 3;
    model->accessors.push_back(indices);
    state->accessor_done.push_back(0);
    primitive.indices = static_cast<int>(model->accessors.size()) - 1;
  }
  if (primitive.indices >= static_cast<int>(model->accessors.size()))
    fail(errc::GLTF_ACCESSOR_INVALID, where, pointer + ": the indices accessor does not exist");
  if (!state->accessor_done[primitive.indices]) {
    tinygltf::Accessor& accessor = model->accessors[primitive.indices];
    const int size = componentBytes(accessor.componentType);
    if (accessor.type != TINYGLTF_TYPE_SCALAR || size == 0 || accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
        accessor.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
        accessor.componentType == TINYGLTF_COMPONENT_TYPE_SHORT ||
        accessor.count != static_cast<size_t>(mesh.num_faces()) * 3)
      fail(errc::GLTF_ACCESSOR_INVALID, where,
           "/accessors/" + std::to_string(primitive.indices) + " (indices) does not fit the Draco mesh's " +
               std::to_string(mesh.num_faces()) + " triangles");
    bool ok = true;
    const std::vector<unsigned char> bytes = convertIndices(mesh, accessor.componentType, &ok);
    if (!ok)
      fail(errc::GLTF_ACCESSOR_INVALID, where,
           "/accessors/" + std::to_string(primitive.indices) + ": a Draco index does not fit its component type");
    accessor.bufferView = viewFor(model, payload, bytes, 0, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER, decoded, state);
    accessor.byteOffset = 0;
    state->accessor_done[primitive.indices] = 1;
  }
  // Draco's faces are a triangle list whatever the primitive drew.
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  primitive.extensions.erase(kDraco);
}

void removeName(std::vector<std::string>* names, const std::string& name) {
  names->erase(std::remove(names->begin(), names->end(), name), names->end());
}

}  // namespace

void prepareCompressedGltf(std::string* bytes) {
  const bool binary = isGlb(*bytes);
  const std::string text = binary ? glbJsonText(*bytes) : *bytes;
  if (text.find(kMeshopt) == std::string::npos && text.find(kDraco) == std::string::npos) return;
  nlohmann::json gltf = nlohmann::json::parse(text, nullptr, false);
  if (!gltf.is_object()) return;  // tinygltf reports what is wrong
  const bool parked = parkDracoIndices(&gltf);
  const bool dropped = dropDatalessFallbacks(&gltf);
  if (!parked && !dropped) return;
  *bytes = binary ? glbWithJson(*bytes, gltf.dump()) : gltf.dump();
}

void decompressGltf(tinygltf::Model* model, const std::string& where) {
  DecodedBuffer decoded(model);
  for (size_t v = 0; v < model->bufferViews.size(); ++v) {
    if (model->bufferViews[v].extensions.count(kMeshopt))
      decodeMeshoptView(model, static_cast<int>(v), &decoded, where);
  }
  DracoState draco;
  draco.accessor_done.assign(model->accessors.size(), 0);
  for (size_t m = 0; m < model->meshes.size(); ++m) {
    for (size_t p = 0; p < model->meshes[m].primitives.size(); ++p) {
      if (model->meshes[m].primitives[p].extensions.count(kDraco))
        decodeDracoPrimitive(model, static_cast<int>(m), static_cast<int>(p), &decoded, &draco, where);
    }
  }
  for (tinygltf::Buffer& buffer : model->buffers) buffer.extensions.erase(kMeshopt);
  for (const char* name : {kMeshopt, kDraco}) {
    removeName(&model->extensionsUsed, name);
    removeName(&model->extensionsRequired, name);
  }
}

}  // namespace rigbake
