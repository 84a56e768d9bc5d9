// Figures of a baked file's skin that validate's report shows and its quality measures read
// (declared in pipeline/checks.h): how many influences the vertices use, and the skin matrices the
// file's own rig gives at a pose.
#include "pipeline/checks.h"

#include "pipeline/muscle_joint.h"
#include "pipeline/pose.h"

namespace rigbake {

std::vector<std::int64_t> influenceHistogram(const BakedFileData& file) {
  std::vector<std::int64_t> histogram;
  for (const FileSkinAttributes& skin : file.skins) {
    if (histogram.size() < static_cast<size_t>(skin.slots) + 1) histogram.resize(skin.slots + 1, 0);
    const int count = skin.slots ? static_cast<int>(skin.weights.size()) / skin.slots : 0;
    for (int v = 0; v < count; ++v) {
      int n = 0;
      for (int k = 0; k < skin.slots; ++k) n += skin.weights[static_cast<size_t>(v) * skin.slots + k] != 0.0;
      ++histogram[n];
    }
  }
  return histogram;
}

std::vector<Eigen::Affine3d> bakedSkinMatrices(const Character& character, const BakedFileData& file, const Pose& pose) {
  const Skeleton& skeleton = character.skeleton;
  std::vector<Eigen::Affine3d> matrices(skeleton.size());
  for (int j = 0; j < skeleton.size(); ++j) matrices[j] = pose.world[j] * skeleton.bind_world[j].inverse();
  if (file.rig.present && file.rig.problems.empty() && !file.rig.rig.muscles.empty()) {
    const RigEvaluation evaluation = evaluateRig(file.rig.rig, pose, false);
    for (size_t m = 0; m < file.rig.skinned_joint.size(); ++m) {
      const int joint = file.rig.skinned_joint[m];
      matrices[joint] = matrixAt(evaluation.skinned, m) * skeleton.bind_world[joint].inverse();
    }
  }
  return matrices;
}

}  // namespace rigbake
