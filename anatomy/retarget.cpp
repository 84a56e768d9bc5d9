// Retargeting muscle locators between characters through canonical landmark frames.
//
// Sources: the God of War Ragnarök talk, "Import/Export Muscle Data" (muscle joints exported as world
// positions per group and side, imported onto another character); the talk's "Spinal Column" landmark
// mapping (docs/landmarks.md), which gives every skeleton the same named points whatever its joints
// are called. The method is the segment-relative transfer common to marker and rig retargeting: a
// point is stored in the frame of the bone segment it rides on, with the coordinate along the bone
// normalized by the bone's length (so it keeps its place between the joints) and the coordinates
// across it by body height (so thickness scales with the body, not with one bone's length).
// docs/retarget.md gives the frames and the measured accuracy.
#include "anatomy/retarget.h"
#include "core/file_name.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <tuple>

#include "core/error.h"
#include "anatomy/placement.h"

namespace rigbake {
namespace {

// A frame is anchored at `origin` with its first axis along from -> to; all three are canonical
// landmark names of one side (or central).
struct SegmentFrame {
  std::string origin;
  std::string from;
  std::string to;

  bool operator==(const SegmentFrame& other) const {
    return origin == other.origin && from == other.from && to == other.to;
  }
  std::string describe() const {
    return origin == from ? from + "->" + to : origin + "@" + from + "->" + to;
  }
};

std::string sideSuffixOf(const std::string& name) {
  if (name.size() > 2 && (name.compare(name.size() - 2, 2, "_l") == 0 || name.compare(name.size() - 2, 2, "_r") == 0))
    return name.substr(name.size() - 1);
  return "";
}

std::string baseNameOf(const std::string& name) {
  return sideSuffixOf(name).empty() ? name : name.substr(0, name.size() - 2);
}

// Each canonical landmark's frame. Frames follow the bone the landmark starts: the spine from sacrum
// to skull, the clavicle to the acromion, the arm bones to the next arm joint. The acromion and the
// scapula share the spine of the scapula (the talk's trapezius B/C and posterior deltoid attach along
// it). The head and the hand end their chains, so they reuse the segment that arrives at them. Twist
// joints lie on their arm bone and take its frame, so a locator on a twist joint lands on a skeleton
// without twist joints unchanged, and back.
SegmentFrame frameOf(const std::string& landmark) {
  static const std::map<std::string, std::array<const char*, 3>> kFrames = {
      {"pelvis", {"pelvis", "pelvis", "spine_l5"}},
      {"spine_l5", {"spine_l5", "spine_l5", "spine_t12"}},
      {"spine_t12", {"spine_t12", "spine_t12", "chest"}},
      {"chest", {"chest", "chest", "neck"}},
      {"neck", {"neck", "neck", "head"}},
      {"head", {"head", "neck", "head"}},
      {"clavicle", {"clavicle", "clavicle", "acromion"}},
      {"acromion", {"acromion", "acromion", "scapula"}},
      {"scapula", {"scapula", "scapula", "acromion"}},
      {"upper_arm", {"upper_arm", "upper_arm", "forearm"}},
      {"upper_arm_twist", {"upper_arm", "upper_arm", "forearm"}},
      {"forearm", {"forearm", "forearm", "hand"}},
      {"forearm_twist", {"forearm", "forearm", "hand"}},
      {"hand", {"hand", "forearm", "hand"}},
      {"upper_leg", {"upper_leg", "upper_leg", "lower_leg"}},
      {"lower_leg", {"lower_leg", "lower_leg", "foot"}},
      {"foot", {"foot", "lower_leg", "foot"}},
      {"toe", {"toe", "foot", "toe"}},
  };
  const std::string side = sideSuffixOf(landmark);
  auto it = kFrames.find(baseNameOf(landmark));
  assert(it != kFrames.end() && "every canonical landmark has a frame");
  return {sidedName(it->second[0], side.empty() ? "l" : side), sidedName(it->second[1], side.empty() ? "l" : side),
          sidedName(it->second[2], side.empty() ? "l" : side)};
}

// An orthonormal basis and per-axis scale: coordinates = scale^-1 * axes^T * (world - origin).
struct Basis {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: along, across (forward-ish), across
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();

