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
#include <sstream>

#include "anatomy/error.h"
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

// Appends `size` bytes so that the new offset has the same remainder modulo 4 as `old_offset`: an
// accessor is valid when (bufferView.byteOffset + accessor.byteOffset) is a multiple of its component
// size (at most 4), and keeping the remainder keeps exactly the validity the source had.
size_t appendAligned(std::vector<unsigned char>* out, const unsigned char* data, size_t size, size_t old_offset) {
  while (out->size() % 4 != old_offset % 4) out->push_back(0);
  size_t offset = out->size();
  out->insert(out->end(), data, data + size);
  return offset;
}

// One buffer holding every buffer view, every image in a buffer view.
tinygltf::Model standAloneCopy(const tinygltf::Model& source) {
  tinygltf::Model model = source;
  std::vector<unsigned char> bytes;
  for (size_t v = 0; v < model.bufferViews.size(); ++v) {
    tinygltf::BufferView& view = model.bufferViews[v];
    std::string where = "/bufferViews/" + std::to_string(v);
    if (view.buffer < 0 || view.buffer >= static_cast<int>(source.buffers.size()))
      fail("GLTF_PARSE_FAILED", where, "refers to a missing buffer " + std::to_string(view.buffer));
    const std::vector<unsigned char>& data = source.buffers[view.buffer].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail("GLTF_PARSE_FAILED", where, "lies outside its buffer (" + std::to_string(data.size()) + " bytes)");
    view.byteOffset = appendAligned(&bytes, data.data() + view.byteOffset, view.byteLength, view.byteOffset);
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
      fail("INTERNAL", "/images/" + std::to_string(i),
           "the image holds decoded pixels, not its file bytes; load it with the raw-bytes image loader");
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteLength = image.image.size();
    view.byteOffset = appendAligned(&bytes, image.image.data(), image.image.size(), 0);
    view.name = image.name;
    model.bufferViews.push_back(view);
    image.bufferView = static_cast<int>(model.bufferViews.size()) - 1;
    image.mimeType = imageMimeType(image, image.image);
    image.uri.clear();
  }
  model.buffers.clear();
  if (!model.bufferViews.empty()) {
    tinygltf::Buffer buffer;
    buffer.data = std::move(bytes);
    model.buffers.push_back(std::move(buffer));
  }
  return model;
}

}  // namespace

bool isBinaryGltfPath(const std::string& path) { return endsWith(path, ".glb") || endsWith(path, ".vrm"); }

std::string glbOf(const std::string& path, const GltfDocument& document) {
  return isBinaryGltfPath(path) ? readFile(path) : serializeGltf(modelOf(document), true);
}

std::string serializeGltf(const tinygltf::Model& model, bool binary) {
  tinygltf::Model stand_alone = standAloneCopy(model);
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(nullptr, nullptr);
  std::ostringstream stream;
  if (!writer.WriteGltfSceneToStream(&stand_alone, stream, /*prettyPrint=*/!binary, binary))
    fail("INTERNAL", "", "tinygltf could not serialize the model");
  return stream.str();
}

void writeGltf(const tinygltf::Model& model, const std::string& path) {
  writeFileAtomically(path, serializeGltf(model, isBinaryGltfPath(path)));
}

}  // namespace rigbake
