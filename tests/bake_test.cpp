// The bake on the sample and every shared asset: the written glTF passes the Khronos validator and
// Blender's importer, the bind pose is unchanged, the packed buffers decode exactly, and the figures
// (deformation error, bytes per vertex) are what the docs claim.
#include "pipeline/bake.h"

#include <algorithm>
#include <tiny_gltf.h>

#include "anatomy_fixture.h"
#include "cli_support.h"
#include "external_tools.h"
#include "formats/gltf_bake.h"
#include "formats/gltf_write.h"
#include "pipeline/body_surface.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/muscle_weights.h"
#include "pipeline/pose.h"
#include "pipeline/skin_volume.h"

using namespace rigbake;
namespace ext = rigbake::test::external;

namespace {

struct BakedCharacter {
  std::string path;
  LoadedCharacter loaded;
  LandmarkSet landmarks;
  MuscleSet muscles;
  BakeResult bake;
  std::string bytes;  // the baked GLB
};

BakedCharacter bakeFile(const std::string& path, int influences, GltfWeights gltf_weights = GltfWeights::kMilli,
                        MuscleMotion motion = MuscleMotion::kRuntime) {
  BakedCharacter baked;
  baked.path = path;
  test::Resolved r = test::resolveShipped(path);
  baked.loaded = loadCharacter(path);
  baked.landmarks = r.landmarks;
  baked.muscles = placeMuscles(baked.loaded.character, baked.landmarks, test::gowPreset(), Sides::kBoth);
  BakeOptions options;
  options.influences = influences;
  options.gltf_weights = gltf_weights;
  options.motion = motion;
  baked.bake = bakeCharacter(baked.loaded.character, baked.muscles, options);
  baked.bytes = serializeGltf(bakedModel(*baked.loaded.document, baked.loaded.character, baked.bake), true);
  return baked;
}

std::vector<std::string> characterPaths() {
  std::vector<std::string> paths = test::sampleAndAssetPaths();
  return paths;
}

// Baked at 10 influences once per test process.
const std::vector<BakedCharacter>& bakedAtTen() {
  static const std::vector<BakedCharacter> all = [] {
    std::vector<BakedCharacter> result;
    for (const std::string& path : characterPaths()) result.push_back(bakeFile(path, 10));
    return result;
  }();
  return all;
}

const ext::ValidationSummary& validatedInput(const std::string& path) {
  static std::map<std::string, ext::ValidationSummary> cache;
  auto it = cache.find(path);
  if (it == cache.end()) it = cache.emplace(path, ext::validateWithKhronos(path)).first;
  return it->second;
}

}  // namespace

TEST_CASE("bake: every baked file passes the Khronos glTF validator with 0 errors, at 4, 7 and 10 influences") {
  if (!ext::requireTool(ext::validatorAvailable(), ext::validatorHint())) return;
  test::TempDir dir;
  const std::vector<std::pair<int, GltfWeights>> variants = {
      {4, GltfWeights::kMilli}, {7, GltfWeights::kMilli}, {10, GltfWeights::kMilli}, {10, GltfWeights::kUnorm16}};
  for (const std::string& path : characterPaths()) {
    for (const auto& [influences, gltf_weights] : variants) {
      const bool unorm16 = gltf_weights == GltfWeights::kUnorm16;
      INFO(path << " at " << influences << " influences" << (unorm16 ? ", unorm16 weights" : ""));
      BakedCharacter baked = bakeFile(path, influences, gltf_weights);
      std::string out = dir / ("baked" + std::to_string(influences) + (unorm16 ? "u16" : "") + ".glb");
      std::ofstream(out, std::ios::binary) << baked.bytes;
      ext::ValidationSummary summary = ext::validateWithKhronos(out);
      INFO(summary.raw.substr(0, 2000));
      CHECK(summary.errors == 0);
      // Warnings only where the input already had them (docs/validator-warnings.md).
      const std::vector<std::string>& input_warnings = validatedInput(path).warning_codes;
      for (const std::string& code : summary.warning_codes)
        CHECK(std::find(input_warnings.begin(), input_warnings.end(), code) != input_warnings.end());
    }
  }
}

