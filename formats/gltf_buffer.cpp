#include "formats/gltf_buffer.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <limits>

namespace rigbake {

GltfBufferAppender::GltfBufferAppender(tinygltf::Model* model) : model_(model) {
  buffer_ = static_cast<int>(model->buffers.size());
  model->buffers.emplace_back();
}

int GltfBufferAppender::addAccessor(const void* data, size_t bytes, int component_type, int type, size_t count,
                                    bool normalized, int target, const std::vector<double>& min,
                                    const std::vector<double>& max) {
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

int GltfBufferAppender::addFloats(const std::vector<float>& values, int type, int components, bool with_bounds) {
  std::vector<double> min, max;
  if (with_bounds) floatBounds(values, components, &min, &max);
  return addAccessor(values.data(), values.size() * sizeof(float), TINYGLTF_COMPONENT_TYPE_FLOAT, type,
                     values.size() / components, false, 0, min, max);
}

void floatBounds(const std::vector<float>& values, int width, std::vector<double>* min, std::vector<double>* max) {
  min->assign(width, std::numeric_limits<double>::infinity());
  max->assign(width, -std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < values.size(); ++i) {
    (*min)[i % width] = std::min((*min)[i % width], static_cast<double>(values[i]));
    (*max)[i % width] = std::max((*max)[i % width], static_cast<double>(values[i]));
  }
}

void addLinearChannel(int input, int output, int node, const char* path, tinygltf::Animation* animation) {
  tinygltf::AnimationSampler sampler;
  sampler.input = input;
  sampler.output = output;
  sampler.interpolation = "LINEAR";
  animation->samplers.push_back(sampler);
  tinygltf::AnimationChannel channel;
  channel.sampler = static_cast<int>(animation->samplers.size()) - 1;
  channel.target_node = node;
  channel.target_path = path;
  animation->channels.push_back(channel);
}

}  // namespace rigbake
