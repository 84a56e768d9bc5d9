#include "pipeline/body_surface.h"

#include <algorithm>

namespace rigbake {

SurfaceGraph BodySurface::partWelds(size_t p) const {
  SurfaceGraph welds;
  welds.weld_of_vertex.assign(graph.weld_of_vertex.begin() + first_vertex[p], graph.weld_of_vertex.begin() + first_vertex[p + 1]);
  return welds;
}

BodySurface buildBodySurface(const Character& character, double weld_tolerance) {
  BodySurface body;
  body.first_vertex.push_back(0);
  int slots = 0;
  for (size_t p = 0; p < character.meshes.size(); ++p) {
    const MeshPart& mesh = character.meshes[p];
    if (!mesh.skinned || mesh.positions.empty()) continue;
    body.mesh_part.push_back(static_cast<int>(p));
    body.first_vertex.push_back(body.first_vertex.back() + static_cast<int>(mesh.positions.size()));
    slots = std::max(slots, mesh.influences_per_vertex);
  }
  if (body.mesh_part.size() > 1) {
    MeshPart& skin = body.joined;
    skin.name = "body";
    skin.skinned = true;
    skin.influences_per_vertex = slots;
    skin.positions.reserve(body.first_vertex.back());
    skin.joints.assign(static_cast<size_t>(body.first_vertex.back()) * slots, 0);
    skin.weights.assign(skin.joints.size(), 0.0);
    for (size_t p = 0; p < body.mesh_part.size(); ++p) {
      const MeshPart& mesh = character.meshes[body.mesh_part[p]];
      const int offset = body.first_vertex[p];
      skin.positions.insert(skin.positions.end(), mesh.positions.begin(), mesh.positions.end());
      for (const auto& triangle : mesh.triangles) skin.triangles.push_back({triangle[0] + offset, triangle[1] + offset, triangle[2] + offset});
      const int own = mesh.influences_per_vertex;
      for (size_t v = 0; v < mesh.positions.size(); ++v) {
        for (int k = 0; k < own; ++k) {
          skin.joints[(offset + v) * slots + k] = mesh.joints[v * own + k];
          skin.weights[(offset + v) * slots + k] = mesh.weights[v * own + k];
        }
      }
    }
  }
  body.graph = buildSurfaceGraph(body.skin(character), weld_tolerance);
  return body;
}

}  // namespace rigbake
