// The plot data of `rigbake validate`'s report (pipeline/checks.h): the muscles' length ratios over the
// clips, the packed influences' deformation error per clip, and the body's figure (front and side
// silhouettes, bones, landmarks and muscles in the body's frame).
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "pipeline/checks.h"
#include "pipeline/deformation_error.h"
#include "pipeline/influences.h"
#include "pipeline/muscle_joint.h"

namespace rigbake {
namespace {

// The influences of one file primitive with skeleton joint indices, or false when an index is outside
// the skin (JOINT_INDEX_IN_RANGE reports it; skinning with it would be meaningless).
bool standardInSkeleton(const FileSkinAttributes& skin, const MeshPart& mesh, InfluenceSet* set) {
  set->slots_per_vertex = skin.slots;
  set->joints.resize(skin.joints.size());
  set->weights = skin.weights;
  for (size_t i = 0; i < skin.joints.size(); ++i) {
    const int local = skin.joints[i];
    if (local < 0 || local >= static_cast<int>(mesh.skin_joints.size())) return false;
    set->joints[i] = mesh.skin_joints[local];
  }
  return true;
}

bool packedInSkeleton(const FileSkinAttributes& skin, const MeshPart& mesh, InfluenceSet* set) {
  if (!skin.has_packed || !packedInfluencesProblem(skin.packed).empty()) return false;
  *set = dequantizeInfluences(unpackInfluences(skin.packed));
  for (int& joint : set->joints) {
    if (joint < 0 || joint >= static_cast<int>(mesh.skin_joints.size())) return false;
    joint = mesh.skin_joints[joint];
  }
  return true;
}

// Sample times of a clip for the checks; a character without clips is checked at its rest pose.
struct SampledClip {
  std::string name;
  const Clip* clip = nullptr;  // nullptr: the rest pose
  std::vector<double> times;
};

std::vector<SampledClip> sampledClips(const Character& character) {
  std::vector<SampledClip> clips;
  for (const Clip& clip : character.clips) {
    SampledClip sampled{clip.name, &clip, sampleTimes(clip, 0.0)};
    if (sampled.times.empty()) sampled.times.push_back(0.0);
    clips.push_back(std::move(sampled));
  }
  if (clips.empty()) clips.push_back({"(rest pose)", nullptr, {0.0}});
  return clips;
}

Pose clipPoseAt(const Skeleton& skeleton, const SampledClip& clip, double time) {
  return clip.clip ? sampleClip(skeleton, *clip.clip, time) : restPose(skeleton);
}

Eigen::Vector3d toBody(const BodyFrame& body, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - body.midline;
  return {d.dot(body.lateral), d.dot(body.up), d.dot(body.forward)};
}

// Rasterizes projected triangles into a grid of about kSilhouetteRows rows; a cell is filled when its
// centre is inside a triangle or a vertex lies in it (so that thin triangles still show).
constexpr int kSilhouetteRows = 180;

Silhouette silhouetteOf(const std::vector<std::vector<Eigen::Vector2d>>& parts,
                        const std::vector<const std::vector<std::array<int, 3>>*>& triangles) {
  Silhouette s;
  double min_u = std::numeric_limits<double>::max(), min_v = min_u;
  double max_u = std::numeric_limits<double>::lowest(), max_v = max_u;
  for (const auto& points : parts) {
    for (const Eigen::Vector2d& p : points) {
      min_u = std::min(min_u, p.x());
      max_u = std::max(max_u, p.x());
      min_v = std::min(min_v, p.y());
      max_v = std::max(max_v, p.y());
    }
  }
  if (min_u > max_u || max_v - min_v <= 0.0) return s;
  s.cell = (max_v - min_v) / kSilhouetteRows;
  s.min_u = min_u - s.cell;
  s.min_v = min_v - s.cell;
  s.columns = static_cast<int>(std::ceil((max_u - min_u) / s.cell)) + 2;
  s.rows = kSilhouetteRows + 2;
  std::vector<char> filled(static_cast<size_t>(s.columns) * s.rows, 0);
  auto cellOf = [&](const Eigen::Vector2d& p) {
    int c = std::clamp(static_cast<int>((p.x() - s.min_u) / s.cell), 0, s.columns - 1);
    int r = std::clamp(static_cast<int>((p.y() - s.min_v) / s.cell), 0, s.rows - 1);
    return std::make_pair(c, r);
  };
  auto edge = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
    return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  };
  for (size_t part = 0; part < parts.size(); ++part) {
    const auto& points = parts[part];
    for (const Eigen::Vector2d& p : points) {
      auto [c, r] = cellOf(p);
      filled[static_cast<size_t>(r) * s.columns + c] = 1;
    }
    for (const auto& t : *triangles[part]) {
      const Eigen::Vector2d &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      const double area = edge(a, b, c);
      if (area == 0.0) continue;
      auto [c0, r0] = cellOf({std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()})});
      auto [c1, r1] = cellOf({std::max({a.x(), b.x(), c.x()}), std::max({a.y(), b.y(), c.y()})});
      for (int r = r0; r <= r1; ++r) {
        for (int col = c0; col <= c1; ++col) {
          Eigen::Vector2d centre(s.min_u + (col + 0.5) * s.cell, s.min_v + (r + 0.5) * s.cell);
          double w0 = edge(b, c, centre), w1 = edge(c, a, centre), w2 = edge(a, b, centre);
          const bool inside = area > 0 ? (w0 >= 0 && w1 >= 0 && w2 >= 0) : (w0 <= 0 && w1 <= 0 && w2 <= 0);
          if (inside) filled[static_cast<size_t>(r) * s.columns + col] = 1;
        }
      }
    }
  }
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.columns;) {
      if (!filled[static_cast<size_t>(r) * s.columns + c]) {
        ++c;
        continue;
      }
      int end = c;
      while (end < s.columns && filled[static_cast<size_t>(r) * s.columns + end]) ++end;
      s.runs.push_back({r, c, end});
      c = end;
    }
  }
  return s;
}

