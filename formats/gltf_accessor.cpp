#include "formats/gltf_accessor.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>

#include "core/error.h"

namespace rigbake {
namespace {


int componentSize(int component_type) {
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

template <typename T>
T load(const unsigned char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

double decode(const unsigned char* p, int component_type, bool normalized) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      double v = load<int8_t>(p);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      double v = load<uint8_t>(p);
      return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      double v = load<int16_t>(p);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      double v = load<uint16_t>(p);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return load<uint32_t>(p);
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return load<float>(p);
    default: return 0.0;
  }
}

// Returns the first byte of element 0 and the stride, checking the whole range lies in the buffer.
const unsigned char* viewRange(const tinygltf::Model& model, int buffer_view, size_t byte_offset, int count,
                               size_t element_size, size_t* stride, const std::string& where,
                               const std::string& what) {
  if (buffer_view < 0 || buffer_view >= static_cast<int>(model.bufferViews.size()))
    fail(errc::GLTF_ACCESSOR_INVALID, where, what + " refers to a missing bufferView");
  const tinygltf::BufferView& view = model.bufferViews[buffer_view];
  if (view.buffer < 0 || view.buffer >= static_cast<int>(model.buffers.size()))
    fail(errc::GLTF_ACCESSOR_INVALID, where, what + " refers to a missing buffer");
  const std::vector<unsigned char>& data = model.buffers[view.buffer].data;
  *stride = view.byteStride ? view.byteStride : element_size;
  size_t span = count == 0 ? 0 : byte_offset + *stride * (count - 1) + element_size;
  if (span > view.byteLength || view.byteOffset + view.byteLength > data.size())
    fail(errc::GLTF_ACCESSOR_INVALID, where, what + " reads past the end of its buffer (file truncated?)");
  return data.data() + view.byteOffset + byte_offset;
}

}  // namespace

int accessorComponentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

AccessorData readAccessor(const tinygltf::Model& model, int accessor_index, const std::string& where) {
  const std::string what = "/accessors/" + std::to_string(accessor_index);
  if (accessor_index < 0 || accessor_index >= static_cast<int>(model.accessors.size()))
    fail(errc::GLTF_ACCESSOR_INVALID, where, what + " does not exist");
  const tinygltf::Accessor& accessor = model.accessors[accessor_index];
  AccessorData out;
  out.components = accessorComponentCount(accessor.type);
  int size = componentSize(accessor.componentType);
  if (out.components == 0 || size == 0) fail(errc::GLTF_ACCESSOR_INVALID, where, what + " has an unknown type");
  if (accessor.count > (1 << 28)) fail(errc::GLTF_ACCESSOR_INVALID, where, what + " has an implausible count");
  out.count = static_cast<int>(accessor.count);
  out.values.assign(static_cast<size_t>(out.count) * out.components, 0.0);
  size_t element_size = static_cast<size_t>(size) * out.components;

  if (accessor.bufferView >= 0) {
    size_t stride = 0;
    const unsigned char* base = viewRange(model, accessor.bufferView, accessor.byteOffset, out.count, element_size,
                                          &stride, where, what);
    for (int i = 0; i < out.count; ++i) {
      for (int c = 0; c < out.components; ++c) {
        out.values[static_cast<size_t>(i) * out.components + c] =
            decode(base + stride * i + static_cast<size_t>(size) * c, accessor.componentType, accessor.normalized);
      }
    }
  }
  if (accessor.sparse.isSparse) {
    const auto& sparse = accessor.sparse;
    int n = sparse.count;
    size_t index_stride = 0, value_stride = 0;
    int index_size = componentSize(sparse.indices.componentType);
    if (index_size == 0 || n < 0 || n > out.count)
      fail(errc::GLTF_ACCESSOR_INVALID, where, what + "/sparse is malformed");
    const unsigned char* indices = viewRange(model, sparse.indices.bufferView, sparse.indices.byteOffset, n,
                                             index_size, &index_stride, where, what + "/sparse/indices");
    const unsigned char* values = viewRange(model, sparse.values.bufferView, sparse.values.byteOffset, n,
                                            element_size, &value_stride, where, what + "/sparse/values");
    for (int k = 0; k < n; ++k) {
      double index = decode(indices + index_stride * k, sparse.indices.componentType, false);
      if (index < 0 || index >= out.count) fail(errc::GLTF_ACCESSOR_INVALID, where, what + "/sparse index out of range");
      for (int c = 0; c < out.components; ++c) {
        out.values[static_cast<size_t>(index) * out.components + c] =
            decode(values + value_stride * k + static_cast<size_t>(size) * c, accessor.componentType,
                   accessor.normalized);
      }
    }
  }
  return out;
}

}  // namespace rigbake