  Eigen::Vector3d toLocal(const Eigen::Vector3d& world) const {
    return (axes.transpose() * (world - origin)).cwiseQuotient(scale);
  }
  Eigen::Vector3d toWorld(const Eigen::Vector3d& coords) const { return origin + axes * coords.cwiseProduct(scale); }
};

// The second axis is the body's forward made orthogonal to the first, or the body's up when the first
// runs nearly forward (a fixed threshold, so both characters pick the same reference unless a bone
// points more than ~37 degrees differently).
constexpr double kForwardAlignedLimit = 0.8;

Basis basisAlong(const Eigen::Vector3d& origin, const Eigen::Vector3d& axis, double across_scale, const BodyFrame& body) {
  Basis basis;
  const double length = axis.norm();
  assert(length > 0.0);
  const Eigen::Vector3d along = axis / length;
  const Eigen::Vector3d reference = std::abs(along.dot(body.forward)) > kForwardAlignedLimit ? body.up : body.forward;
  const Eigen::Vector3d across = (reference - along * reference.dot(along)).normalized();
  basis.origin = origin;
  basis.axes.col(0) = along;
  basis.axes.col(1) = across;
  basis.axes.col(2) = along.cross(across);
  basis.scale = Eigen::Vector3d(length, across_scale, across_scale);
  return basis;
}

Basis segmentBasis(const SegmentFrame& frame, const LandmarkSet& landmarks) {
  const Eigen::Vector3d axis = landmarks.get(frame.to).position - landmarks.get(frame.from).position;
  return basisAlong(landmarks.get(frame.origin).position, axis, landmarks.body.height, landmarks.body);
}

// Below this fraction of body height a segment or a muscle has no usable direction.
constexpr double kDegenerateFraction = 1e-6;

bool segmentUsable(const SegmentFrame& frame, const LandmarkSet& landmarks) {
  const double length = (landmarks.get(frame.to).position - landmarks.get(frame.from).position).norm();
  return length > kDegenerateFraction * landmarks.body.height;
}

// The preset entry a part was placed from: a muscle's by name, a corrective's by the name it has with
// one of the entry's carriers.
const PresetPart* findPresetPart(const MusclePreset& preset, const MusclePart& part) {
  for (const PresetPart& spec : preset.parts) {
    if (spec.kind != part.kind) continue;
    if (spec.kind == PartKind::kMuscle && spec.name == part.name) return &spec;
    for (const std::string& carrier : spec.carriers) {
      if (correctivePartName(spec.name, carrier) == part.name) return &spec;
    }
  }
  return nullptr;
}

// The preset's attach candidates for a locator: the driver rides the origin's joint, as placed.
const std::vector<std::string>* attachCandidates(const PresetPart* spec, const std::string& which) {
  if (!spec) return nullptr;
  return which == "insertion" ? &spec->insertion_attach : &spec->origin_attach;
}

// Among the landmarks riding on `joint`, the one that is the joint itself, else the nearest to the
// locator, else by name; empty when none rides on it. Leg landmarks are not anchors (yet): they are
// optional, so a destination may have no leg frame, and a locator on a leg keeps riding the pelvis
// as it did before legs were landmarks.
std::string landmarkOnJoint(int joint, const Eigen::Vector3d& world, const Skeleton& skeleton,
                            const LandmarkSet& landmarks) {
  std::string best;
  std::tuple<int, double> best_rank{std::numeric_limits<int>::max(), 0.0};
  for (const auto& [name, landmark] : landmarks.landmarks) {  // std::map: name order breaks ties
    if (!landmark.resolved || landmark.joint != joint || isLegLandmark(baseNameOf(name))) continue;
    std::tuple<int, double> rank{landmark.from_joint == skeleton.names[joint] ? 0 : 1,
                                 (landmark.position - world).norm()};
    if (best.empty() || rank < best_rank) {
      best = name;
      best_rank = rank;
    }
  }
  return best;
}

// The frame a preset rule builds its point in: lerp(A, B) lies on the segment A -> B; any other rule
// starts from a landmark (the first term of a sum or mean, the `up` component of a mix, which sets the
// point's height on the trunk) and is carried in that landmark's frame. Why not the attach landmark's:
// the preset hangs some locators on one landmark but places them from others, and those landmarks are
// not where different skeleton conventions agree. CesiumMan's structural chest is the joint where the
// arms branch, on the shoulder line, while the sample's T8 is 0.13 m below it; trapezius B's origin is
// attached to the chest but placed from the neck and the scapula, so carried along chest -> neck it
// missed the direct placement by up to 4.6% of body height (docs/retarget.md).
std::optional<SegmentFrame> formulaFrame(const PointFormula& formula, const std::string& side) {
  using Kind = PointFormula::Kind;
  switch (formula.kind) {
    case Kind::kAt:
      return frameOf(sidedName(formula.name, side));
    case Kind::kLerp: {
      const PointFormula& a = formula.args[0];
      const PointFormula& b = formula.args[1];
      // Twist landmarks are optional: a segment between them may not exist on the destination.
      if (a.kind == Kind::kAt && b.kind == Kind::kAt && !isOptionalLandmark(baseNameOf(a.name)) &&
          !isOptionalLandmark(baseNameOf(b.name)) && sidedName(a.name, side) != sidedName(b.name, side))
        return SegmentFrame{sidedName(a.name, side), sidedName(a.name, side), sidedName(b.name, side)};
      return formulaFrame(a, side);
    }
    case Kind::kMean:
    case Kind::kSum:
      return formula.args.empty() ? std::nullopt : formulaFrame(formula.args[0], side);
    case Kind::kMix:
      return formulaFrame(formula.args[1], side);
    case Kind::kDir:
    case Kind::kJointAxis:
    case Kind::kLocator:
      return std::nullopt;
  }
  return std::nullopt;
}

// The preset rule of a locator, when the preset knows the part (drivers only when it gives one).
const PointFormula* presetFormula(const PresetPart* spec, const std::string& which) {
  if (!spec) return nullptr;
  if (which == "origin") return &spec->origin;
  if (which == "insertion") return &spec->insertion;
  return spec->has_driver ? &spec->driver : nullptr;
}

struct Anchor {
  std::string landmark;  // on the source
  SegmentFrame frame;
  std::string dst_landmark;  // whose joint carries the locator on the destination
};

// Which canonical landmark a source locator rides on. The preset's own attach landmarks decide first
// (several derived landmarks can ride on one joint: on CesiumMan the chest joint carries chest,
// clavicle, acromion and scapula), then the landmarks on the joint, then on its nearest ancestor
// carrying any (a hand-tuned locator on a finger joint follows the hand).
std::string sourceLandmark(const MusclePart& part, const std::string& which, const MuscleLocator& locator,
                           const Skeleton& skeleton, const LandmarkSet& landmarks, const PresetPart* spec,
                           const std::string& where) {
  const std::string side = part.side == "Right" ? "r" : "l";
  if (const std::vector<std::string>* candidates = attachCandidates(spec, which)) {
    for (const std::string& candidate : *candidates) {
      const std::string name = sidedName(candidate, side);
      if (landmarks.has(name) && landmarks.get(name).joint == locator.joint) return name;
    }
  }
  for (int joint = locator.joint; joint >= 0; joint = skeleton.parents[joint]) {
    std::string name = landmarkOnJoint(joint, locator.world, skeleton, landmarks);
    if (!name.empty()) return name;
  }
  fail(errc::RETARGET_LOCATOR_UNANCHORED, where,
       "joint '" + skeleton.names[locator.joint] +
           "' carries no canonical landmark and neither does any joint above it, so the locator has no body "
           "segment to be carried in (attach it to an arm, shoulder or spine joint)");
}

// Which destination landmark's joint carries the locator: the preset's first attach landmark that the
// destination resolves and that shares the frame (a twist joint when the destination has one), else
// the same landmark, else the frame's own origin (a twist landmark the destination lacks).
std::string destinationLandmark(const MusclePart& part, const std::string& which, const std::string& landmark,
                                const LandmarkSet& dst, const PresetPart* spec) {
  const std::string side = part.side == "Right" ? "r" : "l";
  const SegmentFrame frame = frameOf(landmark);
  if (const std::vector<std::string>* candidates = attachCandidates(spec, which)) {
    for (const std::string& candidate : *candidates) {
      const std::string name = sidedName(candidate, side);
      if (dst.has(name) && frameOf(name) == frame) return name;
    }
  }
  if (dst.has(landmark)) return landmark;
  return frame.origin;
}

// The preset placed on a character, or nothing when the preset does not place on it (a landmark one of
// its parts needs is missing): `rigbake place`'s own result, which a part the preset knows is carried
// relative to.
std::optional<MuscleSet> presetPlacement(const Character& character, const LandmarkSet& landmarks,
                                         const MusclePreset& preset) {
  if (preset.parts.empty()) return std::nullopt;
  try {
    return placeMuscles(character, landmarks, preset, Sides::kBoth);
  } catch (const Error&) {
    return std::nullopt;
  }
}

const MusclePart* partNamed(const std::optional<MuscleSet>& set, const MusclePart& part) {
  if (!set) return nullptr;
  for (const MusclePart& candidate : set->parts) {
    if (candidate.kind == part.kind && candidate.fullName() == part.fullName()) return &candidate;
  }
  return nullptr;
}

bool isLimbLandmark(const std::string& base) {
  static const char* const kLimbs[] = {"upper_arm", "upper_arm_twist", "forearm", "forearm_twist", "hand",
                                       "upper_leg", "lower_leg",       "foot",    "toe"};
  return std::find(std::begin(kLimbs), std::end(kLimbs), base) != std::end(kLimbs);
}

// The axes an edit of a preset point turns with. On a limb, its segment's: an edit along the forearm
// stays along it whether the arms rest in a T or an A pose. On the trunk and the shoulder girdle, the
// body's own (lateral, up, forward): where a skeleton puts its spine joints is its author's choice, not
// anatomy, and a trunk segment can point anywhere (the Quaternius Cowboy's derived T12 lies 0.05 m from
// its L5, beside it rather than above it, so its L5 -> T12 segment runs sideways).
Eigen::Matrix3d editAxes(const SegmentFrame& frame, const LandmarkSet& landmarks) {
  if (isLimbLandmark(baseNameOf(frame.from))) return segmentBasis(frame, landmarks).axes;
  Eigen::Matrix3d axes;
  axes << landmarks.body.lateral, landmarks.body.up, landmarks.body.forward;
  return axes;
}

// A displacement carried between two characters: turned with the axes, scaled by body height (an edit of
// a centimetre on a 1.8 m body is half a centimetre on a 0.9 m one, whatever the bone lengths).
Eigen::Vector3d carryEdit(const Eigen::Vector3d& edit, const SegmentFrame& frame, const LandmarkSet& from,
                          const LandmarkSet& to) {
  return editAxes(frame, to) * (editAxes(frame, from).transpose() * edit) * (to.body.height / from.body.height);
}

// A part the preset places on both characters: each locator is the preset's point on `dst` plus the
// source locator's edit of the preset's point on `src` (turned with editAxes(), scaled by body height),
// on the joint the preset's placement rides there.
void carryEdited(const MusclePart& part, const MusclePart& src_rule, const MusclePart& dst_rule,
                 const std::array<Anchor, 3>& anchors, const LandmarkSet& src_landmarks, const LandmarkSet& dst_landmarks,
                 const Skeleton& dst_skeleton, MusclePart* moved) {
  const MuscleLocator* rule_from[3] = {&src_rule.origin, &src_rule.insertion, &src_rule.driver};
  const MuscleLocator* rule_to[3] = {&dst_rule.origin, &dst_rule.insertion, &dst_rule.driver};
  const MuscleLocator* edited[3] = {&part.origin, &part.insertion, &part.driver};
  MuscleLocator* targets[3] = {&moved->origin, &moved->insertion, &moved->driver};
  for (int k = 0; k < 3; ++k) {
    const SegmentFrame& frame = anchors[k].frame;
    const Eigen::Vector3d edit = edited[k]->world - rule_from[k]->world;
    const Eigen::Vector3d world = rule_to[k]->world + carryEdit(edit, frame, src_landmarks, dst_landmarks);
    // The joint `place` attaches it to there (on a skeleton with a twist joint on one side only, the
    // placement mirrors the left side's choice).
    *targets[k] = locatorOn(dst_skeleton, rule_to[k]->joint, world);
  }
}

// A part the preset does not place: origin and insertion carried whole through their landmark frames,
// the driver between the muscle's two ends. Returns whether the driver was carried between the ends.
bool carryThroughFrames(const MusclePart& part, const std::array<Anchor, 3>& anchors, const LandmarkSet& src_landmarks,
                        const LandmarkSet& dst_landmarks, const Skeleton& dst_skeleton, MusclePart* moved) {
  MuscleLocator* targets[2] = {&moved->origin, &moved->insertion};
  const MuscleLocator* from[2] = {&part.origin, &part.insertion};
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d coords = segmentBasis(anchors[k].frame, src_landmarks).toLocal(from[k]->world);
    const Eigen::Vector3d world = segmentBasis(anchors[k].frame, dst_landmarks).toWorld(coords);
    *targets[k] = locatorOn(dst_skeleton, dst_landmarks.get(anchors[k].dst_landmark).joint, world);
  }

