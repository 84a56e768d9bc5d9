#include "formats/gltf_clips.h"

#include <tiny_gltf.h>

#include <cassert>
#include <map>

#include "formats/gltf_buffer.h"

namespace rigbake {
namespace {

const char* interpolationName(Interpolation interpolation) {
  switch (interpolation) {
    case Interpolation::kLinear: return "LINEAR";
    case Interpolation::kStep: return "STEP";
    case Interpolation::kCubicSpline: return "CUBICSPLINE";
  }
  return "LINEAR";
}

const char* pathName(AnimatedPath path) {
  switch (path) {
    case AnimatedPath::kTranslation: return "translation";
    case AnimatedPath::kRotation: return "rotation";
    case AnimatedPath::kScale: return "scale";
  }
  return "rotation";
}

}  // namespace

tinygltf::Model modelWithClips(const GltfDocument& document, const Character& character,
                               const std::vector<Clip>& clips) {
  tinygltf::Model model = modelOf(document);
  GltfBufferAppender data(&model);
  for (const Clip& clip : clips) {
    if (clip.measure_only || clip.tracks.empty()) continue;
    tinygltf::Animation animation;
    animation.name = clip.name;
    std::map<std::vector<double>, int> inputs;  // key times -> accessor
    for (const Track& track : clip.tracks) {
      assert(track.joint >= 0 && track.joint < character.skeleton.size() && !track.times.empty());
      auto input = inputs.find(track.times);
      if (input == inputs.end()) {
        const std::vector<float> times(track.times.begin(), track.times.end());
        input = inputs.emplace(track.times, data.addFloats(times, TINYGLTF_TYPE_SCALAR, 1, true)).first;
      }
      const bool rotation = track.path == AnimatedPath::kRotation;
      std::vector<float> values;
      values.reserve(track.values.size());
      for (size_t i = 0; i < track.values.size(); i += rotation ? 4 : 3) {
        if (rotation && track.interpolation != Interpolation::kCubicSpline) {
          // Unit length as floats, as the validator checks it (spline tangents are not unit).
          Eigen::Vector4d q(track.values[i], track.values[i + 1], track.values[i + 2], track.values[i + 3]);
          q.normalize();
          for (int c = 0; c < 4; ++c) values.push_back(static_cast<float>(q[c]));
        } else {
          for (int c = 0; c < (rotation ? 4 : 3); ++c) values.push_back(static_cast<float>(track.values[i + c]));
        }
      }
      tinygltf::AnimationSampler sampler;
      sampler.input = input->second;
      sampler.output = data.addFloats(values, rotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, rotation ? 4 : 3);
      sampler.interpolation = interpolationName(track.interpolation);
      animation.samplers.push_back(sampler);
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
      channel.target_node = character.skeleton.nodes[track.joint];
      channel.target_path = pathName(track.path);
      animation.channels.push_back(channel);
    }
    model.animations.push_back(animation);
  }
  return model;
}

}  // namespace rigbake
