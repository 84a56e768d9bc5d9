// `rigbake bake --helper-joints` on a VRM 1.0 character: the base and tip joints carry their aim
// constraints as VRMC_node_constraint 1.0 (one per node, the right sources, no circular dependency),
// the constraints reproduce the sampled channels, the file passes the Khronos validator; plain glTF
// and VRM 0.x outputs carry no node constraints.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_support.h"
#include "external_tools.h"
#include "formats/gltf_document.h"
#include "glb_support.h"
#include "pipeline/pose.h"
#include "test_support.h"

#include <catch2/catch.hpp>

using namespace rigbake;
namespace ext = rigbake::test::external;
using rigbake::test::runCli;
using rigbake::test::slurp;

// A named namespace: the test sources are compiled in unity batches, where other files' helpers of
// the same names would clash.
namespace vrm_constraint_test {

constexpr double kDegrees = 57.29577951308232;

std::string sampleVrm(const test::TempDir& dir, int version) {
  const std::string path = dir / ("sample" + std::to_string(version) + ".vrm");
  REQUIRE(runCli("sample --vrm " + std::to_string(version) + " -o " + ext::shellQuote(path)).exit_code == 0);
  return path;
}

test::CliResult bake(const std::string& input, const std::string& output, const std::string& extra) {
  // About the helper joints' constraints, not the response fit: the preset's response is kept.
  return runCli("bake " + ext::shellQuote(input) + " --influences 4 --response keep " + extra + " -o " + ext::shellQuote(output));
}

// A GLB's JSON and its binary chunk, and float accessors read from it.
struct Glb {
  nlohmann::json json;
  std::string bin;

  explicit Glb(const std::string& bytes) : json(test::glbJson(bytes)) {
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const size_t chunk = 20 + static_cast<size_t>(json_length);
    REQUIRE(chunk + 8 <= bytes.size());
    std::uint32_t bin_length = 0;
    std::memcpy(&bin_length, bytes.data() + chunk, 4);
    REQUIRE(chunk + 8 + bin_length <= bytes.size());
    bin = bytes.substr(chunk + 8, bin_length);
  }

  // Accessor `index` as floats, `components` per element (tightly packed or strided).
  std::vector<float> floats(int index, int components) const {
    const nlohmann::json& accessor = json["accessors"][index];
    REQUIRE(accessor["componentType"] == 5126);
    const nlohmann::json& view = json["bufferViews"][accessor["bufferView"].get<int>()];
    const size_t stride = view.value("byteStride", 0) ? view["byteStride"].get<size_t>() : 4 * static_cast<size_t>(components);
    const size_t offset = view.value("byteOffset", size_t{0}) + accessor.value("byteOffset", size_t{0});
    const size_t count = accessor["count"].get<size_t>();
    REQUIRE(offset + stride * (count - 1) + 4 * components <= bin.size());
    std::vector<float> out(count * components);
    for (size_t k = 0; k < count; ++k) std::memcpy(&out[k * components], bin.data() + offset + stride * k, 4 * components);
    return out;
  }

  int nodeNamed(const std::string& name) const {
    for (size_t n = 0; n < json["nodes"].size(); ++n) {
      if (json["nodes"][n].value("name", "") == name) return static_cast<int>(n);
    }
    return -1;
  }

  std::map<int, int> parents() const {
    std::map<int, int> parent;
    for (size_t n = 0; n < json["nodes"].size(); ++n) {
      for (const auto& child : json["nodes"][n].value("children", nlohmann::json::array())) parent[child.get<int>()] = static_cast<int>(n);
    }
    return parent;
  }
};

Eigen::Quaterniond quaternionOf(const float* xyzw) { return Eigen::Quaterniond(xyzw[3], xyzw[0], xyzw[1], xyzw[2]).normalized(); }

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Which muscle helper nodes the file has: node index -> (muscle, role) from the bake's extras.
std::map<int, std::pair<std::string, std::string>> helperRoles(const nlohmann::json& gltf) {
  std::map<int, std::pair<std::string, std::string>> roles;
  for (size_t n = 0; n < gltf["nodes"].size(); ++n) {
    const nlohmann::json& node = gltf["nodes"][n];
    if (!node.contains("extras") || !node["extras"].contains("rigbake")) continue;
    const nlohmann::json& rigbake = node["extras"]["rigbake"];
    roles[static_cast<int>(n)] = {rigbake["muscle"].get<std::string>(), rigbake["role"].get<std::string>()};
  }
  return roles;
}

int countConstraints(const nlohmann::json& gltf) {
  int count = 0;
  for (const auto& node : gltf["nodes"]) count += node.contains("extensions") && node["extensions"].contains("VRMC_node_constraint");
  return count;
}

bool listed(const nlohmann::json& gltf, const char* key, const std::string& extension) {
  if (!gltf.contains(key)) return false;
  return std::count(gltf[key].begin(), gltf[key].end(), extension) > 0;
}

}  // namespace vrm_constraint_test

