#include "anatomy/body_regions.h"

#include <algorithm>
#include <set>

#include "anatomy/point_formula.h"

namespace rigbake {

int BodyRegion::triangleCount() const {
  int count = 0;
  for (const std::vector<int>& part : triangles) count += static_cast<int>(part.size());
  return count;
}

namespace {

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

  // Per joint and rule, whether one of the joint's owning landmarks is among the rule's owners, and
  // whether a central one is: decided once per joint, not once per triangle.
  struct JointRule {
    bool owned = false, central = false;
  };
  std::vector<JointRule> joint_rule(static_cast<size_t>(skeleton.size()) * rules.size());
  for (int j = 0; j < skeleton.size(); ++j) {
    for (size_t i = 0; i < rules.size(); ++i) {
      JointRule& flags = joint_rule[static_cast<size_t>(j) * rules.size() + i];
      for (const std::string& owner : owners[j]) {
        if (rules[i].owners.count(owner) == 0) continue;
        flags.owned = true;
        flags.central = flags.central ||
                        std::find(centralLandmarks().begin(), centralLandmarks().end(), owner) != centralLandmarks().end();
      }
    }
  }
  std::vector<size_t> region_of_rule(rules.size());
  for (size_t i = 0; i < rules.size(); ++i)
    region_of_rule[i] = static_cast<size_t>(std::find(order.begin(), order.end(), rules[i].region) - order.begin());

  std::vector<std::pair<int, double>> weight_of_joint;
  for (const MeshPart& part : character.meshes) {
    if (!part.skinned || part.positions.empty()) continue;
    for (BodyRegion& region : regions) region.triangles.emplace_back();
    const int slots = part.influences_per_vertex;
    for (size_t t = 0; t < part.triangles.size(); ++t) {
      const auto& triangle = part.triangles[t];
      // Each joint's weight summed over the corners, in slot order.
      weight_of_joint.clear();
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int v : triangle) {
        centroid += part.positions[v] / 3.0;
        for (int k = 0; k < slots; ++k) {
          const int joint = part.joints[v * slots + k];
          auto it = std::find_if(weight_of_joint.begin(), weight_of_joint.end(), [joint](const auto& e) { return e.first == joint; });
          if (it == weight_of_joint.end()) {
            weight_of_joint.emplace_back(joint, 0.0);
            it = weight_of_joint.end() - 1;
          }
          it->second += part.weights[v * slots + k];
        }
      }
      int strongest = -1;
      double best = 0.0;
      for (const auto& [joint, weight] : weight_of_joint) {  // the lowest joint wins a tie
        if (weight > best || (weight == best && strongest >= 0 && joint < strongest)) {
          best = weight;
          strongest = joint;
        }
      }
      if (strongest < 0) continue;
      const double lateral = landmarks.body.lateralOffset(centroid);
      for (size_t i = 0; i < rules.size(); ++i) {
        const SidedRule& rule = rules[i];
        if (!rule.usable) continue;
        const JointRule& flags = joint_rule[static_cast<size_t>(strongest) * rules.size() + i];
        if (!flags.owned) continue;
        // A central landmark (the pelvis) can own both sides of a sided region: split at the midline.
        if (flags.central && rule.side == "l" && lateral < 0.0) continue;
        if (flags.central && rule.side == "r" && lateral > 0.0) continue;
        if (!rule.rule->near.empty() && (centroid - rule.near).norm() > rule.radius) continue;
        if (!rule.rule->facing.empty()) {
          const double ahead = (centroid - rule.facing_point).dot(landmarks.body.forward);
          if (rule.rule->facing == "forward" ? ahead < 0.0 : ahead > 0.0) continue;
        }
        regions[region_of_rule[i]].triangles.back().push_back(static_cast<int>(t));
        break;
      }
    }
  }
  regions.erase(std::remove_if(regions.begin(), regions.end(), [](const BodyRegion& r) { return r.triangleCount() == 0; }),
                regions.end());
  return regions;
}

}  // namespace rigbake
