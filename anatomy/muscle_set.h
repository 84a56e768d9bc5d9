// Placed muscles: what `rigbake place` produces, the muscle JSON stores, and the bake consumes.
// Following the God of War Ragnarök talk ("Muscle Joint Group", createFromAttachObjs): each muscle part
// has an origin and an insertion locator riding on attach joints, compression/stretch factors that
// clamp its length ratio, and a bulge vector.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace rigbake {

struct Skeleton;

struct MuscleLocator {
  Eigen::Vector3d world = Eigen::Vector3d::Zero();  // bind pose, scene world space, metres
  int joint = -1;                                   // skeleton joint it rides on
  Eigen::Vector3d local = Eigen::Vector3d::Zero();  // the same point in that joint's bind frame
};

// One key of a muscle's set-driven response (the talk's "set driven key to simulate muscle bulges and
// correct deformation"): at driver value `at` the skinned joint is moved `up` and `side` metres along
// the muscle's rest up and side axes and scaled across its fibre by `scale`. Linear between keys, the
// nearest key outside them. docs/muscle-model.md.
struct ResponseKey {
  double at = 0.0;
  double up = 0.0;
  double side = 0.0;
  double scale = 1.0;
};

struct MuscleResponse {
  std::vector<ResponseKey> ratio;  // driver: length ratio L / L_rest, clamped to [compression, stretch]
  std::vector<ResponseKey> twist;  // driver: the insertion joint's twist about the fibre, radians
  bool fitted = false;             // the keys came from `bake --response fit`
};

// What a part is. A muscle is the talk's muscle joint group: it bulges when it shortens and may thin
// when it lengthens, taking skin weight from the joint its field covers most. A corrective is the talk's
// "SDK joint" ("Tyr's elbow is corrected by SDK joints"): the same driver (its span's length ratio) and
// the same skinned joint, but a set-driven offset of either sign, taking skin weight from one named
// carrier joint and only where the skin blends the joints on either side of its span (the web plain
// skinning stretches across a raised arm's armpit). docs/muscle-model.md, "Correctives".
enum class PartKind { kMuscle, kCorrective };
const char* partKindName(PartKind kind);                   // "muscle", "corrective"
bool parsePartKind(const std::string& name, PartKind* kind);  // false for any other name

struct MusclePart {
  std::string group;  // export group: Arms, Deltoid, LatissimusDorsi, PectoralisMajor, TeresMajor, Trapezius
  std::string name;   // part name without side: TrapeziusA, Bicep, ...
  std::string side;   // "Left" or "Right"
  MuscleLocator origin;
  MuscleLocator insertion;
  // Resting midpoint of the muscle belly (the talk's muscleDriver), riding on the origin joint.
  MuscleLocator driver;
  double compression = 0.5;  // smallest length ratio L / L_rest the muscle reaches
  double stretch = 1.5;      // largest length ratio
  // Bulge across the fibre as the muscle shortens, in the muscle's own frame: x along the muscle's
  // up axis, y along its side axis (the talk's two-component bulgeVector). Units: body-measure metres.
  Eigen::Vector2d bulge = Eigen::Vector2d::Zero();
  // Skin-weight falloff radius around the origin-insertion segment, metres; 0 = derive from body size.
  double weight_radius = 0.0;
  // How the skinned joint moves with the muscle's drivers. placeMuscles() and readMuscleJson() fill it
  // from `bulge` and the factors when the file has no curves (defaultMuscleResponse()).
  MuscleResponse response;
  // The joint the skinned joint rides and takes skin weight from; -1 until the bake chooses it
  // (pipeline/muscle_weights.h chooseCarrierJoints()). A corrective's is fixed by its carrier landmark.
  int carrier = -1;
  PartKind kind = PartKind::kMuscle;
  // Correctives only: the landmark whose joint carries it, with its side suffix (e.g. "clavicle_l"), so
  // that a retarget or a muscle file read on another character finds the same joint again.
  std::string carrier_landmark;

  std::string fullName() const { return side + name; }  // e.g. LeftTrapeziusA
};

// The talk's response, as two linear keys on the length ratio: at full compression the bulge vector and
// the volume-preserving across-fibre scale 1 / sqrt(compression), at rest and when stretched nothing
// (a stretched muscle does not pull the skin in). No twist response.
MuscleResponse defaultMuscleResponse(double compression, double stretch, const Eigen::Vector2d& bulge);

// The response a part starts with: a muscle's is defaultMuscleResponse(); a corrective's is none at all
// (flat keys at full compression, rest and full stretch) until a fit or an artist gives it one.
MuscleResponse defaultResponse(const MusclePart& part);

// "" when the curves are usable: keys ascending, finite, scale > 0, and no response at rest (ratio 1,
// twist 0), so that the bind pose is unchanged; otherwise what is wrong.
std::string muscleResponseProblem(const MuscleResponse& response);

struct MuscleSet {
  std::string character;  // source file name (no directories)
  double body_height = 0.0;
  std::vector<MusclePart> parts;
  // The character's LandmarkSet::anatomical_parents, the hierarchy the muscles span; empty: the skeleton's.
  std::vector<int> anatomical_parents;
};

// The hierarchy `muscles` span on `skeleton`: their anatomical parents when they have one per joint,
// else the skeleton's own.
const std::vector<int>& spannedHierarchy(const MuscleSet& muscles, const Skeleton& skeleton);

}  // namespace rigbake