namespace vc = vrm_constraint_test;

TEST_CASE("cli bake --helper-joints on VRM 1.0: base and tip carry VRMC_node_constraint aims at each other's positions") {
  test::TempDir dir;
  const std::string input = vc::sampleVrm(dir, 1);
  const std::string output = dir / "baked.vrm";
  test::CliResult run = vc::bake(input, output, "--muscle-motion both --helper-joints");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const vc::Glb glb(slurp(output));
  const nlohmann::json& gltf = glb.json;
  const auto roles = vc::helperRoles(gltf);
  std::set<std::string> muscles;
  for (const auto& [node, role] : roles) muscles.insert(role.first);
  REQUIRE(muscles.size() > 10);
  CHECK(run.err.find("the base and tip joints of " + std::to_string(muscles.size()) +
                     " muscles carry VRMC_node_constraint aim constraints") != std::string::npos);

  CHECK(std::count(gltf["extensionsUsed"].begin(), gltf["extensionsUsed"].end(), "VRMC_node_constraint") == 1);
  CHECK_FALSE(vc::listed(gltf, "extensionsRequired", "VRMC_node_constraint"));
  CHECK(vc::countConstraints(gltf) == 2 * static_cast<int>(muscles.size()));

  const std::map<int, int> parent = glb.parents();
  std::set<int> constrained;
  for (size_t n = 0; n < gltf["nodes"].size(); ++n) {
    const nlohmann::json& node = gltf["nodes"][n];
    if (node.contains("extensions") && node["extensions"].contains("VRMC_node_constraint")) constrained.insert(static_cast<int>(n));
  }
  for (const auto& [node, role] : roles) {
    const auto& [muscle, kind] = role;
    INFO(muscle << " " << kind);
    const nlohmann::json& extensions = gltf["nodes"][node].value("extensions", nlohmann::json::object());
    if (kind == "driver" || kind == "skinned") {
      CHECK_FALSE(extensions.contains("VRMC_node_constraint"));
      continue;
    }
    REQUIRE(extensions.contains("VRMC_node_constraint"));
    const nlohmann::json& extension = extensions["VRMC_node_constraint"];
    CHECK(extension["specVersion"] == "1.0");
    REQUIRE(extension["constraint"].size() == 1);
    const nlohmann::json& aim = extension["constraint"]["aim"];
    CHECK(aim["aimAxis"] == "PositiveX");
    CHECK(aim["weight"].get<double>() == 1.0);
    const int source = aim["source"].get<int>();
    if (kind == "base") {
      CHECK(source == glb.nodeNamed(muscle + "_muscleTip"));
    } else {
      // The tip aims at a plain node where the base is: same parent (the origin joint), same place.
      const int base = glb.nodeNamed(muscle + "_muscleBase");
      REQUIRE(base >= 0);
      CHECK(source == glb.nodeNamed(muscle + "_muscleTipTarget"));
      CHECK(parent.at(source) == parent.at(base));
      CHECK(gltf["nodes"][source]["translation"] == gltf["nodes"][base]["translation"]);
      CHECK_FALSE(gltf["nodes"][source].contains("extras"));
      CHECK_FALSE(constrained.count(source));
    }
  }
  // No circular dependency, by the runtime rule: a constraint waits for those on its source and the
  // source's ancestors and on its destination's ancestors.
  std::map<int, int> source_of;
  for (int node : constrained) source_of[node] = gltf["nodes"][node]["extensions"]["VRMC_node_constraint"]["constraint"]["aim"]["source"].get<int>();
  auto waitsFor = [&](int destination) {
    std::vector<int> out;
    for (int start : {source_of.at(destination), parent.count(destination) ? parent.at(destination) : -1}) {
      for (int n = start; n >= 0; n = parent.count(n) ? parent.at(n) : -1) {
        if (source_of.count(n)) out.push_back(n);
      }
    }
    return out;
  };
  for (int node : constrained) {
    std::set<int> seen;
    std::vector<int> stack = waitsFor(node);
    bool cycle = false;
    while (!stack.empty() && !cycle) {
      const int n = stack.back();
      stack.pop_back();
      cycle = n == node;
      if (seen.insert(n).second)
        for (int next : waitsFor(n)) stack.push_back(next);
    }
    CHECK_FALSE(cycle);
  }

  // The constraints against the sampled channels, at every sampled frame of every clip: the base's X
  // axis points at the tip, the tip's at the base; and the base's whole rotation is what the
  // specification's aim evaluation gives (the smallest rotation from its rest orientation, carried
  // by its parent), as the rig transports its up axis with the origin joint the base rides.
  const LoadedCharacter loaded = loadCharacter(output);
  const Skeleton& skeleton = loaded.character.skeleton;
  std::map<int, int> joint_of_node;
  for (int j = 0; j < skeleton.size(); ++j) joint_of_node[skeleton.nodes[j]] = j;
  double base_aim = 0.0, tip_aim = 0.0, base_rotation = 0.0, tip_roll = 0.0, target_offset = 0.0;
  int frames = 0;
  for (const Clip& clip : loaded.character.clips) {
    if (clip.gltf_animation < 0) continue;
    const nlohmann::json& animation = gltf["animations"][clip.gltf_animation];
    // node -> (times, translations, rotations) of its baked channels
    std::map<int, std::vector<float>> times, translations, rotations;
    for (const auto& channel : animation["channels"]) {
      const int node = channel["target"]["node"].get<int>();
      if (!roles.count(node)) continue;
      const nlohmann::json& sampler = animation["samplers"][channel["sampler"].get<int>()];
      const std::string path = channel["target"]["path"].get<std::string>();
      times[node] = glb.floats(sampler["input"].get<int>(), 1);
      if (path == "translation") translations[node] = glb.floats(sampler["output"].get<int>(), 3);
      if (path == "rotation") rotations[node] = glb.floats(sampler["output"].get<int>(), 4);
    }
    for (const std::string& muscle : muscles) {
      const int base = glb.nodeNamed(muscle + "_muscleBase"), tip = glb.nodeNamed(muscle + "_muscleTip");
      const int target = glb.nodeNamed(muscle + "_muscleTipTarget");
      REQUIRE(rotations.count(base));
      REQUIRE(rotations.count(tip));
      const std::vector<float>& t = times[base];
      REQUIRE(t.size() > 2);
      const nlohmann::json& base_rest = gltf["nodes"][base]["rotation"];
      const Eigen::Quaterniond base_rest_q(base_rest[3].get<double>(), base_rest[0].get<double>(), base_rest[1].get<double>(),
                                           base_rest[2].get<double>());
      const nlohmann::json& tip_rest = gltf["nodes"][tip]["rotation"];
      const Eigen::Quaterniond tip_rest_q(tip_rest[3].get<double>(), tip_rest[0].get<double>(), tip_rest[1].get<double>(),
                                          tip_rest[2].get<double>());
      const nlohmann::json& target_at = gltf["nodes"][target]["translation"];
      const Eigen::Vector3d target_local(target_at[0].get<double>(), target_at[1].get<double>(), target_at[2].get<double>());
      for (size_t k = 0; k < t.size(); ++k) {
        const Pose pose = sampleClip(skeleton, clip, t[k]);
        auto world = [&](int node) {
          const Eigen::Affine3d& up = pose.world[joint_of_node.at(parent.at(node))];
          Eigen::Affine3d local = Eigen::Affine3d::Identity();
          const float* p = &translations[node][3 * k];
          local.translate(Eigen::Vector3d(p[0], p[1], p[2]));
          local.rotate(vc::quaternionOf(&rotations[node][4 * k]));
          return std::pair<Eigen::Affine3d, Eigen::Affine3d>(up, up * local);
        };
        const auto [base_parent, base_world] = world(base);
        const auto [tip_parent, tip_world] = world(tip);
        const Eigen::Vector3d target_world = pose.world[joint_of_node.at(parent.at(target))] * target_local;
        const Eigen::Vector3d base_x = base_world.linear().col(0), tip_x = tip_world.linear().col(0);
        base_aim = std::max(base_aim, vc::angleBetween(base_x, tip_world.translation() - base_world.translation()));
        tip_aim = std::max(tip_aim, vc::angleBetween(tip_x, target_world - tip_world.translation()));
        // The tip's source sits where the base is.
        target_offset = std::max(target_offset, (target_world - base_world.translation()).norm());

        // The specification's aim evaluation of the base (and of the tip, for its roll).
        auto specAim = [](const Eigen::Affine3d& parent_world, const Eigen::Quaterniond& rest, const Eigen::Vector3d& from,
                          const Eigen::Vector3d& to) {
          const Eigen::Quaterniond parent_q(parent_world.rotation());
          const Eigen::Vector3d from_vec = parent_q * (rest * Eigen::Vector3d::UnitX());
          const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(from_vec, (to - from).normalized());
          return Eigen::Quaterniond(parent_q.inverse() * turn * parent_q * rest);
        };
        const Eigen::Quaterniond base_spec = specAim(base_parent, base_rest_q, base_world.translation(), tip_world.translation());
        base_rotation = std::max(base_rotation, base_spec.angularDistance(vc::quaternionOf(&rotations[base][4 * k])));
        const Eigen::Quaterniond tip_spec = specAim(tip_parent, tip_rest_q, tip_world.translation(), target_world);
        tip_roll = std::max(tip_roll, tip_spec.angularDistance(vc::quaternionOf(&rotations[tip][4 * k])));
        ++frames;
      }
    }
  }
  std::printf("VRMC_node_constraint vs sampled channels over %d muscle-frames: base X to tip %.3g deg, tip X to base "
              "%.3g deg, base rotation vs aim evaluation %.3g deg, tip roll vs aim evaluation %.3g deg, tip source off the "
              "base %.3g m\n",
              frames, base_aim * vc::kDegrees, tip_aim * vc::kDegrees, base_rotation * vc::kDegrees, tip_roll * vc::kDegrees, target_offset);
  CHECK(frames > 100);
  CHECK(target_offset < 1e-5);  // metres
  CHECK(base_aim * vc::kDegrees < 0.01);
  CHECK(tip_aim * vc::kDegrees < 0.01);
  CHECK(base_rotation * vc::kDegrees < 0.01);
}

