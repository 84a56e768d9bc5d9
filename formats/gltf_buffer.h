// Appends binary data to a tinygltf model: one new buffer per appender, a buffer view and an accessor
// per call, 4-byte aligned as glTF requires of every component type rigbake writes. The sample
// writer and the bake both build their accessors through it.
#pragma once

#include <cstddef>
#include <vector>

namespace tinygltf {
class Model;
struct Animation;
}

namespace rigbake {

class GltfBufferAppender {
 public:
  // Adds an empty buffer at the end of model->buffers; writeGltf merges every buffer into a GLB's one.
  explicit GltfBufferAppender(tinygltf::Model* model);

  // Returns the accessor index. `target` 0 leaves the view's target unset; `min`/`max` are written
  // when non-empty.
  int addAccessor(const void* data, size_t bytes, int component_type, int type, size_t count, bool normalized,
                  int target, const std::vector<double>& min = {}, const std::vector<double>& max = {});

  template <typename T>
  int add(const std::vector<T>& values, int component_type, int type, size_t count, int target,
          const std::vector<double>& min = {}, const std::vector<double>& max = {}) {
    return addAccessor(values.data(), values.size() * sizeof(T), component_type, type, count, false, target, min, max);
  }

  // Float data of `components` per element; with_bounds writes min/max of the stored floats, as the
  // spec requires for POSITION and animation inputs.
  int addFloats(const std::vector<float>& values, int type, int components, bool with_bounds = false);

 private:
  tinygltf::Model* model_;
  int buffer_ = -1;
};

// A LINEAR sampler over the accessors `input` (times) and `output` (values), and the channel that
// drives `path` ("translation", "rotation", "scale") of `node` with it.
void addLinearChannel(int input, int output, int node, const char* path, tinygltf::Animation* animation);

// Component-wise bounds of float data, as the spec wants them: of the stored floats.
void floatBounds(const std::vector<float>& values, int width, std::vector<double>* min, std::vector<double>* max);

}  // namespace rigbake
