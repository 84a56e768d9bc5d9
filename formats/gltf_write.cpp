// glTF/GLB writer on top of tinygltf 2.7's TinyGLTF::WriteGltfSceneToStream.
//
// Why tinygltf's serializer and not our own: it writes every glTF property rigbake does not model
// (materials, samplers, cameras, KHR_lights_punctual, extensions, extras) from the same Model the
// loader filled, its JSON is nlohmann::json with keys in sorted order and shortest round-trip numbers
// (deterministic), and its GLB container is right: JSON chunk padded with spaces, BIN chunk padded
// with zeros, buffer byteLength the unpadded size (glTF 2.0 spec, "GLB File Format Specification").
//
// What it gets wrong for a loaded model, and what this file does about it (checked against the
// tinygltf 2.7 sources):
// - Only buffers[0] without a uri goes into the GLB's BIN chunk; any other buffer is written as a
//   base64 data: URI, and an external buffer (uri "x.bin") is inlined the same way. GLB allows one
//   BIN chunk, so we merge every buffer view into one new buffer.
// - Its default image writer re-encodes Image::image as raw pixels with stb_image_write, but the
//   loader keeps the encoded PNG/JPEG bytes (as_is), so it would write garbage or fall back to the old
//   external uri, which breaks once the file is written elsewhere. We move every image into a buffer
//   view and install no image writer.
// - Animations with no channels are skipped, shifting later animation indices; such an animation is
//   invalid glTF anyway (channels has minItems 1).
#include "formats/gltf_write.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <streambuf>
#include <ostream>

#include "core/error.h"
#include "formats/atomic_file.h"
#include "formats/gltf_document.h"

namespace rigbake {

namespace {

bool endsWith(const std::string& text, const std::string& suffix) {
  if (text.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(text[text.size() - suffix.size() + i])) != suffix[i]) return false;
  }
  return true;
}

// The MIME type glTF wants beside a buffer-view image, from the file's own signature first (an
// extension can lie), then from the old uri.
std::string imageMimeType(const tinygltf::Image& image, const std::vector<unsigned char>& bytes) {
  auto starts = [&](const std::string& magic, size_t at = 0) {
    return bytes.size() >= at + magic.size() && std::equal(magic.begin(), magic.end(), bytes.begin() + at,
                                                           [](char a, unsigned char b) { return static_cast<unsigned char>(a) == b; });
  };
  if (starts("\x89PNG\r\n\x1a\n")) return "image/png";
  if (starts("\xff\xd8\xff")) return "image/jpeg";
  if (starts("RIFF") && starts("WEBP", 8)) return "image/webp";
  if (starts("\xabKTX 20\xbb")) return "image/ktx2";
  if (!image.mimeType.empty()) return image.mimeType;
  if (endsWith(image.uri, ".png")) return "image/png";
  if (endsWith(image.uri, ".jpg") || endsWith(image.uri, ".jpeg")) return "image/jpeg";
  if (endsWith(image.uri, ".webp")) return "image/webp";
  if (endsWith(image.uri, ".ktx2")) return "image/ktx2";
  return "application/octet-stream";
}

// The offset at or after `end` with the same remainder modulo 4 as `old_offset`: an accessor is valid
// when (bufferView.byteOffset + accessor.byteOffset) is a multiple of its component size (at most 4),
// and keeping the remainder keeps exactly the validity the source had.
size_t alignedLike(size_t end, size_t old_offset) { return end + (old_offset % 4 + 4 - end % 4) % 4; }

// One byte range of the merged buffer: where it comes from and where it goes.
struct BinPiece {
  const unsigned char* data = nullptr;
  size_t size = 0;
  size_t offset = 0;
};

// A model whose buffer views all lie in one buffer (its data left empty), every image in a buffer
// view, and the pieces of that buffer, which point into `sources` (the model's old buffers) and into
// the model's images. The bytes are copied once, by the caller, into the file itself: a merged
// buffer, tinygltf's copy of it and a stream's copy of the file cost three times the output.
struct StandAlone {
  tinygltf::Model model;
  std::vector<tinygltf::Buffer> sources;
  std::vector<BinPiece> pieces;
  size_t bin_size = 0;
};