  // The driver is the resting belly of its muscle (the talk's muscleDriver), so it keeps its place
  // between the muscle's two ends rather than on one bone: a midpoint stays the midpoint however
  // differently the two attach segments scale.
  const double src_height = src_landmarks.body.height;
  const double dst_height = dst_landmarks.body.height;
  const Eigen::Vector3d src_span = part.insertion.world - part.origin.world;
  const Eigen::Vector3d dst_span = moved->insertion.world - moved->origin.world;
  const bool between_ends =
      src_span.norm() > kDegenerateFraction * src_height && dst_span.norm() > kDegenerateFraction * dst_height;
  Eigen::Vector3d driver_world;
  if (between_ends) {
    const Eigen::Vector3d coords =
        basisAlong(part.origin.world, src_span, src_height, src_landmarks.body).toLocal(part.driver.world);
    driver_world = basisAlong(moved->origin.world, dst_span, dst_height, dst_landmarks.body).toWorld(coords);
  } else {
    const Eigen::Vector3d coords = segmentBasis(anchors[2].frame, src_landmarks).toLocal(part.driver.world);
    driver_world = segmentBasis(anchors[2].frame, dst_landmarks).toWorld(coords);
  }
  moved->driver = locatorOn(dst_skeleton, dst_landmarks.get(anchors[2].dst_landmark).joint, driver_world);
  return between_ends;
}

}  // namespace

