// The skinned body as one surface. A character built from several meshes (a head, a torso, legs, each
// its own glTF mesh) has vertices of different meshes at the same place along every border; welded
// mesh by mesh, each side of a border got its own muscle weights and the border opened when a muscle
// moved (5.4 mm on the Quaternius Soldier's 11 meshes). Welded across every skinned mesh part, a
// border is one more seam of one surface: its vertices share one welded vertex, so one muscle share
// and, where the input gave them the same skin, the same muscle weights. Issue 29, docs/muscle-weights.md.
#pragma once

#include <vector>

#include "anatomy/character.h"
#include "pipeline/surface_graph.h"

namespace rigbake {

struct BodySurface {
  SurfaceGraph graph;             // skin() welded across the parts
  std::vector<int> mesh_part;     // per skinned part: its index into Character::meshes
  std::vector<int> first_vertex;  // per skinned part: its first vertex in `skin`; one more entry, the total

  // Part p's vertices' welded vertices (weld_of_vertex only, for addMuscleInfluences()).
  SurfaceGraph partWelds(size_t p) const;
  // Every skinned part with positions, in Character::meshes order, as one part: its vertices one part
  // after another, its triangles renumbered, its influences padded with zero-weight slots to the widest
  // part's slot count. With one skinned part, that part itself (not copied: a million-vertex body).
  const MeshPart& skin(const Character& character) const {
    return mesh_part.size() == 1 ? character.meshes[mesh_part[0]] : joined;
  }

  MeshPart joined;  // the parts joined, when there are several
};

// Vertices closer than `weld_tolerance` (as buildSurfaceGraph()) are one, whichever part they are in.
BodySurface buildBodySurface(const Character& character, double weld_tolerance);

}  // namespace rigbake
