#include "pipeline/region_loss_place.h"

#include "pipeline/check_support.h"
#include "pipeline/skinning.h"

namespace rigbake {

RegionLossPlace regionLossPlace(const Character& character, const std::vector<RegionPiece>& pieces,
                                const std::vector<Eigen::Affine3d>& frame, double bind_volume, double time,
                                RegionLossScratch* scratch) {
  RegionLossPlace place;
  place.time = time;
  if (!(bind_volume > 0.0)) return place;
  const double to_points = 100.0 / bind_volume;
  double least = 0.0;  // the most negative share so far; a place must take something to be named
  int least_part = -1, least_vertex = -1;
  RegionLossScratch& s = *scratch;
  for (const RegionPiece& piece : pieces) {
    if (piece.patch->triangles.empty()) continue;
    const VolumeSurface& surface = *piece.surface;
    const std::vector<Eigen::Vector3d>& bind = character.meshes[static_cast<size_t>(piece.mesh_part)].positions;
    const size_t welded_count = static_cast<size_t>(surface.weldedCount());
    const std::vector<int> vertices = patchVertices(*piece.patch, welded_count);
    s.needed.clear();
    for (int w : vertices) s.needed.push_back(surface.vertex_of_weld[static_cast<size_t>(w)]);
    skinLinearBlend(bind, *piece.input, frame, s.needed, &s.plain_listed);
    skinLinearBlend(bind, *piece.rig, frame, s.needed, &s.rig_listed);
    // Welded-indexed, as the patch is. Only the patch's own vertices are written, and only they are read
    // (the volumes and the gradient touch no other), so what earlier calls left elsewhere does not matter.
    for (std::vector<Eigen::Vector3d>* buffer : {&s.plain, &s.rig, &s.middle, &s.gradient})
      if (buffer->size() < welded_count) buffer->resize(welded_count);
    for (size_t i = 0; i < vertices.size(); ++i) {
      const size_t w = static_cast<size_t>(vertices[i]);
      s.plain[w] = s.plain_listed[i];
      s.rig[w] = s.rig_listed[i];
      s.middle[w] = 0.5 * (s.plain_listed[i] + s.rig_listed[i]);
      s.gradient[w].setZero();
    }
    place.difference_points += to_points * (enclosedVolume(*piece.patch, s.rig) - enclosedVolume(*piece.patch, s.plain));
    addVolumeGradient(*piece.patch, s.middle, 1.0, &s.gradient);
    for (int w : vertices) {
      const size_t at = static_cast<size_t>(w);
      const double share = to_points * s.gradient[at].dot(s.rig[at] - s.plain[at]);
      place.first_order_points += share;
      if (share < least) {
        least = share;
        least_part = piece.mesh_part;
        least_vertex = surface.vertex_of_weld[at];
      }
    }
  }
  if (least_part >= 0) place.at = skinPlace(character, least_part, least_vertex);
  place.points = -least;
  return place;
}

std::string regionLossPlaceText(const RegionLossPlace& place) {
  if (!place.at.found) return "";
  return fixedDecimals(place.points, 2) + " points of it at " + skinPlaceText(place.at);
}

}  // namespace rigbake
