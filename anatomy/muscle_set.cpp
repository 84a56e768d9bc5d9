#include "anatomy/muscle_set.h"

#include <cmath>

#include "anatomy/character.h"

namespace rigbake {

MuscleResponse defaultMuscleResponse(double compression, double stretch, const Eigen::Vector2d& bulge) {
  MuscleResponse response;
  if (compression < 1.0) response.ratio.push_back({compression, bulge.x(), bulge.y(), 1.0 / std::sqrt(compression)});
  response.ratio.push_back({1.0, 0.0, 0.0, 1.0});
  if (stretch > 1.0) response.ratio.push_back({stretch, 0.0, 0.0, 1.0});
  return response;
}

MuscleResponse defaultResponse(const MusclePart& part) {
  if (part.kind == PartKind::kMuscle) return defaultMuscleResponse(part.compression, part.stretch, part.bulge);
  MuscleResponse none;
  if (part.compression < 1.0) none.ratio.push_back({part.compression, 0.0, 0.0, 1.0});
  none.ratio.push_back({1.0, 0.0, 0.0, 1.0});
  if (part.stretch > 1.0) none.ratio.push_back({part.stretch, 0.0, 0.0, 1.0});
  return none;
}

const char* partKindName(PartKind kind) { return kind == PartKind::kCorrective ? "corrective" : "muscle"; }

bool parsePartKind(const std::string& name, PartKind* kind) {
  for (PartKind candidate : {PartKind::kMuscle, PartKind::kCorrective}) {
    if (name == partKindName(candidate)) {
      *kind = candidate;
      return true;
    }
  }
  return false;
}

namespace {
// Linear interpolation of a curve at `at`, as runtime/muscle_rig.cpp evaluates it.
ResponseKey curveAt(const std::vector<ResponseKey>& keys, double at) {
  if (keys.empty()) return {at, 0.0, 0.0, 1.0};
  if (at <= keys.front().at) return keys.front();
  if (at >= keys.back().at) return keys.back();
  size_t k = 1;
  while (keys[k].at < at) ++k;
  const ResponseKey& a = keys[k - 1];
  const ResponseKey& b = keys[k];
  const double t = (at - a.at) / (b.at - a.at);
  return {at, a.up + t * (b.up - a.up), a.side + t * (b.side - a.side), a.scale + t * (b.scale - a.scale)};
}

std::string curveProblem(const std::vector<ResponseKey>& keys, const char* name, double rest) {
  for (size_t k = 0; k < keys.size(); ++k) {
    const ResponseKey& key = keys[k];
    if (!std::isfinite(key.at) || !std::isfinite(key.up) || !std::isfinite(key.side) || !std::isfinite(key.scale))
      return std::string(name) + " key " + std::to_string(k) + " is not finite";
    if (!(key.scale > 0.0)) return std::string(name) + " key " + std::to_string(k) + " has a scale that is not positive";
    if (k > 0 && !(key.at > keys[k - 1].at)) return std::string(name) + " keys are not in ascending order";
  }
  const ResponseKey at_rest = curveAt(keys, rest);
  if (std::abs(at_rest.up) > 1e-9 || std::abs(at_rest.side) > 1e-9 || std::abs(at_rest.scale - 1.0) > 1e-9)
    return std::string(name) + " curve is not at rest (bulge 0, scale 1) at " + (rest == 0.0 ? "twist 0" : "ratio 1") +
           ", so the bind pose would move";
  return "";
}
}  // namespace

std::string muscleResponseProblem(const MuscleResponse& response) {
  std::string problem = curveProblem(response.ratio, "ratio", 1.0);
  if (problem.empty()) problem = curveProblem(response.twist, "twist", 0.0);
  return problem;
}

const std::vector<int>& spannedHierarchy(const MuscleSet& muscles, const Skeleton& skeleton) {
  return muscles.anatomical_parents.size() == skeleton.parents.size() ? muscles.anatomical_parents : skeleton.parents;
}

}  // namespace rigbake