TEST_CASE("bake: the baked file reloads with the muscle joints in the hierarchy, every skin and every clip", "[shared:bakes-at-ten]") {
  for (const BakedCharacter& baked : bakedAtTen()) {
    INFO(baked.path);
    test::TempDir dir;
    std::ofstream(dir / "b.glb", std::ios::binary) << baked.bytes;
    Character c = loadCharacter(dir / "b.glb").character;
    const Skeleton& before = baked.loaded.character.skeleton;
    // The skinned joints are skin joints now: 28 muscles and the armpit correctives this skeleton resolves.
    CHECK(c.skeleton.size() == before.size() + static_cast<int>(baked.bake.muscles.parts.size()));
    CHECK(baked.bake.muscles.parts.size() >= 28 + 6);
    for (const MusclePart& part : baked.bake.muscles.parts) {
      INFO(part.fullName());
      int skinned = c.skeleton.find(muscleJointName(part, MuscleJointRole::kSkinned));
      REQUIRE(skinned >= 0);
      // The skinned joint rides its carrier: for a muscle one of the joints it spans, for a corrective
      // its carrier landmark's joint.
      REQUIRE(part.carrier >= 0);
      CHECK(c.skeleton.names[c.skeleton.parents[skinned]] == before.names[part.carrier]);
      if (part.kind == PartKind::kCorrective) {
        CHECK(part.carrier == baked.landmarks.get(part.carrier_landmark).joint);
        continue;
      }
      const std::vector<int> spanned = spannedJoints(spannedHierarchy(baked.bake.muscles, before), part);
      CHECK(std::find(spanned.begin(), spanned.end(), part.carrier) != spanned.end());
    }
    for (const MeshPart& mesh : c.meshes) {
      if (!mesh.skinned) continue;
      CHECK(mesh.influences_per_vertex == 12);  // 10 influences in three JOINTS_n/WEIGHTS_n sets
      for (int v = 0; v < static_cast<int>(mesh.positions.size()); ++v) {
        double sum = 0;
        for (int k = 0; k < mesh.influences_per_vertex; ++k) sum += mesh.weights[v * mesh.influences_per_vertex + k];
        REQUIRE(sum == Approx(1.0).margin(1e-12));
      }
    }
    // The default, runtime motion: no muscle channels (the talk's "+0 animation sampled joints"), the
    // rig in the RIGBAKE_muscle_rig extension instead.
    auto muscleTracks = [](const Character& character, const Clip& clip) {
      int tracks = 0;
      for (const Track& track : clip.tracks) {
        const std::string& name = character.skeleton.names[track.joint];
        tracks += name.size() > 14 && name.compare(name.size() - 14, 14, "_muscleSkinned") == 0;
      }
      return tracks;
    };
    for (const Clip& clip : c.clips) CHECK(muscleTracks(c, clip) == 0);
    CHECK(c.clips.size() == baked.loaded.character.clips.size());
  }
  // Sampled motion: every clip animates every skinned joint's T, R and S.
  const BakedCharacter sampled = bakeFile(test::sampleGlbPath(), 10, GltfWeights::kMilli, MuscleMotion::kSampled);
  test::TempDir dir;
  std::ofstream(dir / "s.glb", std::ios::binary) << sampled.bytes;
  const Character reloaded = loadCharacter(dir / "s.glb").character;
  REQUIRE(reloaded.clips.size() == 3);
  for (const Clip& clip : reloaded.clips) {
    int tracks = 0;
    for (const Track& track : clip.tracks) {
      const std::string& name = reloaded.skeleton.names[track.joint];
      tracks += name.size() > 14 && name.compare(name.size() - 14, 14, "_muscleSkinned") == 0;
    }
    CHECK(tracks == 38 * 3);  // 28 muscles and 10 armpit corrective parts
  }
}

