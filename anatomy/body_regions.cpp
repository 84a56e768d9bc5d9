#include "anatomy/body_regions.h"

#include <algorithm>
#include <map>
#include <set>

#include "anatomy/point_formula.h"

namespace rigbake {

int BodyRegion::triangleCount() const {
  int count = 0;
  for (const std::vector<int>& part : triangles) count += static_cast<int>(part.size());
  return count;
}

namespace {

// joint -> the landmarks that own it: those resolved to the joint itself, else its nearest ancestor's.
std::vector<std::set<std::string>> landmarkOwners(const Skeleton& skeleton, const LandmarkSet& landmarks) {
  std::vector<std::set<std::string>> on_joint(skeleton.size());
  for (const auto& [name, landmark] : landmarks.landmarks) {
    if (landmark.resolved && !landmark.from_joint.empty() && landmark.joint >= 0) on_joint[landmark.joint].insert(name);
  }
  std::vector<std::set<std::string>> owners(skeleton.size());
  for (int j = 0; j < skeleton.size(); ++j) {  // parents come first
    owners[j] = !on_joint[j].empty() || skeleton.parents[j] < 0 ? on_joint[j] : owners[skeleton.parents[j]];
  }
  return owners;
}

struct SidedRule {
  const RegionRule* rule = nullptr;
  std::string region;  // final name
  std::string side;    // "l", "r" or "" (central)
  bool usable = true;
  std::set<std::string> owners;
  Eigen::Vector3d near = Eigen::Vector3d::Zero();
  double radius = 0.0;
  Eigen::Vector3d facing_point = Eigen::Vector3d::Zero();
};

}  // namespace

std::vector<BodyRegion> resolveBodyRegions(const Character& character, const LandmarkSet& landmarks,
                                           const RegionPreset& preset) {
  const Skeleton& skeleton = character.skeleton;
  const std::vector<std::set<std::string>> owners = landmarkOwners(skeleton, landmarks);
  auto resolved = [&](const std::string& name) { return landmarks.has(name) && landmarks.get(name).resolved; };

  std::vector<SidedRule> rules;
  for (const RegionRule& rule : preset.rules) {
    const std::vector<std::string> sides = rule.sided ? std::vector<std::string>{"l", "r"} : std::vector<std::string>{""};
    for (const std::string& side : sides) {
      SidedRule sided;
      sided.rule = &rule;
      sided.region = rule.sided ? rule.name + "_" + side : rule.name;
      sided.side = side;
      auto name = [&](const std::string& landmark) { return side.empty() ? landmark : sidedName(landmark, side); };
      for (const std::string& owner : rule.owners) {
        if (resolved(name(owner))) sided.owners.insert(name(owner));
      }
      sided.usable = !sided.owners.empty();
      if (!rule.near.empty()) {
        sided.usable = sided.usable && resolved(name(rule.near)) && resolved(name(rule.radius_from)) && resolved(name(rule.radius_to));
        if (sided.usable) {
          sided.near = landmarks.get(name(rule.near)).position;
          sided.radius = rule.radius_fraction *
                         (landmarks.get(name(rule.radius_to)).position - landmarks.get(name(rule.radius_from)).position).norm();
        }
      }
      if (!rule.facing.empty()) {
        sided.usable = sided.usable && resolved(name(rule.facing_landmark));
        if (sided.usable) sided.facing_point = landmarks.get(name(rule.facing_landmark)).position;
      }
      rules.push_back(std::move(sided));
    }
  }

  // Region order: first mention in the preset, left before right.
  std::vector<std::string> order;
  for (const SidedRule& rule : rules) {
    if (std::find(order.begin(), order.end(), rule.region) == order.end()) order.push_back(rule.region);
  }
  std::vector<BodyRegion> regions(order.size());
  for (size_t r = 0; r < order.size(); ++r) regions[r].name = order[r];

  for (const MeshPart& part : character.meshes) {
    if (!part.skinned || part.positions.empty()) continue;
    for (BodyRegion& region : regions) region.triangles.emplace_back();
    const int slots = part.influences_per_vertex;
    for (size_t t = 0; t < part.triangles.size(); ++t) {
      const auto& triangle = part.triangles[t];
      std::map<int, double> weight_of_joint;
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int v : triangle) {
        centroid += part.positions[v] / 3.0;
        for (int k = 0; k < slots; ++k) weight_of_joint[part.joints[v * slots + k]] += part.weights[v * slots + k];
      }
      int strongest = -1;
      double best = 0.0;
      for (const auto& [joint, weight] : weight_of_joint) {  // ascending joints: the lowest wins a tie
        if (weight > best) {
          best = weight;
          strongest = joint;
        }
      }
      if (strongest < 0) continue;
      const double lateral = landmarks.body.lateralOffset(centroid);
      for (const SidedRule& rule : rules) {
        if (!rule.usable) continue;
        bool owned = false, central = false;
        for (const std::string& owner : owners[strongest]) {
          if (rule.owners.count(owner) == 0) continue;
          owned = true;
          central = central || std::find(centralLandmarks().begin(), centralLandmarks().end(), owner) != centralLandmarks().end();
        }
        if (!owned) continue;
        // A central landmark (the pelvis) can own both sides of a sided region: split at the midline.
        if (central && rule.side == "l" && lateral < 0.0) continue;
        if (central && rule.side == "r" && lateral > 0.0) continue;
        if (!rule.rule->near.empty() && (centroid - rule.near).norm() > rule.radius) continue;
        if (!rule.rule->facing.empty()) {
          const double ahead = (centroid - rule.facing_point).dot(landmarks.body.forward);
          if (rule.rule->facing == "forward" ? ahead < 0.0 : ahead > 0.0) continue;
        }
        const size_t r = std::find(order.begin(), order.end(), rule.region) - order.begin();
        regions[r].triangles.back().push_back(static_cast<int>(t));
        break;
      }
    }
  }
  regions.erase(std::remove_if(regions.begin(), regions.end(), [](const BodyRegion& r) { return r.triangleCount() == 0; }),
                regions.end());
  return regions;
}

}  // namespace rigbake
