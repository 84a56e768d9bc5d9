// Landmark resolution: naming maps (presets/skeletons/*.json) or the VRM humanoid extension first,
// then the skeleton's structure, then the documented derivations (presets/landmarks.json) for what a
// skeleton lacks (most have no acromion or scapula joint). See docs/landmarks.md.
#include "anatomy/landmarks.h"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <limits>

#include "core/error.h"
#include "anatomy/formula_eval.h"
#include "anatomy/skeleton_structure.h"

namespace rigbake {

Eigen::Vector3d BodyFrame::direction(const std::string& name, const std::string& side) const {
  const double toward_side = side == "r" ? -1.0 : 1.0;
  if (name == "up") return up;
  if (name == "down") return -up;
  if (name == "forward") return forward;
  if (name == "back") return -forward;
  if (name == "lateral") return lateral * toward_side;
  if (name == "medial") return -lateral * toward_side;
  assert(false && "directions are checked when presets are parsed");
  return Eigen::Vector3d::Zero();
}

Eigen::Vector3d BodyFrame::mirror(const Eigen::Vector3d& point) const {
  return point - 2.0 * lateralOffset(point) * lateral;
}

bool LandmarkSet::has(const std::string& name) const {
  auto it = landmarks.find(name);
  return it != landmarks.end() && it->second.resolved;
}

const Landmark& LandmarkSet::get(const std::string& name) const {
  auto it = landmarks.find(name);
  assert(it != landmarks.end() && it->second.resolved);
  return it->second;
}

namespace {

std::string lowercase(const std::string& text) {
  std::string out;
  for (char c : text) out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Joint names as maps compare them: case folded, Maya/FBX namespaces ("rig:") and the map's own
// prefixes removed.
std::string normalizedJointName(const std::string& name, const NamingMap& map) {
  std::string lower = lowercase(name);
  for (const std::string& prefix : map.strip_prefixes) {
    std::string p = lowercase(prefix);
    if (lower.rfind(p, 0) == 0) {
      lower = lower.substr(p.size());
      break;
    }
  }
  size_t colon = lower.find_last_of(':');
  if (colon != std::string::npos) lower = lower.substr(colon + 1);
  return lower;
}

std::vector<std::string> expandPattern(const std::string& pattern, const NamingMap& map, const std::string& side) {
  size_t at = pattern.find("{side}");
  if (at == std::string::npos) return {lowercase(pattern)};
  std::vector<std::string> names;
  auto tokens = map.side_tokens.find(side);
  if (tokens == map.side_tokens.end()) return names;
  for (const std::string& token : tokens->second)
    names.push_back(lowercase(pattern.substr(0, at) + token + pattern.substr(at + 6)));
  return names;
}

struct MapMatch {
  std::map<std::string, int> joints;               // full landmark name -> joint
  std::map<std::string, std::vector<std::string>> tried;  // full landmark name -> names tried
  // full landmark name -> position of the matching name among those tried (0: the map's first choice)
  std::map<std::string, int> rank;
};

MapMatch matchMap(const NamingMap& map, const Character& character) {
  MapMatch match;
  const Skeleton& skeleton = character.skeleton;
  std::map<std::string, int> joint_by_name;  // normalized name -> first joint with it
  if (map.match == "names") {
    for (int j = 0; j < skeleton.size(); ++j) joint_by_name.emplace(normalizedJointName(skeleton.names[j], map), j);
  } else {
    for (const auto& [bone, joint] : character.vrm_humanoid) joint_by_name.emplace(lowercase(bone), joint);
  }
  for (const auto& [landmark, patterns] : map.landmarks) {
    const auto& central = centralLandmarks();
    bool is_central = std::find(central.begin(), central.end(), landmark) != central.end();
    std::vector<std::string> sides = is_central ? std::vector<std::string>{""} : std::vector<std::string>{"l", "r"};
    if (!is_central && (landmark.size() > 2 && (landmark.substr(landmark.size() - 2) == "_l" ||
                                                 landmark.substr(landmark.size() - 2) == "_r")))
      sides = {""};
    for (const std::string& side : sides) {
      std::string full = side.empty() ? landmark : landmark + "_" + side;
      for (const std::string& pattern : patterns) {
        for (const std::string& name : expandPattern(pattern, map, side.empty() ? "l" : side)) {
          match.tried[full].push_back(name);
          auto it = joint_by_name.find(name);
          if (it != joint_by_name.end() && !match.joints.count(full)) {
            match.joints[full] = it->second;
            match.rank[full] = static_cast<int>(match.tried[full].size()) - 1;
          }
        }
      }
    }
  }
  return match;
}

std::vector<std::string> allLandmarkNames() {
  std::vector<std::string> names = centralLandmarks();
  for (const char* side : {"l", "r"}) {
    for (const std::string& base : sidedLandmarks()) names.push_back(base + "_" + side);
  }
  return names;
}

std::string baseOf(const std::string& name) {
  if (name.size() > 2 && (name.substr(name.size() - 2) == "_l" || name.substr(name.size() - 2) == "_r"))
    return name.substr(0, name.size() - 2);
  return name;
}

BodyFrame computeBodyFrame(const Character& character, const LandmarkSet& set) {
  BodyFrame body;
  const Eigen::Vector3d pelvis = set.get("pelvis").position;
  Eigen::Vector3d top = set.has("neck") ? set.get("neck").position
                        : set.has("head") ? set.get("head").position
                                          : set.get("chest").position;
  Eigen::Vector3d left = set.get("upper_arm_l").position;
  Eigen::Vector3d right = set.get("upper_arm_r").position;
  Eigen::Vector3d lateral = left - right;
  Eigen::Vector3d up = top - pelvis;
  // Keep the shoulder line exact (mirroring depends on it) and square the up axis against it.
  body.lateral = lateral.normalized();
  body.up = (up - body.lateral * up.dot(body.lateral)).normalized();
  body.forward = body.lateral.cross(body.up);
  body.midline = (left + right) / 2.0;
  body.height = bodyHeight(character, body.up);
  return body;
}

bool hasDerivation(const LandmarkRules& rules, const std::string& landmark) {
  return std::any_of(rules.derivations.begin(), rules.derivations.end(),
                     [&](const LandmarkDerivation& rule) { return rule.landmark == landmark; });
}

// Two spine landmarks on one joint make a segment of length zero, which no frame built on it survives
// (retargeting, trapezius drivers). It happens when a map's fallback name is another landmark's first
// choice: a VRM humanoid without the optional upperChest bone resolves both spine_t12 (chest) and
// chest (upperChest, else chest) to its Chest bone. Of two such landmarks the one that has a
// derivation is taken off the joint so that presets/landmarks.json places it between its neighbours;
// when both have one, the better match keeps the joint (the earlier pattern of the map; on a tie the
// one higher on the spine). Returns what was taken off, for restoreUnderived.
std::map<std::string, Landmark> separateCoincidentSpineLandmarks(LandmarkSet* set, const MapMatch& match,
                                                                 const LandmarkRules& rules) {
  std::map<std::string, Landmark> taken_off;
  const std::vector<std::string>& spine = centralLandmarks();  // head first, pelvis last
  auto rankOf = [&](const std::string& name) {
    auto it = match.rank.find(name);
    return it == match.rank.end() || set->landmarks.at(name).source == "structure" ? 0 : it->second;
  };
  for (size_t a = 0; a < spine.size(); ++a) {
    for (size_t b = a + 1; b < spine.size(); ++b) {
      const Landmark& upper = set->landmarks.at(spine[a]);
      const Landmark& lower = set->landmarks.at(spine[b]);
      if (!upper.resolved || !lower.resolved || upper.joint != lower.joint) continue;
      const bool upper_derivable = hasDerivation(rules, spine[a]);
      const bool lower_derivable = hasDerivation(rules, spine[b]);
      std::string off;
      if (upper_derivable && lower_derivable) off = rankOf(spine[b]) >= rankOf(spine[a]) ? spine[b] : spine[a];
      else if (upper_derivable) off = spine[a];
      else if (lower_derivable) off = spine[b];
      else continue;
      taken_off[off] = set->landmarks.at(off);
      set->landmarks[off] = Landmark{};
    }
  }
  return taken_off;
}

// A landmark taken off a shared joint whose derivation could not run after all goes back on it: a
// coincident pair is still better than a missing landmark.
void restoreUnderived(LandmarkSet* set, const std::map<std::string, Landmark>& taken_off) {
  for (const auto& [name, landmark] : taken_off) {
    if (!set->has(name)) set->landmarks[name] = landmark;
  }
}

void requireLandmarks(const LandmarkSet& set, const std::vector<std::string>& names, const MapMatch* match,
                      const std::string& map_name, const std::string& file) {
  for (const std::string& name : names) {
    if (set.has(name)) continue;
    std::string tried;
    if (match && match->tried.count(name)) {
      for (const std::string& n : match->tried.at(name)) tried += (tried.empty() ? "" : ", ") + n;
    }
    // A naming map that spells the joint is the fix; the caller knows how its user gives one.
    throw FixableByOption(errc::LANDMARK_UNRESOLVED, file,
                          "landmark '" + name + "' matches no joint (map " + map_name + " tried: " +
                              (tried.empty() ? "nothing" : tried) +
                              "; the structural fallback found none) and cannot be derived; give a JSON naming map",
                          "map");
  }
}

}  // namespace

double bodyHeight(const Character& character, const Eigen::Vector3d& up) {
  double lowest = std::numeric_limits<double>::max();
  double highest = std::numeric_limits<double>::lowest();
  for (const MeshPart& part : character.meshes) {
    if (!part.skinned && part.rigid_joint < 0) continue;
    for (const Eigen::Vector3d& p : part.positions) {
      double h = p.dot(up);
      lowest = std::min(lowest, h);
      highest = std::max(highest, h);
    }
  }
  if (highest > lowest) return highest - lowest;
  // No mesh: the skeleton spans roughly the body minus the skull above the head joint.
  for (int j = 0; j < character.skeleton.size(); ++j) {
    double h = character.skeleton.bindPosition(j).dot(up);
    lowest = std::min(lowest, h);
    highest = std::max(highest, h);
  }
  return (highest - lowest) * 1.1;
}

int countMapMatches(const NamingMap& map, const Character& character) {
  return static_cast<int>(matchMap(map, character).joints.size());
}

namespace {

// LandmarkSet::anatomical_parents. Each rule re-hangs at most one joint per side, in the rules' order,
// and later rules see the earlier ones' hierarchy.
std::vector<int> anatomicalParents(const Skeleton& skeleton, const LandmarkSet& set,
                                   const std::vector<LimbRootRule>& rules) {
  std::vector<int> parents = skeleton.parents;
  // The joint a landmark was resolved to, or -1 when it is derived (it only rides a joint) or missing.
  const auto ownJoint = [&](const std::string& name) {
    if (!set.has(name)) return -1;
    const Landmark& landmark = set.get(name);
    return landmark.resolved && !landmark.from_joint.empty() ? landmark.joint : -1;
  };
  const auto isAncestor = [&](int ancestor, int joint) {  // strictly
    for (int j = parents[joint]; j >= 0; j = parents[j])
      if (j == ancestor) return true;
    return false;
  };
  for (const LimbRootRule& rule : rules) {
    const int anchor = ownJoint(rule.anchor);
    if (anchor < 0) continue;
    std::vector<int> trunk;  // the joints whose subtrees the limb should not hang in
    for (const std::string& name : rule.not_under) {
      const int joint = ownJoint(name);
      if (joint >= 0 && isAncestor(anchor, joint)) trunk.push_back(joint);
    }
    const auto inTrunkSubtree = [&](int joint) {
      for (int top : trunk)
        if (joint == top || isAncestor(top, joint)) return true;
      return false;
    };
    for (const char* side : {"l", "r"}) {
      int root = -1;
      for (const std::string& limb : rule.limb)
        if (root < 0) root = ownJoint(sidedName(limb, side));
      if (root < 0 || !isAncestor(anchor, root) || !inTrunkSubtree(root)) continue;
      int above = parents[root];
      while (inTrunkSubtree(above)) above = parents[above];
      parents[root] = above;
    }
  }
  return parents;
}

}  // namespace

LandmarkSet resolveLandmarks(const Character& character, const LandmarkInputs& inputs) {
  assert(inputs.rules);
  const Skeleton& skeleton = character.skeleton;
  LandmarkSet set;
  for (const std::string& name : allLandmarkNames()) set.landmarks[name] = Landmark{};

  // 1. Naming map: the forced one, the VRM humanoid when the file has one, or the best-matching map.
  const NamingMap* chosen = inputs.forced_map;
  MapMatch match;
  if (!chosen && inputs.maps) {
    int best = 0;
    for (const NamingMap& map : *inputs.maps) {
      if (map.match == "vrm_humanoid" && character.vrm_humanoid.empty()) continue;
      int score = countMapMatches(map, character);
      // VRM's own mapping beats any guess from names.
      if (map.match == "vrm_humanoid") score += 1000;
      if (score > best) {
        best = score;
        chosen = &map;
      }
    }
  }
  if (chosen) {
    match = matchMap(*chosen, character);
    set.map_name = chosen->name;
    for (const auto& [name, joint] : match.joints) {
      Landmark& landmark = set.landmarks[name];
      landmark.resolved = true;
      landmark.joint = joint;
      landmark.from_joint = skeleton.names[joint];
      landmark.position = skeleton.bindPosition(joint);
      landmark.source = chosen->match == "vrm_humanoid" ? "vrm" : "map:" + chosen->name;
    }
  }
  // 2. A map that names fewer than six landmarks is not this skeleton's convention: structure decides
  // what it can, and the map keeps the rest. A fitting map is not mixed with structure, whose chains
  // need not agree with the map's choices.
  if (!inputs.forced_map && match.joints.size() < 6) {
    for (const auto& [name, joint] : landmarksFromStructure(skeleton)) {
      Landmark& landmark = set.landmarks[name];
      landmark.resolved = true;
      landmark.joint = joint;
      landmark.from_joint = skeleton.names[joint];
      landmark.position = skeleton.bindPosition(joint);
      landmark.source = "structure";
    }
    set.map_name = chosen ? chosen->name + "+structure" : "structure";
  }
  const std::map<std::string, Landmark> taken_off = separateCoincidentSpineLandmarks(&set, match, *inputs.rules);
  const std::string file = character.source;
  const std::string map_name = chosen ? chosen->name : "none";
  requireLandmarks(set, {"pelvis", "chest", "upper_arm_l", "upper_arm_r"}, &match, map_name, file);
  set.body = computeBodyFrame(character, set);

  // 3. Derivations, in file order; the first applicable rule for a landmark wins.
  for (const LandmarkDerivation& rule : inputs.rules->derivations) {
    const auto& central = centralLandmarks();
    bool is_central = std::find(central.begin(), central.end(), rule.landmark) != central.end();
    for (const std::string& side : is_central ? std::vector<std::string>{"l"} : std::vector<std::string>{"l", "r"}) {
      std::string full = sidedName(rule.landmark, side);
      if (set.has(full)) continue;
      std::string carrier = sidedName(rule.rides_on, side);
      if (!set.has(carrier) || !formulaInputsResolved(rule.formula, set, side)) continue;
      FormulaContext context{&skeleton, &set, side, inputs.rules->reference_height, nullptr, inputs.rules->file};
      Landmark landmark;
      landmark.resolved = true;
      landmark.position = evaluateFormula(rule.formula, context);
      landmark.joint = set.get(carrier).joint;
      landmark.derived = rule.formula.describe(side);
      landmark.source = "derived";
      set.landmarks[full] = landmark;
    }
  }
  restoreUnderived(&set, taken_off);
  std::vector<std::string> required;
  for (const std::string& name : allLandmarkNames()) {
    if (!isOptionalLandmark(baseOf(name))) required.push_back(name);
  }
  requireLandmarks(set, required, &match, map_name, file);
  set.anatomical_parents = anatomicalParents(skeleton, set, inputs.rules->limb_roots);
  return set;
}

}  // namespace rigbake