bool isBodyPart(const MeshPart& part) { return part.skinned || part.rigid_joint >= 0; }

}  // namespace

std::vector<ClipRatios> muscleRatiosOverClips(const Character& character, const MuscleSet& muscles) {
  const Skeleton& skeleton = character.skeleton;
  std::vector<int> evaluable;
  for (size_t m = 0; m < muscles.parts.size(); ++m) {
    if (musclePartProblem(muscles.parts[m], skeleton).empty()) evaluable.push_back(static_cast<int>(m));
  }
  std::vector<ClipRatios> result;
  for (const SampledClip& clip : sampledClips(character)) {
    ClipRatios ratios;
    ratios.clip = clip.name;
    ratios.times = clip.times;
    for (int m : evaluable) {
      const MusclePart& part = muscles.parts[m];
      ratios.muscles.push_back({part.fullName(), part.group, part.compression, part.stretch, {}});
    }
    for (double t : clip.times) {
      const Pose pose = clipPoseAt(skeleton, clip, t);
      for (size_t i = 0; i < evaluable.size(); ++i) {
        ratios.muscles[i].ratio.push_back(evaluateMuscle(muscles.parts[evaluable[i]], skeleton, pose).ratio);
      }
    }
    result.push_back(std::move(ratios));
  }
  return result;
}

