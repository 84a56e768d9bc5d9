// The muscles' skin weights as a module (pipeline/muscle_weights.h) on the mannequin with the GoW
// preset: the share field's layout and bounds, the carriers among the spanned joints, weights that keep
// every vertex's sum, and the property the design rests on: a muscle joint that moves as its carrier
// moves the skin exactly as the input skinning does.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "anatomy_fixture.h"
#include "pipeline/body_surface.h"
#include "pipeline/influences.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/muscle_weights.h"
#include "pipeline/pose.h"
#include "pipeline/skin_volume.h"
#include "pipeline/skinning.h"

using namespace rigbake;

namespace {

struct WeightedMannequin {
  test::Resolved r;
  MuscleSet placed;   // as placed, before the carriers are chosen
  MuscleSet muscles;
  BodySurface body;
  MuscleShares shares;
  std::vector<double> radii;
};

const WeightedMannequin& weightedMannequin() {
  static const WeightedMannequin weighted = [] {
    WeightedMannequin w;
    w.r = test::resolveShipped(test::sampleGlbPath());
    w.placed = placeMuscles(w.r.character, w.r.landmarks, test::gowPreset(), Sides::kBoth);
    w.muscles = w.placed;
    w.radii = muscleWeightRadii(w.r.character, w.muscles, w.muscles.body_height);
    w.body = buildBodySurface(w.r.character, bodyWeldTolerance(w.muscles.body_height));
    w.shares = muscleShares(w.r.character.skeleton, w.body.skin(w.r.character), w.body.graph, w.muscles, w.radii);
    chooseCarrierJoints(w.r.character, w.body, w.shares, &w.muscles);
    return w;
  }();
  return weighted;
}

}  // namespace

TEST_CASE("muscle weights: shares per welded vertex, muscles ascending, above 0 and at most the peak share, the same at any thread count",
          "[muscle-weights]") {
  const WeightedMannequin& w = weightedMannequin();
  const MuscleShares& shares = w.shares;
  REQUIRE(static_cast<int>(shares.first.size()) == w.body.graph.weldedCount() + 1);
  REQUIRE(shares.first.back() == shares.muscle.size());
  REQUIRE(shares.share.size() == shares.muscle.size());
  std::vector<char> reaches(w.muscles.parts.size(), 0);
  for (size_t v = 0; v + 1 < shares.first.size(); ++v) {
    REQUIRE(shares.first[v] <= shares.first[v + 1]);
    for (std::uint32_t k = shares.first[v]; k < shares.first[v + 1]; ++k) {
      REQUIRE(shares.muscle[k] >= 0);
      REQUIRE(shares.muscle[k] < static_cast<int>(w.muscles.parts.size()));
      if (k > shares.first[v]) REQUIRE(shares.muscle[k - 1] < shares.muscle[k]);
      REQUIRE(shares.share[k] > 0.0);
      REQUIRE(shares.share[k] <= MuscleWeightOptions{}.peak_share + 1e-12);
      reaches[static_cast<size_t>(shares.muscle[k])] = 1;
    }
  }
  // Every muscle of the preset reaches some skin of the mannequin.
  CHECK(std::count(reaches.begin(), reaches.end(), 1) == static_cast<long>(w.muscles.parts.size()));
  const MuscleShares threaded = muscleShares(w.r.character.skeleton, w.body.skin(w.r.character), w.body.graph, w.muscles, w.radii, {}, 3);
  CHECK(threaded.first == shares.first);
  CHECK(threaded.muscle == shares.muscle);
  CHECK(threaded.share == shares.share);
}

TEST_CASE("muscle weights: a muscle's chosen carrier is a joint it spans, and a corrective keeps its landmark's joint", "[muscle-weights]") {
  const WeightedMannequin& w = weightedMannequin();
  int chosen = 0, kept = 0;
  for (size_t m = 0; m < w.muscles.parts.size(); ++m) {
    const MusclePart& part = w.muscles.parts[m];
    INFO(part.fullName());
    REQUIRE(part.carrier >= 0);
    if (w.placed.parts[m].carrier >= 0) {
      // A corrective rides its carrier landmark's joint (the armpit's ride the chest, the scapula, the
      // upper arm...), placed before the weights and kept by them.
      CHECK(part.kind == PartKind::kCorrective);
      CHECK(part.carrier == w.placed.parts[m].carrier);
      CHECK(part.carrier == w.r.landmarks.get(part.carrier_landmark).joint);
      ++kept;
      continue;
    }
    const std::vector<int> spanned = spannedJoints(spannedHierarchy(w.placed, w.r.character.skeleton), part);
    CHECK(std::find(spanned.begin(), spanned.end(), part.carrier) != spanned.end());
    ++chosen;
  }
  CHECK(chosen > 10);
  CHECK(kept > 0);
}

