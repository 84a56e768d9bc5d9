// A vertex of the character's skin named so that a user can find it in the file and in a DCC: which
// mesh part and which of its vertices, where that part is in the glTF (mesh and primitive), and the
// vertex's bind position (vertex numbers change on import; positions do not). The skin figures that
// point at one place use it: where a region loses its volume (pipeline/region_loss_place.h) and where
// the skin is lumpiest (pipeline/surface_figures.h).
#pragma once

#include <Eigen/Core>
#include <string>

#include "anatomy/character.h"

namespace rigbake {

struct SkinPlace {
  bool found = false;
  int mesh_part = -1;  // index into Character::meshes
  int vertex = -1;     // the place's first vertex in that part
  Eigen::Vector3d bind = Eigen::Vector3d::Zero();  // scene units
  std::string mesh;    // the part's mesh name, glTF mesh and primitive
  int gltf_mesh = -1, gltf_primitive = -1;
};

// Where the rig's skin stands out of its neighbours' plane most beyond plain skinning's at a clip's
// roughest sample (the sample where the rig's roughness rise peaks): the moving vertex whose rise over
// the bind pose under the rig exceeds its rise under plain skinning by most (pipeline/surface_figures.h).
struct LumpPlace {
  SkinPlace at;             // at.found = false when no moving vertex rises more under the rig
  double rig_rise = 0.0;    // scene units, |L . n| posed minus bind, under the rig
  double input_rise = 0.0;  // the same under plain skinning
  double time = 0.0;        // the sample, seconds into the clip
};

// The place at `vertex` of mesh part `mesh_part`, found, with its bind position and file names.
SkinPlace skinPlace(const Character& character, int mesh_part, int vertex);

// "vertex 449 of mesh 'Cylinder.005' (glTF mesh 0, primitive 0; bind position -0.313 2.695 0.032)";
// empty when not found.
std::string skinPlaceText(const SkinPlace& place);

// "lumpiest at vertex ... at 0.50 s: 4.243 mm further out of its neighbours' plane under the rig than
// under plain skinning (rise over the bind pose 7.671 and 3.428 mm)" for bake's roughness line and
// validate's findings; empty when not found.
std::string lumpPlaceText(const LumpPlace& lump);

}  // namespace rigbake