StandAlone standAloneLayout(tinygltf::Model model) {
  StandAlone out;
  out.sources = std::move(model.buffers);
  model.buffers.clear();
  size_t end = 0;
  std::vector<size_t> embedded;  // images moved into a buffer view here
  for (size_t v = 0; v < model.bufferViews.size(); ++v) {
    tinygltf::BufferView& view = model.bufferViews[v];
    std::string where = "/bufferViews/" + std::to_string(v);
    if (view.buffer < 0 || view.buffer >= static_cast<int>(out.sources.size()))
      fail(errc::GLTF_PARSE_FAILED, where, "refers to a missing buffer " + std::to_string(view.buffer));
    const std::vector<unsigned char>& data = out.sources[view.buffer].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail(errc::GLTF_PARSE_FAILED, where, "lies outside its buffer (" + std::to_string(data.size()) + " bytes)");
    const size_t offset = alignedLike(end, view.byteOffset);
    out.pieces.push_back(BinPiece{data.data() + view.byteOffset, view.byteLength, offset});
    end = offset + view.byteLength;
    view.byteOffset = offset;
    view.buffer = 0;
  }
  for (size_t i = 0; i < model.images.size(); ++i) {
    tinygltf::Image& image = model.images[i];
    if (image.bufferView >= 0) {
      if (image.mimeType.empty()) image.mimeType = imageMimeType(image, image.image);
      continue;
    }
    // An external image the loader could not read stays a reference: there is nothing to embed.
    if (image.image.empty()) continue;
    if (!image.as_is)
      fail(errc::INTERNAL, "/images/" + std::to_string(i),
           "the image holds decoded pixels, not its file bytes; load it with the raw-bytes image loader");
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteLength = image.image.size();
    view.byteOffset = alignedLike(end, 0);
    view.name = image.name;
    end = view.byteOffset + view.byteLength;
    model.bufferViews.push_back(view);
    image.bufferView = static_cast<int>(model.bufferViews.size()) - 1;
    image.mimeType = imageMimeType(image, image.image);
    image.uri.clear();
    embedded.push_back(i);
  }
  // The images' pieces point into the images' own bytes, which keep their address when the model
  // (and so its images vector) is moved into `out`.
  out.model = std::move(model);
  for (size_t i : embedded) {
    const tinygltf::Image& image = out.model.images[i];
    out.pieces.push_back(BinPiece{image.image.data(), image.image.size(), out.model.bufferViews[image.bufferView].byteOffset});
  }
  out.bin_size = end;
  if (!out.model.bufferViews.empty()) out.model.buffers.emplace_back();
  return out;
}

// tinygltf 2.7 writes an empty object or array nested in an extension or extras as null (its ValueToJson
// builds a JSON value from members only), and glTF has no null: a VRM 0.x avatar's
// "floatProperties": {} came out as null (found by the validator pass over every model the test suite
// writes). Each empty one is swapped for a marker string before serialization, and the marker for {}
// or [] in the JSON text after. A null it drops instead (NULL_TYPE) never reaches the text.
constexpr const char* kEmptyObjectMarker = "\"rigbake:empty-object:3f9d2c\"";
constexpr const char* kEmptyArrayMarker = "\"rigbake:empty-array:3f9d2c\"";

void markEmptyValues(tinygltf::Value* value) {
  if (value->IsObject()) {
    auto& members = value->Get<tinygltf::Value::Object>();
    if (members.empty()) {
      *value = tinygltf::Value(std::string(kEmptyObjectMarker + 1, std::strlen(kEmptyObjectMarker) - 2));
      return;
    }
    for (auto& member : members) markEmptyValues(&member.second);
  } else if (value->IsArray()) {
    auto& items = value->Get<tinygltf::Value::Array>();
    if (items.empty()) {
      *value = tinygltf::Value(std::string(kEmptyArrayMarker + 1, std::strlen(kEmptyArrayMarker) - 2));
      return;
    }
    for (auto& item : items) markEmptyValues(&item);
  }
}

template <typename Part>
void markEmptyValuesOf(Part* part) {
  markEmptyValues(&part->extras);
  for (auto& extension : part->extensions) markEmptyValues(&extension.second);
}

template <typename Part>
void markEmptyValuesOfEach(std::vector<Part>* parts) {
  for (Part& part : *parts) markEmptyValuesOf(&part);
}