TEST_CASE("bake: at the bind pose the baked skin reproduces the original vertices", "[shared:bakes-at-ten]") {
  for (const BakedCharacter& baked : bakedAtTen()) {
    INFO(baked.path);
    test::TempDir dir;
    std::ofstream(dir / "b.glb", std::ios::binary) << baked.bytes;
    Character reloaded = loadCharacter(dir / "b.glb").character;
    const Skeleton& original = baked.loaded.character.skeleton;
    const double h = baked.landmarks.body.height;
    // Skin matrices at the bind pose: original joints at their bind, muscle joints evaluated by the
    // muscle model, both against the inverse bind matrices as written in the file.
    Pose bind = bindPose(original);
    std::vector<Eigen::Affine3d> skin(reloaded.skeleton.size(), Eigen::Affine3d::Identity());
    for (int j = 0; j < reloaded.skeleton.size(); ++j) {
      int source = original.find(reloaded.skeleton.names[j]);
      if (source >= 0) skin[j] = original.bind_world[source] * reloaded.skeleton.bind_world[j].inverse();
    }
    for (const MusclePart& part : baked.bake.muscles.parts) {
      int j = reloaded.skeleton.find(muscleJointName(part, MuscleJointRole::kSkinned));
      skin[j] = evaluateMuscle(part, original, bind).skinned * reloaded.skeleton.bind_world[j].inverse();
    }
    double worst = 0.0;
    for (size_t p = 0; p < reloaded.meshes.size(); ++p) {
      const MeshPart& mesh = reloaded.meshes[p];
      if (!mesh.skinned) continue;
      for (int v = 0; v < static_cast<int>(mesh.positions.size()); ++v) {
        Eigen::Vector3d skinned = Eigen::Vector3d::Zero();
        for (int k = 0; k < mesh.influences_per_vertex; ++k) {
          double w = mesh.weights[v * mesh.influences_per_vertex + k];
          if (w > 0) skinned += w * (skin[mesh.joints[v * mesh.influences_per_vertex + k]] * mesh.positions[v]);
        }
        worst = std::max(worst, (skinned - baked.loaded.character.meshes[p].positions[v]).norm());
      }
    }
    CHECK(worst < 1e-6 * h);
  }
}

TEST_CASE("bake: packed influences decode to exactly the quantized weights on every vertex") {
  for (int influences : {4, 7, 10}) {
    for (const std::string& path : characterPaths()) {
      INFO(path << " at " << influences);
      BakedCharacter baked = bakeFile(path, influences);
      for (const BakedPart& part : baked.bake.parts) {
        QuantizedInfluences decoded = unpackInfluences(part.packed);
        REQUIRE(decoded.slots_per_vertex == part.quantized.slots_per_vertex);
        CHECK(decoded.joints == part.quantized.joints);
        CHECK(decoded.weights == part.quantized.weights);
        for (int v = 0; v < part.quantized.vertexCount(); ++v) {
          int sum = 0;
          for (int k = 0; k < part.quantized.slots_per_vertex; ++k) sum += part.quantized.weights[v * part.quantized.slots_per_vertex + k];
          REQUIRE(sum == 1000);
        }
      }
    }
  }
}

// Two bakes of the same inputs give the same bytes: parallel_test.cpp's determinism test, which bakes
// every character at 1, 2 and 3 threads.

TEST_CASE("bake: the muscles' share of the weights comes from the joints they span", "[shared:bakes-at-ten]") {
  for (const BakedCharacter& baked : bakedAtTen()) {
    INFO(baked.path);
    const Skeleton& skeleton = baked.loaded.character.skeleton;
    std::vector<double> muscle_weight(baked.muscles.parts.size(), 0.0);
    for (const BakedPart& part : baked.bake.parts) {
      const InfluenceSet& full = part.full;
      for (size_t i = 0; i < full.joints.size(); ++i) {
        int m = full.joints[i] - skeleton.size();
        if (m >= 0 && full.weights[i] > 0) muscle_weight[m] += full.weights[i];
      }
    }
    // The sample and the fully skinned assets give every muscle some skin; RobotExpressive only skins
    // its hands, so its arm and back muscles have none. A muscle takes skin only on its belly's side
    // (docs/muscle-weights.md "side"), so one lying deep under skin that faces away from its up axis
    // (Cyberpunk's lower trapezius: 0.003 summed) gets little; most get plenty.
    if (baked.path.find("RobotExpressive") == std::string::npos) {
      for (size_t m = 0; m < muscle_weight.size(); ++m) {
        INFO(baked.muscles.parts[m].fullName());
        // A corrective has skin only where its carrier's weight blends across its span (the next test).
        if (baked.muscles.parts[m].kind == PartKind::kMuscle) CHECK(muscle_weight[m] > 0.002);
      }
      std::vector<double> sorted = muscle_weight;
      std::sort(sorted.begin(), sorted.end());
      // The KayKit mannequin's segments that one joint holds alone take no share (the next test): its
      // median muscle has 0.94 of a vertex's weight summed.
      CHECK(sorted[sorted.size() / 2] > (baked.path.find("KayKit") != std::string::npos ? 0.5 : 1.0));
    }
  }
}