std::vector<ClipDeformation> packedDeformationPerClip(const Character& character, const BakedFileData& file, int threads) {
  struct PartSets {
    const MeshPart* mesh;
    InfluenceSet standard, packed;
  };
  std::vector<PartSets> parts;
  for (const FileSkinAttributes& skin : file.skins) {
    PartSets sets{&character.meshes[skin.mesh_part], {}, {}};
    if (sets.mesh->positions.size() * static_cast<size_t>(skin.slots) != skin.weights.size()) continue;
    if (!standardInSkeleton(skin, *sets.mesh, &sets.standard) || !packedInSkeleton(skin, *sets.mesh, &sets.packed)) continue;
    if (sets.packed.vertexCount() != static_cast<int>(sets.mesh->positions.size())) continue;
    parts.push_back(std::move(sets));
  }
  std::vector<ClipDeformation> result;
  if (parts.empty()) return result;
  const Skeleton& skeleton = character.skeleton;
  // A block of frames' skin matrices at a time, each part's error at every frame of it on the threads,
  // combined in frame order and within a frame in part order: one frame after another gave the same.
  constexpr size_t kFramesPerBlock = 64;
  for (const SampledClip& clip : sampledClips(character)) {
    ClipDeformation deformation;
    deformation.clip = clip.name;
    DeformationError total;
    for (size_t first = 0; first < clip.times.size(); first += kFramesPerBlock) {
      std::vector<std::vector<Eigen::Affine3d>> frames;
      for (size_t t = first; t < std::min(clip.times.size(), first + kFramesPerBlock); ++t)
        frames.push_back(bakedSkinMatrices(character, file, clipPoseAt(skeleton, clip, clip.times[t])));
      std::vector<std::vector<DeformationError>> part_errors;
      for (const PartSets& part : parts)
        part_errors.push_back(skinningDeformationErrors(part.mesh->positions, part.standard, part.packed, frames, threads));
      for (size_t f = 0; f < frames.size(); ++f) {
        for (const std::vector<DeformationError>& errors : part_errors) total = combineDeformationErrors(total, errors[f]);
        ++deformation.samples;
      }
    }
    deformation.max_displacement = total.max_displacement;
    deformation.rms_displacement = total.rms_displacement;
    result.push_back(deformation);
  }
  return result;
}

Figure bodyFigure(const Character& character, const LandmarkSet& landmarks, const MuscleSet* muscles) {
  const BodyFrame& body = landmarks.body;
  Figure figure;
  figure.height = body.height;
  std::vector<std::vector<Eigen::Vector2d>> front, side;
  std::vector<const std::vector<std::array<int, 3>>*> triangles;
  for (const MeshPart& part : character.meshes) {
    if (!isBodyPart(part)) continue;
    std::vector<Eigen::Vector2d> f, s;
    for (const Eigen::Vector3d& p : part.positions) {
      const Eigen::Vector3d b = toBody(body, p);
      f.emplace_back(b.x(), b.y());
      s.emplace_back(b.z(), b.y());
    }
    front.push_back(std::move(f));
    side.push_back(std::move(s));
    triangles.push_back(&part.triangles);
  }
  figure.front = silhouetteOf(front, triangles);
  figure.side = silhouetteOf(side, triangles);
  const Skeleton& skeleton = character.skeleton;
  // The bake's muscle joints are skeleton joints too; they are drawn as muscles, not bones.
  std::set<std::string> muscle_joints;
  if (muscles) {
    for (const MusclePart& part : muscles->parts) {
      for (const char* suffix : {"_muscleBase", "_muscleTip", "_muscleDriver", "_muscleSkinned"})
        muscle_joints.insert(part.fullName() + suffix);
    }
  }
  for (int j = 0; j < skeleton.size(); ++j) {
    const int parent = skeleton.parents[j];
    if (parent < 0 || muscle_joints.count(skeleton.names[j]) ||
        skeleton.names[j].find("_muscle") != std::string::npos)
      continue;
    figure.bones.push_back({toBody(body, skeleton.bindPosition(parent)), toBody(body, skeleton.bindPosition(j))});
  }
  for (const auto& [name, landmark] : landmarks.landmarks) {
    if (landmark.resolved) figure.landmarks.push_back({name, toBody(body, landmark.position)});
  }
  if (muscles) {
    for (const MusclePart& part : muscles->parts) {
      figure.muscles.push_back({part.fullName(), part.group, toBody(body, part.origin.world),
                                toBody(body, part.driver.world), toBody(body, part.insertion.world), false});
    }
  }
  return figure;
}

}  // namespace rigbake
