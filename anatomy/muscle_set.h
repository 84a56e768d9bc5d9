// Placed muscles: what `rigbake place` produces, the muscle JSON stores, and the bake consumes.
// Following the God of War Ragnarök talk ("Muscle Joint Group", createFromAttachObjs): each muscle part
// has an origin and an insertion locator riding on attach joints, compression/stretch factors that
// clamp its length ratio, and a bulge vector.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace rigbake {

struct MuscleLocator {
  Eigen::Vector3d world = Eigen::Vector3d::Zero();  // bind pose, scene world space, metres
  int joint = -1;                                   // skeleton joint it rides on
  Eigen::Vector3d local = Eigen::Vector3d::Zero();  // the same point in that joint's bind frame
};

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

  std::string fullName() const { return side + name; }  // e.g. LeftTrapeziusA
};

struct MuscleSet {
  std::string character;  // source file name (no directories)
  double body_height = 0.0;
  std::vector<MusclePart> parts;
};

}  // namespace rigbake
