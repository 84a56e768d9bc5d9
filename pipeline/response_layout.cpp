// The response fit's keys and amplitudes (pipeline/response_layout.h).
#include "pipeline/response_layout.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "pipeline/response_fit.h"

namespace rigbake {
namespace {

constexpr double kQuarterTurn = 3.14159265358979323846 / 2.0;

// A quarter turn each way, and half the largest twist the poses reach each way (`most_negative`,
// `most_positive`, quarter turns) where that is at least 5 degrees and short of a quarter turn.
DriverKeys twistKeys(double most_negative, double most_positive) {
  constexpr double kMinHalf = 5.0 / 90.0;  // a twist the poses reach less than 10 degrees gets no half key
  DriverKeys keys;
  keys.add(-1.0, kTwistNegative);
  if (0.5 * most_negative >= kMinHalf && most_negative < 1.0) keys.add(-0.5 * most_negative, kHalfTwistNegative);
  keys.add(0.0, -1);
  if (0.5 * most_positive >= kMinHalf && most_positive < 1.0) keys.add(0.5 * most_positive, kHalfTwistPositive);
  keys.add(1.0, kTwistPositive);
  return keys;
}

// The hat weights of the piecewise-linear curve through `keys` at `x` (rest has none).
void addHatWeights(const DriverKeys& keys, double x, double weights[]) {
  const size_t count = keys.at.size();
  if (count < 2) return;
  size_t j = 0;  // at[j] <= x <= at[j + 1]
  while (j + 2 < count && keys.at[j + 1] <= x) ++j;
  const double lower = keys.at[j], upper = keys.at[j + 1];
  const double t = upper > lower ? std::clamp((x - lower) / (upper - lower), 0.0, 1.0) : 0.0;
  if (keys.key[j] >= 0) weights[keys.key[j]] = 1.0 - t;
  if (keys.key[j + 1] >= 0) weights[keys.key[j + 1]] = t;
}

// Full compression, kBetweenKeys keys spread evenly from rest to the deepest ratio the poses reach
// (`least`; those distinct from rest and from the full key), rest, and one stretch key at the longest
// ratio the poses reach (`most`; full stretch when they barely stretch the muscle). Beyond the last
// key the response holds, so a pose stretched further than the clips keeps the fitted thinning
// instead of extrapolating it.
DriverKeys ratioKeys(double compression, double stretch, double least, double most, bool between_stretch) {
  constexpr double kMinSpan = 0.02;   // a muscle the poses compress less than this keeps its full key only
  constexpr double kDistinct = 1e-3;  // ratios closer than this make one key
  DriverKeys keys;
  if (compression < 1.0) {
    keys.add(compression, kCompressed);
    const double deepest = std::max(least, compression);
    if (1.0 - deepest >= kMinSpan) {
      for (int k = kBetweenKeys; k >= 1; --k) {
        const double at = 1.0 - (1.0 - deepest) * k / kBetweenKeys;
        if (at - keys.at.back() >= kDistinct) keys.add(at, kFirstCompressing + kBetweenKeys - k);
      }
    }
  }
  keys.add(1.0, -1);
  if (stretch <= 1.0) return keys;
  const double longest = most - 1.0 >= kMinSpan ? std::min(most, stretch) : stretch;
  if (between_stretch && most - 1.0 >= kMinSpan) {
    for (int k = 1; k <= kBetweenKeys; ++k) {
      const double at = 1.0 + (longest - 1.0) * k / (kBetweenKeys + 1);
      if (at - keys.at.back() >= kDistinct) keys.add(at, kFirstStretching + k - 1);
    }
  }
  keys.add(longest, kStretched);
  return keys;
}

}  // namespace

double sideTwist(const MusclePart& part, const runtime::MuscleDrivers<double>& drivers) {
  return std::clamp((part.side == "Right" ? -drivers.twist : drivers.twist) / kQuarterTurn, -1.0, 1.0);
}

KeyShape keyShape(const MusclePart& part, int key, double stretched_at) {
  if (part.kind == PartKind::kCorrective) return isTwistKey(key) ? KeyShape{} : KeyShape{part.bulge.x(), part.bulge.y(), 0.0};
  const double bulge_scale = part.compression < 1.0 ? 1.0 / std::sqrt(part.compression) - 1.0 : 0.0;
  if (isStretchKey(key)) return {0.0, 0.0, 1.0 / std::sqrt(stretched_at) - 1.0};
  if (isTwistKey(key)) return {part.bulge.x(), 0.0, bulge_scale};
  return {part.bulge.x(), part.bulge.y(), bulge_scale};  // compression keys
}

void keyWeights(const MusclePart& part, const DriverKeys& ratio, const DriverKeys& twist,
                const runtime::MuscleDrivers<double>& drivers, double weights[kKeys]) {
  for (int k = 0; k < kKeys; ++k) weights[k] = 0.0;
  addHatWeights(ratio, drivers.clamped_ratio, weights);
  addHatWeights(twist, sideTwist(part, drivers), weights);
}

ResponseLayout layoutResponses(const MuscleSet& muscles, const std::vector<char>& fit,
                               const std::vector<std::vector<runtime::MuscleDrivers<double>>>& pose_drivers) {
  const int muscle_count = static_cast<int>(muscles.parts.size());
  ResponseLayout layout;
  std::map<std::string, int> kind_of_name;
  layout.kind.assign(muscle_count, -1);
  for (int m = 0; m < muscle_count; ++m) {
    if (fit[m]) layout.kind[m] = kind_of_name.emplace(muscles.parts[m].name, static_cast<int>(kind_of_name.size())).first->second;
  }
  const int kinds = static_cast<int>(kind_of_name.size());
  layout.kinds = kinds;
  const std::vector<int>& kind = layout.kind;
  layout.corrective.assign(kinds, 0);
  for (int m = 0; m < muscle_count; ++m) {
    if (kind[m] >= 0) layout.corrective[kind[m]] = muscles.parts[m].kind == PartKind::kCorrective;
  }
  // Each kind's keys from the deepest compression, longest stretch and largest twists its parts reach.
  std::vector<double> least(kinds, 1.0), most(kinds, 1.0), most_negative(kinds, 0.0), most_positive(kinds, 0.0);
  for (const auto& drivers : pose_drivers) {
    for (int m = 0; m < muscle_count; ++m) {
      if (kind[m] < 0) continue;
      least[kind[m]] = std::min(least[kind[m]], drivers[m].clamped_ratio);
      most[kind[m]] = std::max(most[kind[m]], drivers[m].clamped_ratio);
      const double twist = sideTwist(muscles.parts[m], drivers[m]);
      most_negative[kind[m]] = std::max(most_negative[kind[m]], -twist);
      most_positive[kind[m]] = std::max(most_positive[kind[m]], twist);
    }
  }
  layout.twist_keys.resize(kinds);
  for (int k = 0; k < kinds; ++k) {
    if (!layout.corrective[k]) layout.twist_keys[k] = twistKeys(most_negative[k], most_positive[k]);
  }
  layout.ratio_keys.resize(kinds);
  for (int m = 0; m < muscle_count; ++m) {
    if (kind[m] >= 0)
      layout.ratio_keys[kind[m]] = ratioKeys(muscles.parts[m].compression, muscles.parts[m].stretch, least[kind[m]], most[kind[m]],
                                             layout.corrective[kind[m]] != 0);
  }
  layout.stretched_at.assign(kinds, 1.0);
  for (int k = 0; k < kinds; ++k) {
    const DriverKeys& keys = layout.ratio_keys[k];
    for (size_t j = 0; j < keys.at.size(); ++j) {
      if (keys.key[j] == kStretched) layout.stretched_at[k] = keys.at[j];
    }
  }
  return layout;
}

Eigen::VectorXd talkAmplitudes(const ResponseLayout& layout, const MuscleSet& muscles) {
  Eigen::VectorXd talk = Eigen::VectorXd::Zero(layout.unknowns());
  for (size_t m = 0; m < muscles.parts.size(); ++m) {
    const int kind = layout.kind[m];
    if (kind < 0 || layout.corrective[kind]) continue;
    const DriverKeys& keys = layout.ratio_keys[kind];
    for (size_t j = 0; j < keys.at.size(); ++j) {
      if (keys.key[j] >= 0 && !isStretchKey(keys.key[j]))
        talk[kind * kKeys + keys.key[j]] = (1.0 - keys.at[j]) / (1.0 - muscles.parts[m].compression);
    }
  }
  return talk;
}

std::vector<double> keyReach(const ResponseLayout& layout, const MuscleSet& muscles,
                             const std::vector<std::vector<runtime::MuscleDrivers<double>>>& pose_drivers) {
  // The prior bounds the response the poses actually see, so a key the clips barely reach cannot grow
  // without limit, and a key they never reach keeps its prior value.
  const std::vector<int>& kind = layout.kind;
  const size_t muscle_count = muscles.parts.size();
  std::vector<double> reach(layout.unknowns(), 0.0);
  for (const auto& drivers : pose_drivers) {
    for (size_t m = 0; m < muscle_count; ++m) {
      if (kind[m] < 0) continue;
      double weights[kKeys];
      keyWeights(muscles.parts[m], layout.ratio_keys[kind[m]], layout.twist_keys[kind[m]], drivers[m], weights);
      for (int k = 0; k < kKeys; ++k) reach[kind[m] * kKeys + k] = std::max(reach[kind[m] * kKeys + k], weights[k]);
    }
  }
  // A stretch key sits where the poses are, so they reach it fully; its prior is measured in the talk's
  // full-stretch thinning instead (the thinning at the key over that at full stretch), as a key at
  // full stretch would be.
  for (size_t m = 0; m < muscle_count; ++m) {
    if (kind[m] < 0 || layout.corrective[kind[m]] || muscles.parts[m].stretch <= 1.0) continue;
    const double full = 1.0 - 1.0 / std::sqrt(muscles.parts[m].stretch);
    double& stretch_reach = reach[kind[m] * kKeys + kStretched];
    stretch_reach = std::min(stretch_reach, (1.0 - 1.0 / std::sqrt(layout.stretched_at[kind[m]])) / full);
  }
  return reach;
}

// A compression key's upper bound is max_amplitude where the poses compress the muscle at least 1/4
// as far as the talk's full compression, and falls in proportion nearer rest (docs/muscle-model.md).
constexpr double kCompressionBoundRise = 4.0;

HingeBounds amplitudeBounds(const ResponseLayout& layout, const Eigen::VectorXd& talk, const ResponseFitOptions& options) {
  const int unknowns = layout.unknowns();
  HingeBounds bounds;
  bounds.lower.resize(unknowns);
  bounds.upper.resize(unknowns);
  for (int u = 0; u < unknowns; ++u) {
    const int key = u % kKeys, kind = u / kKeys;
    if (layout.corrective[kind]) {
      bounds.lower[u] = -options.max_corrective_amplitude;
      bounds.upper[u] = options.max_corrective_amplitude;
    } else if (isTwistKey(key)) {
      bounds.lower[u] = -options.min_twist_amplitude;
      bounds.upper[u] = options.max_twist_amplitude;
    } else if (isStretchKey(key)) {
      // No thinner than min_stretch_scale across the fibre at the key.
      const double thinning = 1.0 - 1.0 / std::sqrt(layout.stretched_at[kind]);
      bounds.lower[u] = 0.0;
      bounds.upper[u] = thinning > 0.0 ? std::min(options.max_stretch_amplitude, (1.0 - options.min_stretch_scale) / thinning) : 0.0;
    } else {
      bounds.lower[u] = options.min_compression_fraction * talk[u];
      bounds.upper[u] = options.max_amplitude * std::min(1.0, kCompressionBoundRise * talk[u]);
    }
  }
  return bounds;
}

void applyAmplitudes(const ResponseLayout& layout, const Eigen::VectorXd& amplitudes, MuscleSet* muscles) {
  for (size_t m = 0; m < muscles->parts.size(); ++m) {
    const int kind = layout.kind[m];
    if (kind < 0) continue;
    MusclePart& part = muscles->parts[m];
    const double* a = amplitudes.data() + kind * kKeys;
    auto key = [&](double at, int which) {
      const KeyShape shape = keyShape(part, which, layout.stretched_at[kind]);
      return ResponseKey{at, a[which] * shape.up, a[which] * shape.side, 1.0 + a[which] * shape.scale};
    };
    MuscleResponse response;
    response.fitted = true;
    const DriverKeys& keys = layout.ratio_keys[kind];
    for (size_t j = 0; j < keys.at.size(); ++j)
      response.ratio.push_back(keys.key[j] < 0 ? ResponseKey{1.0, 0.0, 0.0, 1.0} : key(keys.at[j], keys.key[j]));
    // The right side's keys are the left's mirrored: its twist of +x is the left's -x. A corrective
    // has no twist curve.
    const DriverKeys& twist = layout.twist_keys[kind];
    const bool right = part.side == "Right";
    for (size_t j = 0; j < twist.at.size(); ++j) {
      const size_t i = right ? twist.at.size() - 1 - j : j;
      const double at = (right ? -twist.at[i] : twist.at[i]) * kQuarterTurn;
      response.twist.push_back(twist.key[i] < 0 ? ResponseKey{0.0, 0.0, 0.0, 1.0} : key(at, twist.key[i]));
    }
    part.response = response;
  }
}

}  // namespace rigbake
