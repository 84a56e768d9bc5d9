// Numeric helpers shared by the transform tests.
#pragma once

#include <Eigen/Geometry>

namespace rigbake::test {

constexpr double kPi = 3.14159265358979323846;

// Largest absolute difference between the entries of two transforms.
inline double maxDifference(const Eigen::Affine3d& a, const Eigen::Affine3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

}  // namespace rigbake::test
