// Anatomy as data: the plain structs that presets/*.json are parsed into (formats/preset_json.cpp
// parses them strictly). Adding a muscle or a skeleton naming needs only a JSON file.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "anatomy/muscle_set.h"
#include "anatomy/point_formula.h"

namespace rigbake {

// presets/skeletons/*.json: how one naming convention spells the canonical landmarks.
struct NamingMap {
  std::string name;
  std::string file;
  std::string description;
  // "names": match joint names; "vrm_humanoid": match the VRM extension's humanoid bone names.
  std::string match = "names";
  // Prefixes removed from joint names before matching (e.g. "mixamorig:"). Matching ignores case.
  std::vector<std::string> strip_prefixes;
  // Tokens "{side}" stands for, per side ("l", "r"): e.g. {"l": ["Left"], "r": ["Right"]}.
  std::map<std::string, std::vector<std::string>> side_tokens;
  // Canonical landmark (central name, or sided base name) -> candidate joint names, best first.
  std::map<std::string, std::vector<std::string>> landmarks;
};

// presets/landmarks.json: how a landmark that a skeleton lacks is derived from the ones it has.
struct LandmarkDerivation {
  std::string landmark;  // central name or sided base name
  PointFormula formula;
  std::string rides_on;  // landmark whose joint carries the derived point
  std::string pointer;
};

// presets/landmarks.json "limb_roots": where the muscles take a limb to hang from when a rig hangs it
// elsewhere (3ds Max's Biped can hang the clavicles from the neck and the thighs from the spine).
// Per side, the first `limb` landmark resolved to a joint of its own: when that joint lies in the
// subtree of a `not_under` landmark's joint (one resolved to a joint of its own, strictly below
// `anchor`'s joint), the muscles take it as hanging from its nearest ancestor outside those subtrees.
struct LimbRootRule {
  std::vector<std::string> limb;       // sided base names, best first
  std::string anchor;                  // central name
  std::vector<std::string> not_under;  // central names
  std::string pointer;
};

struct LandmarkRules {
  std::string file;
  double reference_height = 1.8;
  std::vector<LandmarkDerivation> derivations;  // in evaluation order
  std::vector<LimbRootRule> limb_roots;
};

// presets/muscles/*.json: one entry per muscle part, left side; the right side is mirrored.
struct PresetPart {
  std::string group;
  std::vector<std::string> group_aliases;  // other spellings read from talk-shaped files (TerasMajor)
  std::string name;
  // Attach landmarks, best first: the first that the skeleton resolves is used (the talk attaches
  // the biceps to the twist joints; skeletons without them fall back to the arm joints).
  std::vector<std::string> origin_attach;
  std::vector<std::string> insertion_attach;
  PointFormula origin;
  PointFormula insertion;
  bool has_driver = false;  // absent: the driver rests at the origin-insertion midpoint
  PointFormula driver;
  double compression = 0.5;
  double stretch = 1.5;
  double bulge[2] = {0.0, 0.0};
  double weight_radius_ref_m = 0.0;  // 0: derive from the body measure
  bool optional = false;  // skipped (both sides) when a landmark it needs does not resolve
  PartKind kind = PartKind::kMuscle;
  // Correctives: the landmarks whose joints carry them, one part each, named name + the landmark in
  // UpperCamelCase (correctivePartName()). A carrier the skeleton does not resolve, or whose joint an
  // earlier carrier of the entry already has, makes no part.
  std::vector<std::string> carriers;
  std::string pointer;
};

// "Axilla" carried by "upper_arm" is "AxillaUpperArm".
std::string correctivePartName(const std::string& name, const std::string& carrier_landmark);

struct MusclePreset {
  std::string name;
  std::string file;
  double reference_height = 1.8;
  std::vector<PresetPart> parts;
};

}  // namespace rigbake