TEST_CASE("Khronos validator: a VRM 1.0 bake with helper joints and VRMC_node_constraint has 0 errors") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  test::TempDir dir;
  const std::string input = vc::sampleVrm(dir, 1);
  for (const std::string motion : {"both", "runtime"}) {
    const std::string output = dir / ("baked-" + motion + ".vrm");
    test::CliResult run = vc::bake(input, output, "--muscle-motion " + motion + " --helper-joints");
    INFO(motion << "\n" << run.err);
    REQUIRE(run.exit_code == 0);
    REQUIRE(vc::countConstraints(test::glbJson(slurp(output))) > 0);
    const ext::ValidationSummary summary = ext::validateWithKhronos(output);
    INFO(summary.raw);
    CHECK(summary.errors == 0);
  }
}

TEST_CASE("cli bake: plain GLB, VRM 0.x and VRM 1.0 without helper joints carry no VRMC_node_constraint") {
  test::TempDir dir;
  struct Case {
    std::string input, flags;
  };
  const std::vector<Case> cases = {{test::sampleGlbPathForCli(), "--muscle-motion both --helper-joints"},
                                   {vc::sampleVrm(dir, 0), "--muscle-motion both --helper-joints"},
                                   {vc::sampleVrm(dir, 1), "--muscle-motion both"}};
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string output = dir / ("out" + std::to_string(i) + (i == 0 ? ".glb" : ".vrm"));
    test::CliResult run = vc::bake(cases[i].input, output, cases[i].flags);
    INFO(cases[i].input << " " << cases[i].flags << "\n" << run.err);
    REQUIRE(run.exit_code == 0);
    CHECK(run.err.find("VRMC_node_constraint") == std::string::npos);
    const std::string bytes = slurp(output);
    const nlohmann::json gltf = test::glbJson(bytes);
    CHECK(vc::countConstraints(gltf) == 0);
    CHECK_FALSE(vc::listed(gltf, "extensionsUsed", "VRMC_node_constraint"));
    // No tip targets either: the nodes are the input's plus the bake's muscle joints.
    const nlohmann::json source = test::glbJson(slurp(cases[i].input));
    const auto roles = vc::helperRoles(gltf);
    CHECK(gltf["nodes"].size() == source["nodes"].size() + roles.size());
    for (const auto& node : gltf["nodes"]) CHECK(node.value("name", "").find("_muscleTipTarget") == std::string::npos);
  }
}

