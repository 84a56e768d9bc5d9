// `rigbake landmarks CHAR`: the canonical landmarks of a character, where each came from, and the
// body frame. --json prints the stable contract of docs/output-contract.md.
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/common.h"
#include "formats/json_text.h"

namespace rigbake::cli {
namespace {

struct LandmarksOptions {
  std::string character;
  PresetOptions presets;
  bool json = false;
};

nlohmann::json vec(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

// The joints the muscles take as hanging from another joint than the rig's (LandmarkSet::anatomical_parents).
std::vector<int> rehungJoints(const Skeleton& skeleton, const LandmarkSet& set) {
  std::vector<int> joints;
  for (int j = 0; j < skeleton.size(); ++j)
    if (set.anatomical_parents[j] != skeleton.parents[j]) joints.push_back(j);
  return joints;
}

nlohmann::json landmarksJson(const std::string& character, const Skeleton& skeleton, const LandmarkSet& set) {
  nlohmann::json landmarks = nlohmann::json::object();
  for (const auto& [name, landmark] : set.landmarks) {
    if (!landmark.resolved) {
      landmarks[name] = nullptr;
      continue;
    }
    landmarks[name] = {
        {"position", vec(landmark.position)},
        {"joint", landmark.from_joint.empty() ? nlohmann::json(nullptr) : nlohmann::json(landmark.from_joint)},
        {"derived", landmark.derived.empty() ? nlohmann::json(nullptr) : nlohmann::json(landmark.derived)},
        {"rides_on", skeleton.names[landmark.joint]},
        {"source", landmark.source},
    };
  }
  nlohmann::json rehung = nlohmann::json::array();
  for (int j : rehungJoints(skeleton, set))
    rehung.push_back({{"joint", skeleton.names[j]}, {"rig_parent", skeleton.names[skeleton.parents[j]]},
                      {"body_parent", skeleton.names[set.anatomical_parents[j]]}});
  return {
      {"character", character},
      {"units", "m"},
      {"map", set.map_name},
      {"body",
       {{"height", set.body.height}, {"up", vec(set.body.up)}, {"lateral", vec(set.body.lateral)},
        {"forward", vec(set.body.forward)}}},
      {"landmarks", landmarks},
      {"rehung", rehung},
  };
}

int run(const LandmarksOptions& options) {
  ResolvedCharacter resolved = loadAndResolve(options.character, options.presets);
  const LandmarkSet& set = resolved.landmarks;
  const Skeleton& skeleton = resolved.loaded.character.skeleton;
  if (options.json) {
    std::cout << jsonText(landmarksJson(fileNameOf(options.character), skeleton, set)) << "\n";
    return 0;
  }
  std::cout << fileNameOf(options.character) << ": map " << set.map_name << ", body height " << std::fixed
            << std::setprecision(3) << set.body.height << " m\n";
  std::cout << std::left << std::setw(18) << "landmark" << std::setw(30) << "position (m)"
            << "from\n";
  for (const auto& [name, landmark] : set.landmarks) {
    std::cout << std::setw(18) << name;
    if (!landmark.resolved) {
      std::cout << std::setw(30) << "-" << "none (optional)\n";
      continue;
    }
    std::ostringstream position;
    position << std::fixed << std::setprecision(3) << landmark.position.x() << " " << landmark.position.y() << " "
             << landmark.position.z();
    std::cout << std::setw(30) << position.str();
    if (!landmark.from_joint.empty()) std::cout << "joint " << landmark.from_joint << " (" << landmark.source << ")\n";
    else std::cout << "derived " << landmark.derived << " on " << skeleton.names[landmark.joint] << "\n";
  }
  for (int j : rehungJoints(skeleton, set)) {
    std::cout << "the muscles take " << skeleton.names[j] << " as hanging from "
              << skeleton.names[set.anatomical_parents[j]] << ", not from the rig's " << skeleton.names[skeleton.parents[j]]
              << " (docs/landmarks.md, \"The body's hierarchy\")\n";
  }
  return 0;
}

}  // namespace

void addLandmarksCommand(CLI::App& app, Runner* runner) {
  auto options = std::make_shared<LandmarksOptions>();
  CLI::App* command = app.add_subcommand(
      "landmarks",
      "Resolve and print the canonical skeleton landmarks (head, neck, chest, spine_t12, spine_l5, pelvis; per side "
      "clavicle, acromion, scapula, upper_arm(_twist), forearm(_twist), hand, and the optional upper_leg, lower_leg, "
      "foot, toe) with the joint each came from or the formula that derived it. Positions are world space at bind "
      "pose, in metres.");
  command->add_option("character", options->character, "Character file (.glb, .gltf, .vrm, .fbx)")->required();
  addPresetOptions(command, &options->presets);
  command->add_flag("--json", options->json, "Print machine-readable JSON (docs/output-contract.md)");
  command->callback([runner, options]() { *runner = [options]() { return run(*options); }; });
}

}  // namespace rigbake::cli