MuscleSet retargetMuscles(const MuscleSet& source, const Character& src, const LandmarkSet& src_landmarks,
                          const Character& dst, const LandmarkSet& dst_landmarks, const MusclePreset& preset,
                          const std::string& source_file, std::vector<CarriedLocator>* carried) {
  const Skeleton& src_skeleton = src.skeleton;
  const Skeleton& dst_skeleton = dst.skeleton;
  const char* kWhich[3] = {"origin", "insertion", "driver"};

  // 1. Anchor every locator and check every frame on both characters before moving anything.
  std::vector<std::array<Anchor, 3>> anchors(source.parts.size());
  for (size_t i = 0; i < source.parts.size(); ++i) {
    const MusclePart& part = source.parts[i];
    const PresetPart* spec = findPresetPart(preset, part);
    const MuscleLocator* locators[3] = {&part.origin, &part.insertion, &part.driver};
    for (int k = 0; k < 3; ++k) {
      assert(locators[k]->joint >= 0 && locators[k]->joint < src_skeleton.size());
      const std::string where = source_file + "#/rigbake/muscles/" + part.fullName() + "/" + kWhich[k];
      Anchor& anchor = anchors[i][k];
      anchor.landmark = sourceLandmark(part, kWhich[k], *locators[k], src_skeleton, src_landmarks, spec, where);
      const PointFormula* formula = presetFormula(spec, kWhich[k]);
      std::optional<SegmentFrame> from_formula =
          formula ? formulaFrame(*formula, part.side == "Right" ? "r" : "l") : std::nullopt;
      anchor.frame = from_formula ? *from_formula : frameOf(anchor.landmark);
      anchor.dst_landmark = destinationLandmark(part, kWhich[k], anchor.landmark, dst_landmarks, spec);
      for (const auto& [landmarks, character] : {std::pair<const LandmarkSet*, const Character*>{&src_landmarks, &src},
                                                 {&dst_landmarks, &dst}}) {
        if (!segmentUsable(anchor.frame, *landmarks))
          fail(errc::RETARGET_SEGMENT_DEGENERATE, character->source,
               "landmarks '" + anchor.frame.from + "' and '" + anchor.frame.to + "' coincide, so the segment that " +
                   part.fullName() + "'s " + kWhich[k] + " rides on has no direction; fix the skeleton or pass a "
                   "naming map that picks other joints");
      }
    }
  }

  // 2. Carry the locators. A part the preset places on both characters is carried as the preset's own
  // point on `dst` plus the source's edit of it: where the preset puts it on `src` is the anatomy the
  // edit was made against, and placing the preset on `dst` finds that anatomy on the new body from its
  // landmarks, whatever its skeleton's hierarchy, root, facing, scale or names. Only the edit travels
  // through a landmark frame. Other parts are carried whole through their frame.
  const std::optional<MuscleSet> src_placed = presetPlacement(src, src_landmarks, preset);
  const std::optional<MuscleSet> dst_placed = presetPlacement(dst, dst_landmarks, preset);
  const double src_height = src_landmarks.body.height;
  const double dst_height = dst_landmarks.body.height;
  const double body_scale = dst_height / src_height;
  MuscleSet out;
  out.character = fileNameOf(dst.source);
  out.body_height = dst_height;
  out.anatomical_parents = dst_landmarks.anatomical_parents;
  out.parts.reserve(source.parts.size());
  if (carried) carried->clear();
  for (size_t i = 0; i < source.parts.size(); ++i) {
    const MusclePart& part = source.parts[i];
    MusclePart moved = part;
    const MusclePart* src_rule = partNamed(src_placed, part);
    const MusclePart* dst_rule = src_rule ? partNamed(dst_placed, part) : nullptr;
    bool between_ends = false;
    if (dst_rule)
      carryEdited(part, *src_rule, *dst_rule, anchors[i], src_landmarks, dst_landmarks, dst_skeleton, &moved);
    else
      between_ends = carryThroughFrames(part, anchors[i], src_landmarks, dst_landmarks, dst_skeleton, &moved);

    // Bulge and falloff radius are lengths on the body: they scale with it.
    moved.bulge = part.bulge * body_scale;
    moved.weight_radius = part.weight_radius * body_scale;
    // So are the response's offsets (fitted or edited curves travel with the muscle); scales are ratios.
    for (std::vector<ResponseKey>* curve : {&moved.response.ratio, &moved.response.twist}) {
      for (ResponseKey& key : *curve) {
        key.up *= body_scale;
        key.side *= body_scale;
      }
    }
    // A muscle's carrier is chosen again from the new character's weights; a corrective's is the joint
    // of the same landmark there. As a placement does, a corrective whose carrier the new character
    // does not resolve, or whose carrier joint a corrective of its group and side already has there
    // (two landmarks on one joint), is left out.
    moved.carrier = -1;
    if (part.kind == PartKind::kCorrective) {
      if (!dst_landmarks.has(part.carrier_landmark)) continue;
      moved.carrier = dst_landmarks.get(part.carrier_landmark).joint;
      const bool taken = std::any_of(out.parts.begin(), out.parts.end(), [&](const MusclePart& earlier) {
        return earlier.kind == PartKind::kCorrective && earlier.group == moved.group && earlier.side == moved.side &&
               earlier.carrier == moved.carrier;
      });
      if (taken) continue;
    }

    if (carried) {
      const MuscleLocator* before[3] = {&part.origin, &part.insertion, &part.driver};
      const MuscleLocator* after[3] = {&moved.origin, &moved.insertion, &moved.driver};
      for (int k = 0; k < 3; ++k) {
        CarriedLocator entry;
        entry.part = part.fullName();
        entry.locator = kWhich[k];
        entry.frame = k == 2 && between_ends ? "muscle" : anchors[i][k].frame.describe();
        entry.src_joint = src_skeleton.names[before[k]->joint];
        entry.dst_joint = dst_skeleton.names[after[k]->joint];
        carried->push_back(std::move(entry));
      }
    }
    out.parts.push_back(std::move(moved));
  }
  return out;
}

}  // namespace rigbake