// Every extras and extension value of the model (tinygltf 2.7's 26 kinds of glTF object).
void markEmptyValuesInModel(tinygltf::Model* model) {
  markEmptyValuesOf(model);
  markEmptyValuesOf(&model->asset);
  markEmptyValuesOfEach(&model->accessors);
  markEmptyValuesOfEach(&model->buffers);
  markEmptyValuesOfEach(&model->bufferViews);
  markEmptyValuesOfEach(&model->images);
  markEmptyValuesOfEach(&model->samplers);
  markEmptyValuesOfEach(&model->textures);
  markEmptyValuesOfEach(&model->skins);
  markEmptyValuesOfEach(&model->scenes);
  markEmptyValuesOfEach(&model->nodes);
  for (tinygltf::Animation& animation : model->animations) {
    markEmptyValuesOf(&animation);
    markEmptyValuesOfEach(&animation.channels);
    markEmptyValuesOfEach(&animation.samplers);
  }
  for (tinygltf::Material& material : model->materials) {
    markEmptyValuesOf(&material);
    markEmptyValuesOf(&material.pbrMetallicRoughness);
    markEmptyValuesOf(&material.pbrMetallicRoughness.baseColorTexture);
    markEmptyValuesOf(&material.pbrMetallicRoughness.metallicRoughnessTexture);
    markEmptyValuesOf(&material.normalTexture);
    markEmptyValuesOf(&material.occlusionTexture);
    markEmptyValuesOf(&material.emissiveTexture);
  }
  for (tinygltf::Mesh& mesh : model->meshes) {
    markEmptyValuesOf(&mesh);
    markEmptyValuesOfEach(&mesh.primitives);
  }
  for (tinygltf::Camera& camera : model->cameras) {
    markEmptyValuesOf(&camera);
    markEmptyValuesOf(&camera.perspective);
    markEmptyValuesOf(&camera.orthographic);
  }
  for (tinygltf::Light& light : model->lights) {
    markEmptyValuesOf(&light);
    markEmptyValuesOf(&light.spot);
  }
}

// The JSON text with every marker replaced by what it stands for (a marker is a JSON string token, so
// it cannot appear by accident inside another string: its quotes would be escaped there).
void restoreEmptyValues(std::string* json) {
  for (const auto& [marker, empty] : {std::pair<const char*, const char*>{kEmptyObjectMarker, "{}"}, {kEmptyArrayMarker, "[]"}}) {
    const size_t length = std::strlen(marker);
    for (size_t at = json->find(marker); at != std::string::npos; at = json->find(marker, at + 2)) json->replace(at, length, empty);
  }
}

// Appends everything written to it to a string the caller owns, so the serialized bytes are not
// copied out of an ostringstream a second time.
class StringAppender : public std::streambuf {
 public:
  explicit StringAppender(std::string* out) : out_(out) {}

 protected:
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) out_->push_back(traits_type::to_char_type(c));
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* data, std::streamsize size) override {
    out_->append(data, static_cast<size_t>(size));
    return size;
  }

 private:
  std::string* out_;
};

// tinygltf's serialization of `model` (its buffers' data embedded as base64 in JSON, or in the BIN chunk
// of a GLB), images as they are in their buffer views.
std::string tinygltfBytes(const tinygltf::Model& model, bool binary) {
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(nullptr, nullptr);
  std::string bytes;
  StringAppender appender(&bytes);
  std::ostream stream(&appender);
  if (!writer.WriteGltfSceneToStream(&model, stream, /*prettyPrint=*/!binary, /*writeBinary=*/binary))
    fail(errc::INTERNAL, "", "tinygltf could not serialize the model");
  return bytes;
}

void writeLittleEndian32(std::string* out, size_t offset, uint32_t value) {
  for (int b = 0; b < 4; ++b) (*out)[offset + b] = static_cast<char>((value >> (8 * b)) & 0xff);
}

