#include "anatomy/character.h"

namespace rigbake {

Eigen::Affine3d Trs::matrix() const {
  Eigen::Affine3d m = Eigen::Affine3d::Identity();
  m.translate(translation);
  m.rotate(rotation.normalized());
  m.scale(scale);
  return m;
}

int Skeleton::find(const std::string& name) const {
  for (int i = 0; i < size(); ++i) {
    if (names[i] == name) return i;
  }
  return -1;
}

std::vector<int> Skeleton::children(int joint) const {
  std::vector<int> result;
  for (int i = 0; i < size(); ++i) {
    if (parents[i] == joint) result.push_back(i);
  }
  return result;
}

}  // namespace rigbake
