// The poses the response fit solves over (pipeline/response_fit.h chooseFitPoses): farthest-point
// sampling in the muscles' drivers, measured on the mannequin's own clips against poses spaced evenly
// in time, as the fit took them before.
#include <algorithm>
#include <cmath>

#include "anatomy_fixture.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/response_fit.h"

using namespace rigbake;

namespace {

struct FitPoseCandidates {
  std::vector<int> clip;  // per candidate
  std::vector<std::vector<double>> features;
};

FitPoseCandidates mannequinCandidates() {
  test::Resolved r = test::resolveShipped(test::sampleGlbPath());
  const MuscleSet muscles = placeMuscles(r.character, r.landmarks, test::gowPreset(), Sides::kBoth);
  const runtime::MuscleRig<double> rig = buildMuscleRig(muscles, r.character.skeleton);
  const std::vector<char> fit(muscles.parts.size(), 1);
  FitPoseCandidates out;
  for (size_t c = 0; c < r.character.clips.size(); ++c) {
    for (double time : sampleTimes(r.character.clips[c], 0.0)) {
      out.clip.push_back(static_cast<int>(c));
      out.features.push_back(driverFeatures(rig, muscles, fit, sampleClip(r.character.skeleton, r.character.clips[c], time)));
    }
  }
  return out;
}

double distanceBetween(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0.0;
  for (size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(sum);
}

// The farthest any candidate is from its nearest chosen pose: how much of the drivers' range the
// chosen poses leave out.
double coveringRadius(const std::vector<std::vector<double>>& features, const std::vector<size_t>& chosen) {
  double radius = 0.0;
  for (const std::vector<double>& f : features) {
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t i : chosen) nearest = std::min(nearest, distanceBetween(f, features[i]));
    radius = std::max(radius, nearest);
  }
  return radius;
}

}  // namespace

TEST_CASE("fit poses: 64 of the mannequin's frames, the extremes first, closer to every frame than even spacing") {
  const FitPoseCandidates candidates = mannequinCandidates();
  const size_t n = candidates.features.size();
  REQUIRE(n == 183);  // ArmRaise, ElbowFlexion and ForearmTwist at 30 fps
  REQUIRE(candidates.features[0].size() == 2 * 38);  // 28 muscles and 10 correctives: ratio and twist

  const std::vector<size_t> chosen = chooseFitPoses(candidates.features, 64);
  REQUIRE(chosen.size() == 64);
  CHECK(std::is_sorted(chosen.begin(), chosen.end()));
  CHECK(std::adjacent_find(chosen.begin(), chosen.end()) == chosen.end());
  CHECK(chooseFitPoses(candidates.features, 64) == chosen);  // the same every time

  // The pose farthest from rest is in, and every clip has poses.
  const std::vector<double> rest(candidates.features[0].size(), 0.0);
  size_t farthest = 0;
  for (size_t i = 0; i < n; ++i) {
    if (distanceBetween(candidates.features[i], rest) > distanceBetween(candidates.features[farthest], rest)) farthest = i;
  }
  CHECK(std::binary_search(chosen.begin(), chosen.end(), farthest));
  for (int c = 0; c < 3; ++c) {
    INFO("clip " << c);
    CHECK(std::count_if(chosen.begin(), chosen.end(), [&](size_t i) { return candidates.clip[i] == c; }) >= 10);
  }

  // Every frame is nearer a chosen pose than with 64 poses spaced evenly in time.
  std::vector<size_t> even;
  for (size_t i = 0; i < 64; ++i) even.push_back(i * n / 64);
  const double radius = coveringRadius(candidates.features, chosen), even_radius = coveringRadius(candidates.features, even);
  INFO("covering radius: chosen " << radius << ", even " << even_radius);
  CHECK(radius < 0.75 * even_radius);

  // No more candidates than asked for: all of them, in order.
  const std::vector<std::vector<double>> few(candidates.features.begin(), candidates.features.begin() + 10);
  const std::vector<size_t> all = chooseFitPoses(few, 64);
  REQUIRE(all.size() == 10);
  for (size_t i = 0; i < all.size(); ++i) CHECK(all[i] == i);
}
