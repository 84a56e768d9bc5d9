// Structural landmark finder. A humanoid hierarchy has one joint where the legs and the spine part
// (the pelvis) and one where the neck and both arms part (the chest); the chain between them is the
// lumbar/thoracic spine, the middle branch of the chest is the neck and head, the two outer branches
// are the arms. A short first arm segment before two long ones is a clavicle. The pelvis' other
// branches that reach down are the legs: hip, knee, ankle, toe.
#include "anatomy/skeleton_structure.h"

#include <algorithm>
#include <cctype>
#include <vector>

namespace rigbake {
namespace {

struct Tree {
  std::vector<std::vector<int>> children;
  std::vector<int> subtree_size;
};

Tree buildTree(const Skeleton& skeleton) {
  Tree tree;
  tree.children.resize(skeleton.size());
  tree.subtree_size.assign(skeleton.size(), 1);
  for (int j = 0; j < skeleton.size(); ++j) {
    if (skeleton.parents[j] >= 0) tree.children[skeleton.parents[j]].push_back(j);
  }
  for (int j = skeleton.size() - 1; j >= 0; --j) {
    if (skeleton.parents[j] >= 0) tree.subtree_size[skeleton.parents[j]] += tree.subtree_size[j];
  }
  return tree;
}

// Children whose subtrees have at least two joints: limbs and spine, not end sites or IK helpers.
std::vector<int> branches(const Tree& tree, int joint) {
  std::vector<int> result;
  for (int child : tree.children[joint]) {
    if (tree.subtree_size[child] >= 2) result.push_back(child);
  }
  return result;
}

int largestChild(const Tree& tree, int joint) {
  int best = -1;
  for (int child : tree.children[joint]) {
    if (best < 0 || tree.subtree_size[child] > tree.subtree_size[best]) best = child;
  }
  return best;
}

double distanceToLine(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Vector3d direction = (b - a).normalized();
  Eigen::Vector3d offset = p - a;
  return (offset - direction * offset.dot(direction)).norm();
}

std::vector<std::string> nameTokens(const std::string& name) {
  std::vector<std::string> tokens;
  std::string current;
  auto flush = [&]() {
    if (!current.empty()) tokens.push_back(current);
    current.clear();
  };
  for (size_t i = 0; i < name.size(); ++i) {
    char c = name[i];
    if (!std::isalnum(static_cast<unsigned char>(c))) {
      flush();
      continue;
    }
    // CamelCase boundary: "UpperArmL" -> upper, arm, l.
    if (std::isupper(static_cast<unsigned char>(c)) && !current.empty() &&
        !std::isupper(static_cast<unsigned char>(current.back())))
      flush();
    current += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  flush();
  return tokens;
}

// The legs: of the pelvis' other branches, the two whose chains reach lowest below the pelvis (a tail
// or an IK helper does not), each at least hip, knee and ankle. A first segment shorter than half the
// next is a hip offset joint, not the femur. Sides come from the names, else from which side of the
// shoulders' midline the leg starts. Nothing is added unless both legs are found.
void addLegsFromStructure(const Skeleton& skeleton, const Tree& tree, int pelvis, int spine_start,
                          std::map<std::string, int>* found) {
  if (!found->count("upper_arm_l") || !found->count("upper_arm_r") || !found->count("chest")) return;
  const Eigen::Vector3d pelvis_position = skeleton.bindPosition(pelvis);
  const Eigen::Vector3d up = (skeleton.bindPosition(found->at("chest")) - pelvis_position).normalized();
  struct LegChain {
    std::vector<int> joints;
    double depth = 0.0;  // how far below the pelvis the chain's tip reaches
  };
  std::vector<LegChain> legs;
  for (int branch : branches(tree, pelvis)) {
    if (branch == spine_start) continue;
    LegChain leg;
    for (int j = branch; j >= 0; j = largestChild(tree, j)) leg.joints.push_back(j);
    leg.depth = (pelvis_position - skeleton.bindPosition(leg.joints.back())).dot(up);
    if (leg.joints.size() >= 3 && leg.depth > 0.0) legs.push_back(std::move(leg));
  }
  if (legs.size() < 2) return;
  std::stable_sort(legs.begin(), legs.end(), [](const LegChain& a, const LegChain& b) { return a.depth > b.depth; });
  legs.resize(2);
  auto length = [&](int a, int b) { return (skeleton.bindPosition(a) - skeleton.bindPosition(b)).norm(); };
  const Eigen::Vector3d left = skeleton.bindPosition(found->at("upper_arm_l")) - skeleton.bindPosition(found->at("upper_arm_r"));
  const Eigen::Vector3d midline = (skeleton.bindPosition(found->at("upper_arm_l")) + skeleton.bindPosition(found->at("upper_arm_r"))) / 2.0;
  std::string sides[2];
  for (int k = 0; k < 2; ++k) sides[k] = sideFromName(skeleton.names[legs[k].joints.front()]);
  if (sides[0].empty() || sides[1].empty() || sides[0] == sides[1]) {
    const bool first_is_left = (skeleton.bindPosition(legs[0].joints.front()) - midline).dot(left) >
                               (skeleton.bindPosition(legs[1].joints.front()) - midline).dot(left);
    sides[0] = first_is_left ? "l" : "r";
    sides[1] = first_is_left ? "r" : "l";
  }
  for (int k = 0; k < 2; ++k) {
    const std::vector<int>& chain = legs[k].joints;
    size_t first = 0;
    if (chain.size() >= 4 && length(chain[0], chain[1]) < 0.5 * length(chain[1], chain[2])) first = 1;
    if (chain.size() < first + 3) continue;
    (*found)["upper_leg_" + sides[k]] = chain[first];
    (*found)["lower_leg_" + sides[k]] = chain[first + 1];
    (*found)["foot_" + sides[k]] = chain[first + 2];
    if (chain.size() >= first + 4) (*found)["toe_" + sides[k]] = chain[first + 3];
  }
}

}  // namespace

std::string sideFromName(const std::string& name) {
  std::string lower;
  for (char c : name) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.find("left") != std::string::npos) return "l";
  if (lower.find("right") != std::string::npos) return "r";
  for (const std::string& token : nameTokens(name)) {
    if (token == "l") return "l";
    if (token == "r") return "r";
  }
  return "";
}

std::map<std::string, int> landmarksFromStructure(const Skeleton& skeleton) {
  std::map<std::string, int> found;
  if (skeleton.size() < 8) return found;
  Tree tree = buildTree(skeleton);

  int pelvis = -1;
  for (int j = 0; j < skeleton.size() && pelvis < 0; ++j) {
    if (branches(tree, j).size() >= 3) pelvis = j;
  }
  if (pelvis < 0) return found;
  std::vector<int> pelvis_branches = branches(tree, pelvis);
  int spine_start = *std::max_element(pelvis_branches.begin(), pelvis_branches.end(),
                                      [&](int a, int b) { return tree.subtree_size[a] < tree.subtree_size[b]; });

  std::vector<int> spine_chain;
  int chest = -1;
  for (int j = spine_start; j >= 0; j = largestChild(tree, j)) {
    if (branches(tree, j).size() >= 3) {
      chest = j;
      break;
    }
    spine_chain.push_back(j);
  }
  if (chest < 0) return found;

  const Eigen::Vector3d pelvis_position = skeleton.bindPosition(pelvis);
  const Eigen::Vector3d chest_position = skeleton.bindPosition(chest);
  std::vector<int> chest_branches = branches(tree, chest);
  // The neck continues the spine's line; the arms leave it sideways.
  std::sort(chest_branches.begin(), chest_branches.end(), [&](int a, int b) {
    double da = distanceToLine(skeleton.bindPosition(a), pelvis_position, chest_position);
    double db = distanceToLine(skeleton.bindPosition(b), pelvis_position, chest_position);
    return da != db ? da < db : a < b;
  });
  int neck = chest_branches[0];
  int arm_a = chest_branches[chest_branches.size() - 2];
  int arm_b = chest_branches[chest_branches.size() - 1];

  found["pelvis"] = pelvis;
  found["chest"] = chest;
  if (!spine_chain.empty()) found["spine_l5"] = spine_chain.front();
  if (spine_chain.size() >= 2) found["spine_t12"] = spine_chain.back();
  found["neck"] = neck;
  int head = largestChild(tree, neck);
  if (head >= 0) found["head"] = head;

  // Sides: names first; else geometry, with forward taken from the feet (toes point forward).
  std::string side_a = sideFromName(skeleton.names[arm_a]);
  std::string side_b = sideFromName(skeleton.names[arm_b]);
  if (side_a.empty() || side_b.empty() || side_a == side_b) {
    Eigen::Vector3d up = (chest_position - pelvis_position).normalized();
    Eigen::Vector3d toes = Eigen::Vector3d::Zero();
    for (int leg : pelvis_branches) {
      if (leg == spine_start) continue;
      int tip = leg;
      while (largestChild(tree, tip) >= 0) tip = largestChild(tree, tip);
      int ankle = skeleton.parents[tip];
      toes += skeleton.bindPosition(tip) - skeleton.bindPosition(ankle);
    }
    Eigen::Vector3d forward = (toes - up * toes.dot(up)).normalized();
    Eigen::Vector3d left = up.cross(forward);
    bool a_is_left = (skeleton.bindPosition(arm_a) - chest_position).dot(left) > 0;
    side_a = a_is_left ? "l" : "r";
    side_b = a_is_left ? "r" : "l";
  }

  for (auto [root, side] : {std::pair<int, std::string>{arm_a, side_a}, {arm_b, side_b}}) {
    std::vector<int> chain;
    for (int j = root; j >= 0 && chain.size() < 4; j = largestChild(tree, j)) chain.push_back(j);
    auto length = [&](int a, int b) { return (skeleton.bindPosition(a) - skeleton.bindPosition(b)).norm(); };
    size_t first_arm = 0;
    if (chain.size() >= 4 && length(chain[0], chain[1]) < 0.75 * length(chain[1], chain[2])) {
      found["clavicle_" + side] = chain[0];
      first_arm = 1;
    }
    if (chain.size() >= first_arm + 3) {
      found["upper_arm_" + side] = chain[first_arm];
      found["forearm_" + side] = chain[first_arm + 1];
      found["hand_" + side] = chain[first_arm + 2];
    }
  }
  addLegsFromStructure(skeleton, tree, pelvis, spine_start, &found);
  return found;
}

}  // namespace rigbake
