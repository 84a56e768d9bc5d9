// The mannequin's skinned body: closed tubes around the joint table of sample/canonical_skeleton.h,
// skinned to its bones. Internal to sample/ (sample/sample_character.cpp calls it).
#pragma once

#include "sample/canonical_skeleton.h"
#include "sample/sample_character.h"

namespace rigbake::sample_internal {

// The plain variant's mesh, within a few percent of target_vertices: positions and normals in the
// bind pose, world space, at most 4 influences per vertex (SampleMesh says how they are stored).
SampleMesh buildSampleMesh(const CanonicalSkeleton& skeleton, int target_vertices);

}  // namespace rigbake::sample_internal