TEST_CASE("bake: no muscle takes weight on a piece of skin the input moves rigidly", "[shared:bakes-at-ten]") {
  // Armour, props and a segmented body's segments: every vertex of the welded piece held by one joint
  // alone. Plain skinning keeps their shape and volume; a muscle could only deform them
  // (docs/muscle-weights.md, "Rigid pieces").
  for (const BakedCharacter& baked : bakedAtTen()) {
    INFO(baked.path);
    const Character& character = baked.loaded.character;
    const BodySurface body = buildBodySurface(character, bodyWeldTolerance(baked.muscles.body_height));
    const std::vector<char> rigid = rigidPieces(body.skin(character), body.graph);
    size_t rigid_vertices = 0, muscle_weighted_on_rigid = 0;
    for (const BakedPart& part : baked.bake.parts) {
      const auto index = std::find(body.mesh_part.begin(), body.mesh_part.end(), part.mesh_part) - body.mesh_part.begin();
      REQUIRE(static_cast<size_t>(index) < body.mesh_part.size());
      const InfluenceSet& full = part.full;
      for (int v = 0; v < full.vertexCount(); ++v) {
        if (!rigid[body.graph.weld_of_vertex[body.first_vertex[index] + v]]) continue;
        ++rigid_vertices;
        for (int k = 0; k < full.slots_per_vertex; ++k) {
          const size_t slot = static_cast<size_t>(v) * full.slots_per_vertex + k;
          if (full.joints[slot] >= character.skeleton.size() && full.weights[slot] > 0.0) ++muscle_weighted_on_rigid;
        }
      }
    }
    CHECK(muscle_weighted_on_rigid == 0);
    // The bake counts them for its line and the stats' rigid_piece_vertices.
    CHECK(baked.bake.rigid_piece_vertices == static_cast<int>(rigid_vertices));
    // Measured: Quaternius Cyberpunk 4,852 of its 7,778 vertices (armour plates, head, hands, sword), the
    // Soldier 4,848 of 15,836 (its head), the KayKit mannequin 1,738 (its rigid segments); the mannequin
    // and CesiumMan, one welded body each, none.
    if (baked.path.find("Cyberpunk") != std::string::npos) CHECK(rigid_vertices == 4852);
    if (baked.path.find("Soldier") != std::string::npos) CHECK(rigid_vertices == 4848);
    if (baked.path.find("KayKit") != std::string::npos) CHECK(rigid_vertices == 1738);
    if (baked.path.find("CesiumMan") != std::string::npos) CHECK(rigid_vertices == 0);
  }
}

