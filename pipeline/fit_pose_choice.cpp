#include "pipeline/fit_pose_choice.h"

#include <algorithm>

namespace rigbake {

std::vector<size_t> chooseFitPoses(const std::vector<std::vector<double>>& features, size_t count) {
  const size_t n = features.size();
  std::vector<size_t> chosen;
  if (n <= count) {
    for (size_t i = 0; i < n; ++i) chosen.push_back(i);
    return chosen;
  }
  auto squaredDistance = [](const std::vector<double>& a, const std::vector<double>& b) {
    double sum = 0.0;
    for (size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
    return sum;
  };
  // Distance to the nearest pose taken; rest (all features zero) counts as taken, so the first pose is
  // the one farthest from it. Ties go to the earlier candidate, and distances within kTieTolerance of
  // each other tie: the features carry the last bits of sums over the skin, which change with the
  // vertices' order, and one pose taken elsewhere moved a region of the fitted Male Casual by 1.6 points.
  constexpr double kTieTolerance = 1e-9;
  std::vector<double> nearest(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    for (double f : features[i]) nearest[i] += f * f;
  }
  std::vector<char> taken(n, 0);
  for (size_t c = 0; c < count; ++c) {
    size_t next = n;
    for (size_t i = 0; i < n; ++i) {
      if (!taken[i] && (next == n || nearest[i] > nearest[next] * (1.0 + kTieTolerance))) next = i;
    }
    taken[next] = 1;
    chosen.push_back(next);
    for (size_t i = 0; i < n; ++i) nearest[i] = std::min(nearest[i], squaredDistance(features[i], features[next]));
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace rigbake