// tinygltf's GLB bytes for `model` with buffer 0 empty, reassembled with the BIN chunk `layout` lays
// out. The JSON is tinygltf's, but for buffer 0's byteLength, which it writes as 0 (the size of the
// data it was given) and which becomes the merged size: tinygltf writes a buffer with no name or
// extras as {"byteLength":N}, the first element of the top-level "buffers" array.
std::string assembleGlb(const StandAlone& layout) {
  std::string empty_glb = tinygltfBytes(layout.model, /*binary=*/true);
  // Header (12 bytes), JSON chunk length and type (8), then the JSON padded with spaces.
  uint32_t json_chunk = 0;
  for (int b = 0; b < 4; ++b) json_chunk |= static_cast<uint32_t>(static_cast<unsigned char>(empty_glb[12 + b])) << (8 * b);
  std::string json = empty_glb.substr(20, json_chunk);
  while (!json.empty() && json.back() == ' ') json.pop_back();
  restoreEmptyValues(&json);
  std::string().swap(empty_glb);
  if (!layout.model.buffers.empty()) {
    const std::string placeholder = "\"buffers\":[{\"byteLength\":0}]";
    size_t at = std::string::npos;
    int depth = 0;
    bool in_string = false, escaped = false;
    for (size_t i = 0; i < json.size() && at == std::string::npos; ++i) {
      const char c = json[i];
      if (in_string) {
        if (escaped) escaped = false;
        else if (c == '\\') escaped = true;
        else if (c == '"') in_string = false;
      } else if (c == '"') {
        if (depth == 1 && json.compare(i, placeholder.size(), placeholder) == 0) at = i;
        in_string = true;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if (c == '}' || c == ']') {
        --depth;
      }
    }
    if (at == std::string::npos) fail(errc::INTERNAL, "", "tinygltf wrote the merged buffer in an unexpected form");
    const std::string length_key = "\"buffers\":[{\"byteLength\":";
    json.replace(at + length_key.size(), 1, std::to_string(layout.bin_size));
  }
  const size_t json_padded = (json.size() + 3) / 4 * 4;
  const size_t bin_padded = (layout.bin_size + 3) / 4 * 4;
  const size_t total = 12 + 8 + json_padded + (layout.bin_size > 0 ? 8 + bin_padded : 0);
  std::string glb;
  glb.reserve(total);
  glb.append("glTF", 4);
  glb.append(8, '\0');
  writeLittleEndian32(&glb, 4, 2);
  writeLittleEndian32(&glb, 8, static_cast<uint32_t>(total));
  glb.append(8, '\0');
  writeLittleEndian32(&glb, 12, static_cast<uint32_t>(json_padded));
  writeLittleEndian32(&glb, 16, 0x4E4F534A);  // "JSON"
  glb.append(json);
  glb.append(json_padded - json.size(), ' ');
  if (layout.bin_size > 0) {
    const size_t chunk = glb.size();
    glb.append(8, '\0');
    writeLittleEndian32(&glb, chunk, static_cast<uint32_t>(bin_padded));
    writeLittleEndian32(&glb, chunk + 4, 0x004E4942);  // "BIN"
    const size_t bin = glb.size();
    glb.append(bin_padded, '\0');  // the alignment padding between pieces and at the end stays zero
    for (const BinPiece& piece : layout.pieces)
      if (piece.size > 0) std::memcpy(&glb[bin + piece.offset], piece.data, piece.size);
  }
  return glb;
}

}  // namespace

bool isBinaryGltfPath(const std::string& path) { return endsWith(path, ".glb") || endsWith(path, ".vrm"); }

bool glbUsesExtension(const std::string& glb, const std::string& extension) {
  if (glb.size() < 20) return false;
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, glb.data() + 12, 4);
  const std::string json = glb.substr(20, std::min<size_t>(json_length, glb.size() - 20));
  return json.find("\"" + extension + "\"") != std::string::npos;
}

std::string glbOf(const std::string& path, const GltfDocument& document) {
  if (!isBinaryGltfPath(path)) return serializeGltf(modelOf(document), true);
  return readFile(path);
}

std::string serializeGltf(tinygltf::Model model, bool binary) {
  markEmptyValuesInModel(&model);
  StandAlone layout = standAloneLayout(std::move(model));
  if (binary) return assembleGlb(layout);
  // A .gltf embeds the buffer as base64: tinygltf needs the merged bytes in the model.
  if (!layout.model.buffers.empty()) {
    std::vector<unsigned char>& bytes = layout.model.buffers[0].data;
    bytes.assign(layout.bin_size, 0);
    for (const BinPiece& piece : layout.pieces)
      if (piece.size > 0) std::memcpy(bytes.data() + piece.offset, piece.data, piece.size);
  }
  std::vector<tinygltf::Buffer>().swap(layout.sources);
  std::string text = tinygltfBytes(layout.model, /*binary=*/false);
  restoreEmptyValues(&text);
  return text;
}

void writeGltf(tinygltf::Model model, const std::string& path) {
  writeFileAtomically(path, serializeGltf(std::move(model), isBinaryGltfPath(path)));
}

}  // namespace rigbake
