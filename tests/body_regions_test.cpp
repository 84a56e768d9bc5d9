// Body regions as a module (anatomy/body_regions.h) on the mannequin with the shipped preset: the
// order the preset names them in, no triangle in two regions, the first rule keeping a triangle, rules
// whose landmarks do not resolve taking nothing, and the landmark owners of every joint.
#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "anatomy/body_regions.h"
#include "anatomy_fixture.h"

using namespace rigbake;

namespace {

const test::Resolved& regionsMannequin() {
  static const test::Resolved resolved = test::resolveShipped(test::sampleGlbPath());
  return resolved;
}

const RegionPreset& shippedRegionPreset() {
  static const RegionPreset preset = readRegionPreset(test::presetsDir() + "/regions/body.json");
  return preset;
}

std::vector<std::string> regionNames(const std::vector<BodyRegion>& regions) {
  std::vector<std::string> names;
  for (const BodyRegion& region : regions) names.push_back(region.name);
  return names;
}

}  // namespace

TEST_CASE("body regions: the mannequin's regions come in the preset's order, left before right, and share no triangle",
          "[body-regions]") {
  const test::Resolved& r = regionsMannequin();
  const RegionPreset& preset = shippedRegionPreset();
  const std::vector<BodyRegion> regions = resolveBodyRegions(r.character, r.landmarks, preset);
  const std::vector<std::string> names = regionNames(regions);
  for (const char* expected : {"shoulder_l", "shoulder_r", "elbow_l", "elbow_r", "upper_arm_l", "forearm_r", "chest", "back"}) {
    INFO(expected);
    CHECK(std::find(names.begin(), names.end(), expected) != names.end());
  }
  // The preset's first naming of each region, sided ones as _l then _r, kept where the mannequin has it.
  std::vector<std::string> order;
  for (const RegionRule& rule : preset.rules) {
    const std::vector<std::string> sided =
        rule.sided ? std::vector<std::string>{rule.name + "_l", rule.name + "_r"} : std::vector<std::string>{rule.name};
    for (const std::string& name : sided) {
      if (std::find(order.begin(), order.end(), name) == order.end() && std::find(names.begin(), names.end(), name) != names.end())
        order.push_back(name);
    }
  }
  CHECK(order == names);
  // Each region has triangles, each a valid index of its part, and no triangle is in two regions.
  std::vector<std::set<int>> taken;
  for (const BodyRegion& region : regions) {
    INFO(region.name);
    CHECK(region.triangleCount() > 0);
    if (taken.size() < region.triangles.size()) taken.resize(region.triangles.size());
    for (size_t p = 0; p < region.triangles.size(); ++p) {
      for (int t : region.triangles[p]) {
        REQUIRE(t >= 0);
        CHECK(taken[p].insert(t).second);
      }
    }
  }
}

TEST_CASE("body regions: the first rule that takes a triangle keeps it, and a rule without its landmarks takes nothing",
          "[body-regions]") {
  const test::Resolved& r = regionsMannequin();
  RegionRule first;
  first.name = "first";
  first.sided = true;
  first.owners = {"forearm", "forearm_twist"};
  RegionRule second = first;
  second.name = "second";
  RegionPreset preset;
  preset.rules = {first, second};
  std::vector<BodyRegion> regions = resolveBodyRegions(r.character, r.landmarks, preset);
  CHECK(regionNames(regions) == std::vector<std::string>{"first_l", "first_r"});
  const int forearm_triangles = regions[0].triangleCount();
  CHECK(forearm_triangles > 0);
  preset.rules = {second, first};
  regions = resolveBodyRegions(r.character, r.landmarks, preset);
  REQUIRE(regionNames(regions) == std::vector<std::string>{"second_l", "second_r"});
  CHECK(regions[0].triangleCount() == forearm_triangles);
  RegionRule unresolved = first;
  unresolved.name = "nowhere";
  unresolved.owners = {"no_such_landmark"};
  preset.rules = {unresolved};
  CHECK(resolveBodyRegions(r.character, r.landmarks, preset).empty());
}

TEST_CASE("body regions: a joint is owned by the landmarks on it, else by its nearest owned ancestor's", "[body-regions]") {
  const test::Resolved& r = regionsMannequin();
  const Skeleton& skeleton = r.character.skeleton;
  const std::vector<std::set<std::string>> owners = landmarkOwners(skeleton, r.landmarks);
  REQUIRE(static_cast<int>(owners.size()) == skeleton.size());
  int owned_directly = 0;
  for (int j = 0; j < skeleton.size(); ++j) {
    std::set<std::string> on_joint;
    for (const auto& [name, landmark] : r.landmarks.landmarks)
      if (landmark.resolved && !landmark.from_joint.empty() && landmark.joint == j) on_joint.insert(name);
    INFO(skeleton.names[j]);
    if (!on_joint.empty()) {
      ++owned_directly;
      CHECK(owners[j] == on_joint);
    } else if (skeleton.parents[j] >= 0) {
      CHECK(owners[j] == owners[skeleton.parents[j]]);
    }
  }
  CHECK(owned_directly > 10);
  // The forearm's joint is owned by the forearm landmark.
  const Landmark& forearm = r.landmarks.get("forearm_l");
  REQUIRE(forearm.joint >= 0);
  CHECK(owners[forearm.joint].count("forearm_l") == 1);
}
