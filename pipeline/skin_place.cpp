#include "pipeline/skin_place.h"

#include "pipeline/check_support.h"

namespace rigbake {

SkinPlace skinPlace(const Character& character, int mesh_part, int vertex) {
  const MeshPart& mesh = character.meshes[static_cast<size_t>(mesh_part)];
  SkinPlace place;
  place.found = true;
  place.mesh_part = mesh_part;
  place.vertex = vertex;
  place.bind = mesh.positions[static_cast<size_t>(vertex)];
  place.mesh = mesh.name;
  place.gltf_mesh = mesh.gltf_mesh;
  place.gltf_primitive = mesh.gltf_primitive;
  return place;
}

std::string skinPlaceText(const SkinPlace& place) {
  if (!place.found) return "";
  return "vertex " + std::to_string(place.vertex) + " of mesh '" + place.mesh + "' (glTF mesh " + std::to_string(place.gltf_mesh) +
         ", primitive " + std::to_string(place.gltf_primitive) + "; bind position " + fixedDecimals(place.bind.x(), 3) + " " +
         fixedDecimals(place.bind.y(), 3) + " " + fixedDecimals(place.bind.z(), 3) + ")";
}

std::string lumpPlaceText(const LumpPlace& lump) {
  if (!lump.at.found) return "";
  return "lumpiest at " + skinPlaceText(lump.at) + " at " + fixedDecimals(lump.time, 2) + " s: " +
         fixedDecimals(1000.0 * (lump.rig_rise - lump.input_rise), 3) +
         " mm further out of its neighbours' plane under the rig than under plain skinning (rise over the bind pose " +
         fixedDecimals(1000.0 * lump.rig_rise, 3) + " and " + fixedDecimals(1000.0 * lump.input_rise, 3) + " mm)";
}

}  // namespace rigbake
