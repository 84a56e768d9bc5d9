// Distance from a point to a character's body surface (skinned parts and rigid parts riding on
// joints), used to check that muscle locators sit in the body and not in the air.
#pragma once

#include <Eigen/Core>

#include "anatomy/character.h"

namespace rigbake {

// Closest point on a triangle (Ericson, "Real-Time Collision Detection", 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

// Unsigned distance to the nearest body triangle at bind pose; infinity when there is no body mesh.
double distanceToBodySurface(const Character& character, const Eigen::Vector3d& point);

}  // namespace rigbake
