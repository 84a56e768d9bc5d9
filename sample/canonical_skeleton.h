// The mannequin's joint table in its plain variant (God of War Ragnarök names, T-pose, world
// positions), which sample/sample_character.cpp turns into the public SampleCharacter and
// sample/sample_mesh.cpp skins its body to. Internal to sample/: its users include the public
// sample/sample_character.h.
#pragma once

#include <Eigen/Core>
#include <cassert>
#include <string>
#include <vector>

namespace rigbake::sample_internal {

inline constexpr double kPi = 3.14159265358979323846;

// Reflection across the sagittal plane x = 0: the body's left and right are exact mirror images.
inline Eigen::Vector3d mirrorX(const Eigen::Vector3d& p) { return {-p.x(), p.y(), p.z()}; }

// Joint table of the plain variant: central joints, the left arm, the right arm, the left leg, the
// right leg. Keeping each side's chain contiguous keeps parents before children.
struct CanonicalSkeleton {
  std::vector<std::string> names;
  std::vector<int> parents;
  std::vector<Eigen::Vector3d> world;
  std::vector<int> mirror;

  int find(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i) {
      if (names[i] == name) return static_cast<int>(i);
    }
    return -1;
  }
  int at(const std::string& name) const {
    int index = find(name);
    assert(index >= 0);
    return index;
  }
};

CanonicalSkeleton buildCanonicalSkeleton();

}  // namespace rigbake::sample_internal
