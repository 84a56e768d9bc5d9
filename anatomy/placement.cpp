#include "anatomy/placement.h"
#include "core/file_name.h"

#include <algorithm>
#include <cctype>
#include <iomanip>
#include <map>
#include <sstream>

#include "core/error.h"
#include "anatomy/formula_eval.h"

namespace rigbake {

std::string correctivePartName(const std::string& name, const std::string& carrier_landmark) {
  std::string out = name;
  bool start = true;
  for (char c : carrier_landmark) {
    if (c == '_') {
      start = true;
      continue;
    }
    out += start ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    start = false;
  }
  return out;
}

MuscleLocator locatorOn(const Skeleton& skeleton, int joint, const Eigen::Vector3d& world) {
  MuscleLocator locator;
  locator.world = world;
  locator.joint = joint;
  locator.local = skeleton.bind_world[joint].inverse() * world;
  return locator;
}

MusclePart partFromPreset(const Skeleton& skeleton, const PresetPart& spec, const std::string& side, int origin_joint,
                          int insertion_joint, const Eigen::Vector3d& origin, const Eigen::Vector3d& insertion,
                          const Eigen::Vector3d& driver, double scale) {
  MusclePart part;
  part.group = spec.group;
  part.name = spec.name;
  part.side = side;
  part.kind = spec.kind;
  part.origin = locatorOn(skeleton, origin_joint, origin);
  part.insertion = locatorOn(skeleton, insertion_joint, insertion);
  part.driver = locatorOn(skeleton, origin_joint, driver);
  part.compression = spec.compression;
  part.stretch = spec.stretch;
  part.bulge = Eigen::Vector2d(spec.bulge[0], spec.bulge[1]) * scale;
  part.weight_radius = spec.weight_radius_ref_m * scale;
  part.response = defaultResponse(part);
  return part;
}

namespace {

// The first attach landmark the skeleton resolves (the talk's twist joints, else the arm joints).
std::string chooseAttach(const std::vector<std::string>& candidates, const LandmarkSet& landmarks,
                         const std::string& side, const MusclePreset& preset, const PresetPart& part,
                         const char* which) {
  for (const std::string& candidate : candidates) {
    if (landmarks.has(sidedName(candidate, side))) return candidate;
  }
  std::string list;
  for (const std::string& candidate : candidates) list += (list.empty() ? "" : ", ") + sidedName(candidate, side);
  fail(errc::LANDMARK_UNRESOLVED, preset.file + "#" + part.pointer + "/" + which,
       "no attach landmark of " + part.name + " is resolved (tried: " + list + ")");
}

// The landmark on the other side: clavicle_l <-> clavicle_r; central landmarks are their own twin.
std::string twinLandmark(const std::string& name) {
  if (name.size() > 2 && name.compare(name.size() - 2, 2, "_l") == 0) return name.substr(0, name.size() - 2) + "_r";
  if (name.size() > 2 && name.compare(name.size() - 2, 2, "_r") == 0) return name.substr(0, name.size() - 2) + "_l";
  return name;
}

}  // namespace

MusclePart mirrorPart(const MusclePart& left, const Skeleton& skeleton, const LandmarkSet& landmarks,
                      const std::string& origin_landmark, const std::string& insertion_landmark) {
  const BodyFrame& body = landmarks.body;
  MusclePart right = left;
  right.side = "Right";
  int origin_joint = landmarks.get(twinLandmark(origin_landmark)).joint;
  int insertion_joint = landmarks.get(twinLandmark(insertion_landmark)).joint;
  right.origin = locatorOn(skeleton, origin_joint, body.mirror(left.origin.world));
  right.insertion = locatorOn(skeleton, insertion_joint, body.mirror(left.insertion.world));
  right.driver = locatorOn(skeleton, origin_joint, body.mirror(left.driver.world));
  if (left.kind == PartKind::kCorrective) {
    right.carrier_landmark = twinLandmark(left.carrier_landmark);
    right.carrier = landmarks.get(right.carrier_landmark).joint;
  }
  return right;
}

namespace {

// The muscle file's range (docs/muscle-json.md, formats/muscle_json.cpp): no locator further than this
// many body heights from the scene's origin. A preset within its own ranges (offsets up to 100 reference
// heights, lerps up to 100 beyond their ends) can still add up to a point far past it, which the bake
// would write into a muscle file that it then refuses to read (found by tests/cli_edge_numbers_test.cpp).
constexpr double kMaxReachBodyHeights = 100.0;

void requirePlacedWithinReach(const MusclePreset& preset, const PresetPart& spec, const char* which,
                              const Eigen::Vector3d& point, double body_height) {
  const double reach = kMaxReachBodyHeights * std::max(body_height, 1e-3);
  if (point.norm() <= reach) return;
  std::ostringstream text;
  text << std::setprecision(6) << "places the " << which << " of " << spec.name << " " << point.norm()
       << " m from the origin; a muscle lies within " << kMaxReachBodyHeights << " body heights (" << reach << " m)";
  fail(errc::PRESET_INVALID, preset.file + "#" + spec.pointer, text.str());
}

}  // namespace

MuscleSet placeMuscles(const Character& character, const LandmarkSet& landmarks, const MusclePreset& preset,
                       Sides sides) {
  const Skeleton& skeleton = character.skeleton;
  MuscleSet set;
  set.character = fileNameOf(character.source);
  set.body_height = landmarks.body.height;
  set.anatomical_parents = landmarks.anatomical_parents;
  const double scale = landmarks.body.height / preset.reference_height;

  std::map<std::string, Eigen::Vector3d> placed;
  std::vector<MusclePart> lefts, rights;
  for (const PresetPart& spec : preset.parts) {
    // An optional part (a leg muscle on a character without legs) is left out when a landmark it
    // needs does not resolve; any other part fails the placement with the landmark's name.
    try {
      std::string origin_attach = sidedName(chooseAttach(spec.origin_attach, landmarks, "l", preset, spec, "origin_attach"), "l");
      std::string insertion_attach =
          sidedName(chooseAttach(spec.insertion_attach, landmarks, "l", preset, spec, "insertion_attach"), "l");
      FormulaContext context{&skeleton, &landmarks, "l", preset.reference_height, &placed, preset.file};
      Eigen::Vector3d origin = evaluateFormula(spec.origin, context);
      placed[spec.name + ".origin"] = origin;
      Eigen::Vector3d insertion = evaluateFormula(spec.insertion, context);
      placed[spec.name + ".insertion"] = insertion;
      Eigen::Vector3d driver = spec.has_driver ? evaluateFormula(spec.driver, context) : (origin + insertion) / 2.0;
      requirePlacedWithinReach(preset, spec, "origin", origin, landmarks.body.height);
      requirePlacedWithinReach(preset, spec, "insertion", insertion, landmarks.body.height);
      requirePlacedWithinReach(preset, spec, "driver", driver, landmarks.body.height);

      const MusclePart part = partFromPreset(skeleton, spec, "Left", landmarks.get(origin_attach).joint,
                                             landmarks.get(insertion_attach).joint, origin, insertion, driver, scale);
      // A muscle is one part; a corrective one part per carrier its skeleton resolves (a carrier whose
      // joint an earlier one has would only split that joint's weight between two equal joints).
      std::vector<MusclePart> made;
      if (spec.kind == PartKind::kMuscle) made.push_back(part);
      std::vector<int> carrier_joints;
      for (const std::string& carrier : spec.carriers) {
        const std::string sided = sidedName(carrier, "l");
        if (!landmarks.has(sided) || !landmarks.has(twinLandmark(sided))) continue;
        const int joint = landmarks.get(sided).joint;
        if (std::find(carrier_joints.begin(), carrier_joints.end(), joint) != carrier_joints.end()) continue;
        carrier_joints.push_back(joint);
        MusclePart carried = part;
        carried.name = correctivePartName(spec.name, carrier);
        carried.carrier_landmark = sided;
        carried.carrier = joint;
        made.push_back(std::move(carried));
      }
      for (MusclePart& one : made) {
        if (sides != Sides::kLeft) {
          // The mirror plane need not pass near the scene's origin, so a left locator within reach can
          // mirror out of it: the right side is checked on its own.
          MusclePart right = mirrorPart(one, skeleton, landmarks, origin_attach, insertion_attach);
          requirePlacedWithinReach(preset, spec, "mirrored origin", right.origin.world, landmarks.body.height);
          requirePlacedWithinReach(preset, spec, "mirrored insertion", right.insertion.world, landmarks.body.height);
          requirePlacedWithinReach(preset, spec, "mirrored driver", right.driver.world, landmarks.body.height);
          rights.push_back(std::move(right));
        }
        lefts.push_back(std::move(one));
      }
    } catch (const Error& error) {
      if (!spec.optional || error.code() != "LANDMARK_UNRESOLVED") throw;
    }
  }
  if (sides != Sides::kRight) set.parts.insert(set.parts.end(), lefts.begin(), lefts.end());
  set.parts.insert(set.parts.end(), rights.begin(), rights.end());
  return set;
}

}  // namespace rigbake