TEST_CASE("cli bake --helper-joints on a baked VRM 1.0: the new joints get the constraints, the old keep theirs") {
  test::TempDir dir;
  const std::string first = dir / "first.vrm", second = dir / "second.vrm";
  REQUIRE(vc::bake(vc::sampleVrm(dir, 1), first, "--muscle-motion both --helper-joints").exit_code == 0);
  test::CliResult run = vc::bake(first, second, "--muscle-motion both --helper-joints");
  INFO(run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json before = test::glbJson(slurp(first)), after = test::glbJson(slurp(second));
  const int old_nodes = static_cast<int>(before["nodes"].size());
  CHECK(vc::countConstraints(after) == 2 * vc::countConstraints(before));
  for (size_t n = 0; n < after["nodes"].size(); ++n) {
    const nlohmann::json& node = after["nodes"][n];
    if (!node.contains("extensions") || !node["extensions"].contains("VRMC_node_constraint")) continue;
    const int source = node["extensions"]["VRMC_node_constraint"]["constraint"]["aim"]["source"].get<int>();
    INFO(node["name"]);
    // Each constraint aims at a node of its own bake: the old at the old, the new at the new.
    CHECK((static_cast<int>(n) < old_nodes) == (source < old_nodes));
    if (static_cast<int>(n) < old_nodes) CHECK(node["extensions"] == before["nodes"][n]["extensions"]);
  }
  CHECK(std::count(after["extensionsUsed"].begin(), after["extensionsUsed"].end(), "VRMC_node_constraint") == 1);
}