TEST_CASE("muscle weights: the muscles' weights keep every vertex's sum, and a muscle joint riding its carrier skins as the input",
          "[muscle-weights]") {
  const WeightedMannequin& w = weightedMannequin();
  const Character& character = w.r.character;
  const Skeleton& skeleton = character.skeleton;
  const int muscle_count = static_cast<int>(w.muscles.parts.size());
  std::vector<int> muscle_joints(muscle_count);
  for (int m = 0; m < muscle_count; ++m) muscle_joints[m] = skeleton.size() + m;
  REQUIRE(!character.clips.empty());
  const Clip& clip = character.clips.front();
  const Pose pose = sampleClip(skeleton, clip, 0.5 * clip.duration);
  // Muscle m's skin matrix is its carrier's: at rest response the skinned joint rides the carrier.
  std::vector<Eigen::Affine3d> frame;
  for (int j = 0; j < skeleton.size(); ++j) frame.push_back(skinMatrix(pose, skeleton, j));
  for (int m = 0; m < muscle_count; ++m) frame.push_back(frame[static_cast<size_t>(w.muscles.parts[m].carrier)]);
  double muscle_weight = 0.0;
  for (size_t s = 0; s < w.body.mesh_part.size(); ++s) {
    const MeshPart& mesh = character.meshes[w.body.mesh_part[s]];
    INFO(mesh.name);
    const InfluenceSet input = normalizedInfluences(influencesFromMesh(mesh));
    const InfluenceSet rig = addMuscleInfluences(input, w.body.partWelds(s), w.shares, w.muscles, muscle_joints);
    REQUIRE(rig.vertexCount() == input.vertexCount());
    for (int v = 0; v < input.vertexCount(); ++v) {
      double before = 0.0, after = 0.0;
      int used = 0;
      for (int k = 0; k < input.slots_per_vertex; ++k) before += input.weights[static_cast<size_t>(v) * input.slots_per_vertex + k];
      for (int k = 0; k < rig.slots_per_vertex; ++k) {
        const size_t at = static_cast<size_t>(v) * rig.slots_per_vertex + k;
        REQUIRE(rig.weights[at] >= 0.0);
        after += rig.weights[at];
        used += rig.weights[at] != 0.0;
        if (rig.joints[at] >= skeleton.size()) muscle_weight += rig.weights[at];
      }
      REQUIRE(std::abs(after - before) <= 1e-12);
      REQUIRE(used <= MuscleWeightOptions{}.max_influences);
    }
    const std::vector<Eigen::Vector3d> plain = skinLinearBlend(mesh.positions, input, frame);
    const std::vector<Eigen::Vector3d> rigged = skinLinearBlend(mesh.positions, rig, frame);
    double worst = 0.0;
    for (size_t v = 0; v < plain.size(); ++v) worst = std::max(worst, (plain[v] - rigged[v]).norm());
    CHECK(worst <= 1e-9 * w.muscles.body_height);
  }
  CHECK(muscle_weight > 1.0);  // the muscles did take weight (summed over vertices)
}

namespace {

// Two unit cubes of 8 corners each: the first held by joint 0 alone, the second by joints 0 and 1.
MeshPart twoCubes(double second_cube_weight_on_0) {
  MeshPart part;
  part.skinned = true;
  part.influences_per_vertex = 2;
  const std::array<std::array<int, 3>, 12> faces = {{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}}};
  for (int cube = 0; cube < 2; ++cube) {
    for (int corner = 0; corner < 8; ++corner) {
      part.positions.emplace_back(2.0 * cube + (corner & 1), (corner >> 1) & 1, (corner >> 2) & 1);
      const double on_0 = cube == 0 ? 1.0 : second_cube_weight_on_0;
      part.joints.insert(part.joints.end(), {0, 1});
      part.weights.insert(part.weights.end(), {on_0, 1.0 - on_0});
    }
    for (const auto& face : faces) part.triangles.push_back({face[0] + 8 * cube, face[1] + 8 * cube, face[2] + 8 * cube});
  }
  return part;
}

}  // namespace

TEST_CASE("muscle weights: a piece the input moves rigidly is found whole, and a piece welded to blended skin is not rigid",
          "[muscle-weights]") {
  // One joint alone on every vertex of the first cube (0.0005 of the weight elsewhere is the 0.001
  // rounding's, still alone); the second cube blends two joints.
  MeshPart part = twoCubes(0.6);
  part.weights[0] = 0.9995;
  part.weights[1] = 0.0005;
  std::vector<char> rigid = rigidPieces(part, buildSurfaceGraph(part, 1e-6));
  REQUIRE(rigid.size() == 16);
  CHECK(std::count(rigid.begin(), rigid.begin() + 8, 1) == 8);
  CHECK(std::count(rigid.begin() + 8, rigid.end(), 1) == 0);
  auto rigidCount = [](const MeshPart& mesh) {
    const std::vector<char> flags = rigidPieces(mesh, buildSurfaceGraph(mesh, 1e-6));
    return std::count(flags.begin(), flags.end(), 1);
  };
  // Both cubes held by joint 0 alone: both rigid. The second by joint 1 alone: each is rigid on its own.
  CHECK(rigidCount(twoCubes(1.0)) == 16);
  CHECK(rigidCount(twoCubes(0.0)) == 16);
  // Moved onto the first cube's face, the second cube welds to it: one piece, blended, not rigid.
  MeshPart touching = twoCubes(0.6);
  for (int corner = 8; corner < 16; ++corner) touching.positions[corner].x() -= 1.0;
  CHECK(rigidCount(touching) == 0);
  // Vertex 0's row with 0.002 on joint 1 is not one joint's alone: the first cube is not rigid.
  MeshPart loose = twoCubes(0.6);
  loose.weights[0] = 0.998;
  loose.weights[1] = 0.002;
  CHECK(rigidCount(loose) == 0);
}
