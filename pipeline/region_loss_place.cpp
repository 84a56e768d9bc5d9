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
  bool every_full = true;
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
    every_full = every_full && piece.full;
    if (piece.full) skinLinearBlend(bind, *piece.full, frame, s.needed, &s.full_listed);
    // Welded-indexed, as the patch is. Only the patch's own vertices are written, and only they are read
    // (the volumes and the gradient touch no other), so what earlier calls left elsewhere does not matter.
    for (std::vector<Eigen::Vector3d>* buffer : {&s.plain, &s.rig, &s.middle, &s.gradient, &s.full})
      if (buffer->size() < welded_count) buffer->resize(welded_count);
    for (size_t i = 0; i < vertices.size(); ++i) {
      const size_t w = static_cast<size_t>(vertices[i]);
      s.plain[w] = s.plain_listed[i];
      s.rig[w] = s.rig_listed[i];
      s.middle[w] = 0.5 * (s.plain_listed[i] + s.rig_listed[i]);
      s.gradient[w].setZero();
      if (piece.full) s.full[w] = s.full_listed[i];
    }
    const double rig_volume = enclosedVolume(*piece.patch, s.rig);
    place.difference_points += to_points * (rig_volume - enclosedVolume(*piece.patch, s.plain));
    if (piece.full) place.cut_points += to_points * (rig_volume - enclosedVolume(*piece.patch, s.full));
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
  place.cut_measured = every_full;
  if (!every_full) place.cut_points = 0.0;
  return place;
}

std::string regionLossPlaceText(const RegionLossPlace& place) {
  if (!place.at.found) return "";
  return fixedDecimals(place.points, 2) + " points of it at " + skinPlaceText(place.at);
}

}  // namespace rigbake