TEST_CASE("bake: a corrective takes weight from its carrier only, where the skin blends the two sides of its span", "[shared:bakes-at-ten]") {
  // Plain skinning stretches a web only where it blends joints that move apart; skin one side holds
  // alone moves rigidly and needs no correcting. KayKit's rigid segments and RobotExpressive's
  // hands-only skin blend nowhere at the armpit, and give the correctives no skin at all.
  for (const BakedCharacter& baked : bakedAtTen()) {
    INFO(baked.path);
    const Skeleton& skeleton = baked.loaded.character.skeleton;
    const MuscleSet& muscles = baked.bake.muscles;
    const int muscle_count = static_cast<int>(muscles.parts.size());
    std::vector<double> total(muscle_count, 0.0);
    for (const BakedPart& part : baked.bake.parts) {
      const MeshPart& mesh = baked.loaded.character.meshes[part.mesh_part];
      const InfluenceSet input = normalizedInfluences(influencesFromMesh(mesh));
      const InfluenceSet& full = part.full;
      for (int v = 0; v < full.vertexCount(); ++v) {
        for (int k = 0; k < full.slots_per_vertex; ++k) {
          const int m = full.joints[v * full.slots_per_vertex + k] - skeleton.size();
          const double weight = full.weights[v * full.slots_per_vertex + k];
          if (m < 0 || weight <= 0.0 || muscles.parts[m].kind != PartKind::kCorrective) continue;
          double carrier = 0.0, insertion_side = 0.0;
          for (int i = 0; i < input.slots_per_vertex; ++i) {
            const int joint = input.joints[v * input.slots_per_vertex + i];
            const double w = input.weights[v * input.slots_per_vertex + i];
            if (joint == muscles.parts[m].carrier) carrier += w;
            for (int a = joint; a >= 0; a = skeleton.parents[a]) {
              if (a == muscles.parts[m].insertion.joint) {
                insertion_side += w;
                break;
              }
            }
          }
          INFO(muscles.parts[m].fullName() << " at vertex " << v << ": weight " << weight << ", carrier's " << carrier
                                           << ", insertion side's " << insertion_side);
          CHECK(weight <= carrier + 1e-12);  // taken from the carrier, nothing else
          CHECK(insertion_side > 0.0);       // on skin the input blends across the span
          CHECK(insertion_side < 1.0);
          total[m] += weight;
        }
      }
    }
    const bool blends = baked.path.find("KayKit") == std::string::npos && baked.path.find("RobotExpressive") == std::string::npos;
    for (int m = 0; m < muscle_count; ++m) {
      INFO(muscles.parts[m].fullName());
      if (muscles.parts[m].kind == PartKind::kCorrective && !blends) CHECK(total[m] == 0.0);
    }
    if (!blends) continue;
    // The arm's own corrective has skin on every character whose armpit blends.
    for (const char* side : {"Left", "Right"}) {
      double arm = 0.0;
      for (int m = 0; m < muscle_count; ++m)
        if (muscles.parts[m].fullName() == std::string(side) + "AxillaUpperArm") arm = total[m];
      INFO(side);
      CHECK(arm > 1.0);
    }
  }
}

TEST_CASE("bake: each clip's reported peak is the vertex and time where the rounded skin moves most", "[shared:bakes-at-ten]") {
  for (const BakedCharacter& baked : bakedAtTen()) {
    const Character& character = baked.loaded.character;
    const Skeleton& skeleton = character.skeleton;
    REQUIRE(baked.bake.clips.size() == character.clips.size());
    for (size_t c = 0; c < character.clips.size(); ++c) {
      const BakedClip& clip = baked.bake.clips[c];
      const ErrorPeak& peak = baked.bake.error.peaks[c];
      const double clip_max = baked.bake.error.per_clip[c].max_displacement;
      INFO(baked.path << " clip " << clip.name);
      REQUIRE(peak.vertex >= 0);
      // Skin matrices at the peak's time, skeleton indices then muscles, as the bake defines them.
      const Pose pose = sampleClip(skeleton, character.clips[c], peak.time);
      std::vector<Eigen::Affine3d> skin;
      for (int j = 0; j < skeleton.size(); ++j) skin.push_back(skinMatrix(pose, skeleton, j));
      for (size_t m = 0; m < baked.muscles.parts.size(); ++m) {
        const BakedJoint& joint = baked.bake.joints[baked.bake.skinned_joint_of_muscle[m]];
        skin.push_back(evaluateMuscle(baked.bake.muscles.parts[m], skeleton, pose).skinned * joint.bind_world.inverse());
      }
      double largest = 0.0, at_peak = -1.0;
      for (const BakedPart& part : baked.bake.parts) {
        QuantizedInfluences rounded = part.quantized;  // skin-local joints back to skeleton indices
        for (size_t k = 0; k < rounded.joints.size(); ++k) rounded.joints[k] = part.skin_joints[rounded.joints[k]];
        const std::vector<double> moved = skinningDisplacements(character.meshes[part.mesh_part].positions, part.full,
                                                                dequantizeInfluences(rounded), skin);
        largest = std::max(largest, *std::max_element(moved.begin(), moved.end()));
        if (part.mesh_part == peak.mesh_part) at_peak = moved[peak.vertex];
      }
      CHECK(at_peak == Approx(clip_max).epsilon(1e-9));
      CHECK(largest == Approx(clip_max).epsilon(1e-9));
    }
    const DeformationFigures& figures = baked.bake.error;
    if (figures.peak_clip >= 0)
      CHECK(figures.per_clip[figures.peak_clip].max_displacement == figures.overall.max_displacement);
  }
}
