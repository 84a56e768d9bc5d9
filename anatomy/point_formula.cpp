#include "anatomy/point_formula.h"

#include <algorithm>
#include <sstream>

namespace rigbake {

const std::vector<std::string>& centralLandmarks() {
  static const std::vector<std::string> kNames = {"head", "neck", "chest", "spine_t12", "spine_l5", "pelvis"};
  return kNames;
}

const std::vector<std::string>& sidedLandmarks() {
  static const std::vector<std::string> kNames = {"clavicle",  "acromion",      "scapula", "upper_arm", "upper_arm_twist",
                                                  "forearm",   "forearm_twist", "hand",    "upper_leg", "lower_leg",
                                                  "foot",      "toe"};
  return kNames;
}

bool isOptionalLandmark(const std::string& base_name) {
  // Twist joints are a rig's choice; legs are optional so that a bust or a legless character still
  // resolves (the muscle presets and everything before the ROM clips use the arms and trunk only).
  return base_name == "upper_arm_twist" || base_name == "forearm_twist" || isLegLandmark(base_name);
}

bool isLegLandmark(const std::string& base_name) {
  return base_name == "upper_leg" || base_name == "lower_leg" || base_name == "foot" || base_name == "toe";
}

std::string sidedName(const std::string& name, const std::string& side) {
  const auto& sided = sidedLandmarks();
  if (std::find(sided.begin(), sided.end(), name) != sided.end()) return name + "_" + side;
  return name;
}

bool isCanonicalLandmark(const std::string& name) {
  const auto& central = centralLandmarks();
  if (std::find(central.begin(), central.end(), name) != central.end()) return true;
  for (const std::string& base : sidedLandmarks()) {
    if (name == base || name == base + "_l" || name == base + "_r") return true;
  }
  return false;
}

namespace {
std::string number(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}
}  // namespace

std::string PointFormula::describe(const std::string& side) const {
  auto list = [&](const std::vector<PointFormula>& items) {
    std::string text;
    for (size_t i = 0; i < items.size(); ++i) text += (i ? ", " : "") + items[i].describe(side);
    return text;
  };
  switch (kind) {
    case Kind::kAt: return sidedName(name, side);
    case Kind::kMean: return "mean(" + list(args) + ")";
    case Kind::kLerp: return "lerp(" + list(args) + ", " + number(t) + ")";
    case Kind::kSum: return "sum(" + list(args) + ")";
    case Kind::kDir: return name + "*" + number(ref_m);
    case Kind::kJointAxis: return sidedName(name, side) + "." + axis + "*" + number(ref_m);
    case Kind::kMix:
      return "mix(lateral=" + args[0].describe(side) + ", up=" + args[1].describe(side) +
             ", forward=" + args[2].describe(side) + ")";
    case Kind::kLocator: return name;
  }
  return "";
}

}  // namespace rigbake
