#include "anatomy/creases.h"

#include <algorithm>
#include <set>

#include "anatomy/body_regions.h"
#include "anatomy/point_formula.h"

namespace rigbake {
namespace {

// The vertex's strongest input joint (its slots' weights summed per joint; the lowest joint on a tie),
// -1 when it has no weight.
int creaseStrongestJoint(const MeshPart& part, size_t vertex) {
  const int slots = part.influences_per_vertex;
  int strongest = -1;
  double best = 0.0;
  for (int k = 0; k < slots; ++k) {
    const int joint = part.joints[vertex * slots + k];
    double weight = 0.0;
    for (int l = 0; l < slots; ++l) {
      if (part.joints[vertex * slots + l] == joint) weight += part.weights[vertex * slots + l];
    }
    if (weight > best || (weight == best && strongest >= 0 && joint < strongest)) {
      best = weight;
      strongest = joint;
    }
  }
  return strongest;
}

}  // namespace

std::vector<Crease> resolveCreases(const Character& character, const LandmarkSet& landmarks,
                                   const std::vector<CreaseRule>& rules) {
  const Skeleton& skeleton = character.skeleton;
  const std::vector<std::set<std::string>> owners = landmarkOwners(skeleton, landmarks);
  auto resolved = [&](const std::string& name) { return landmarks.has(name) && landmarks.get(name).resolved; };
  std::vector<Crease> creases;
  for (const CreaseRule& rule : rules) {
    const std::vector<std::string> sides = rule.sided ? std::vector<std::string>{"l", "r"} : std::vector<std::string>{""};
    for (const std::string& side : sides) {
      auto name = [&](const std::string& landmark) { return side.empty() ? landmark : sidedName(landmark, side); };
      if (!resolved(name(rule.bend_proximal)) || !resolved(name(rule.bend_distal)) || !resolved(name(rule.near)) ||
          !resolved(name(rule.radius_from)) || !resolved(name(rule.radius_to)))
        continue;
      Crease crease;
      crease.name = rule.sided ? rule.name + "_" + side : rule.name;
      crease.proximal_joint = landmarks.get(name(rule.bend_proximal)).joint;
      crease.distal_joint = landmarks.get(name(rule.bend_distal)).joint;
      if (crease.proximal_joint < 0 || crease.distal_joint < 0 || crease.proximal_joint == crease.distal_joint) continue;
      const Eigen::Vector3d centre = landmarks.get(name(rule.near)).position;
      crease.radius = rule.radius_fraction *
                      (landmarks.get(name(rule.radius_to)).position - landmarks.get(name(rule.radius_from)).position).norm();
      // Per joint: which side owns it (0 none, 1 proximal, 2 distal; the distal side wins a joint both
      // name, as the skin below the fold's joint is the distal limb's).
      std::vector<int> side_of_joint(static_cast<size_t>(skeleton.size()), 0);
      for (int j = 0; j < skeleton.size(); ++j) {
        for (const std::string& owner : owners[static_cast<size_t>(j)]) {
          for (const std::string& landmark : rule.proximal)
            if (owner == name(landmark)) side_of_joint[static_cast<size_t>(j)] = std::max(side_of_joint[static_cast<size_t>(j)], 1);
          for (const std::string& landmark : rule.distal)
            if (owner == name(landmark)) side_of_joint[static_cast<size_t>(j)] = 2;
        }
      }
      size_t proximal_count = 0, distal_count = 0;
      for (const MeshPart& part : character.meshes) {
        crease.proximal.emplace_back();
        crease.distal.emplace_back();
        if (!part.skinned) continue;
        for (size_t v = 0; v < part.positions.size(); ++v) {
          if ((part.positions[v] - centre).norm() > crease.radius) continue;
          const int joint = creaseStrongestJoint(part, v);
          if (joint < 0 || joint >= skeleton.size()) continue;
          const int on = side_of_joint[static_cast<size_t>(joint)];
          if (on == 1) crease.proximal.back().push_back(static_cast<int>(v));
          if (on == 2) crease.distal.back().push_back(static_cast<int>(v));
        }
        proximal_count += crease.proximal.back().size();
        distal_count += crease.distal.back().size();
      }
      if (proximal_count > 0 && distal_count > 0) creases.push_back(std::move(crease));
    }
  }
  return creases;
}

}  // namespace rigbake
