// Deformation quality: volumes of skinned surfaces (pipeline/skin_volume.h) under linear blend and
// dual-quaternion skinning and the baked rig, and the muscles' skin displacement along the normal.
// docs/deformation-quality.md.
//
// Every frame is measured in one pass that skins each vertex once (pipeline/skinning_batch.h: single
// precision, four vertices that share their joints in the lanes of one SSE register, the input's and
// the rig's weights and up to two weight differences, whose displacement is the bake's deformation
// error, blended from each joint's one transform). The volumes then take the three skinnings of a
// triangle in the lanes of one register: with a, b, c the corners' x, y and z, one lane per skinning,
// a . ((b - a) x (c - a)) needs no shuffles. Terms are summed in single precision eight at a time and
// those sums in double.
#include "pipeline/deformation_quality.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

#include "pipeline/parallel.h"
#include "pipeline/skinning.h"
#include "pipeline/skinning_batch.h"

namespace rigbake {
namespace {

constexpr int kMaxApproximations = 2;
// Weight sets of the skinning batch: the two whose volumes are measured, then the weight differences
// whose displacement is measured.
constexpr int kInputSet = 0, kRigSet = 1, kFirstErrorSet = 2;
// Lanes of the stored positions: one per skinning, in the order of the figures.
constexpr int kSkinnings = 3;  // input (linear blend), dual quaternions, rig (linear blend)

void keepExtreme(double change, double time, VolumeExtreme* extreme) {
  if (std::abs(change) > std::abs(extreme->change)) *extreme = {change, time};
}

// Sums single-precision lanes in double, blocks of at most kBlock terms summed in single precision:
// each rounding is relative to a few terms, not to the running total (the terms about a far origin are
// many times the volume they add up to).
class LaneSum {
 public:
  static constexpr size_t kBlock = 8;
  void addBlock(__m128 block) {
    low_ = _mm_add_pd(low_, _mm_cvtps_pd(block));
    high_ = _mm_add_pd(high_, _mm_cvtps_pd(_mm_movehl_ps(block, block)));
  }
  void add(__m128 value) { addBlock(value); }
  std::array<double, 4> total() const {
    std::array<double, 4> out;
    _mm_storeu_pd(out.data(), low_);
    _mm_storeu_pd(out.data() + 2, high_);
    return out;
  }

 private:
  __m128d low_ = _mm_setzero_pd(), high_ = _mm_setzero_pd();
};

// A welded vertex's posed x, y and z, one skinning per lane (the fourth lane is not used).
struct PlanarPosition {
  __m128 x, y, z;
};

inline PlanarPosition loadPlanarAt(const Float4* p) { return {_mm_load_ps(p[0].v), _mm_load_ps(p[1].v), _mm_load_ps(p[2].v)}; }

inline PlanarPosition loadPlanar(const Float4* planar, int w) { return loadPlanarAt(planar + 3 * static_cast<size_t>(w)); }

inline PlanarPosition minus(const PlanarPosition& a, const PlanarPosition& b) {
  return {_mm_sub_ps(a.x, b.x), _mm_sub_ps(a.y, b.y), _mm_sub_ps(a.z, b.z)};
}

// (b - a) x (c - a) in each lane: twice the triangle's area vector. The edges are short, so this keeps
// single precision's digits where b x c of two corners far from the origin would cancel most of them.
inline PlanarPosition areaVector(const PlanarPosition& a, const PlanarPosition& b, const PlanarPosition& c) {
  const PlanarPosition u = minus(b, a), v = minus(c, a);
  return {_mm_sub_ps(_mm_mul_ps(u.y, v.z), _mm_mul_ps(u.z, v.y)), _mm_sub_ps(_mm_mul_ps(u.z, v.x), _mm_mul_ps(u.x, v.z)),
          _mm_sub_ps(_mm_mul_ps(u.x, v.y), _mm_mul_ps(u.y, v.x))};
}

inline __m128 dot(const PlanarPosition& a, const PlanarPosition& b) {
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_mul_ps(a.y, b.y)), _mm_mul_ps(a.z, b.z));
}

// a . (b x c) in each lane, as a . ((b - a) x (c - a)), its equal.
inline __m128 tetrahedron(const PlanarPosition& a, const PlanarPosition& b, const PlanarPosition& c) {
  return dot(a, areaVector(a, b, c));
}

// The caps of `patch`'s holes (pipeline/skin_volume.cpp enclosedVolumeAbout()), positions relative to
// the sum's origin, added to `sum`. A cap's centre is the mean of its loop's positions taken relative to
// the loop's first vertex (small numbers), so its rounding is relative to the hole's size: the centre
// moves every fan triangle of a cap the same way, and a rounding relative to the positions' size would
// not average out over the few caps there are.
void addCaps(const ClosedPatch& patch, const Float4* planar, const PlanarPosition& origin, LaneSum* sum) {
  for (const std::vector<int>& hole : patch.holes) {
    const PlanarPosition first = loadPlanar(planar, hole[0]);
    PlanarPosition offset{_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()};
    for (size_t k = 1; k < hole.size(); ++k) {
      const PlanarPosition d = minus(loadPlanar(planar, hole[k]), first);
      offset = {_mm_add_ps(offset.x, d.x), _mm_add_ps(offset.y, d.y), _mm_add_ps(offset.z, d.z)};
    }
    const __m128 scale = _mm_set1_ps(1.0f / static_cast<float>(hole.size()));
    offset = {_mm_mul_ps(offset.x, scale), _mm_mul_ps(offset.y, scale), _mm_mul_ps(offset.z, scale)};
    __m128 terms = _mm_setzero_ps();
    for (size_t k = 0; k < hole.size(); ++k) {
      const PlanarPosition a = loadPlanar(planar, hole[k]);
      const PlanarPosition b = loadPlanar(planar, hole[(k + 1) % hole.size()]);
      // (a - o) . ((b - a) x (centre - a)), centre - a = (first - a) + offset.
      const PlanarPosition u = minus(b, a), to_first = minus(first, a);
      const PlanarPosition v{_mm_add_ps(to_first.x, offset.x), _mm_add_ps(to_first.y, offset.y), _mm_add_ps(to_first.z, offset.z)};
      const PlanarPosition area{_mm_sub_ps(_mm_mul_ps(u.y, v.z), _mm_mul_ps(u.z, v.y)), _mm_sub_ps(_mm_mul_ps(u.z, v.x), _mm_mul_ps(u.x, v.z)),
                                _mm_sub_ps(_mm_mul_ps(u.x, v.y), _mm_mul_ps(u.y, v.x))};
      terms = _mm_add_ps(terms, dot(minus(a, origin), area));
      if ((k + 1) % LaneSum::kBlock == 0) {
        sum->addBlock(terms);
        terms = _mm_setzero_ps();
      }
    }
    sum->addBlock(terms);
  }
}

// A muscle's skin move, summed over the parts at one frame (docs/deformation-quality.md).
struct MoveSums {
  int muscle = -1;
  double weighted = 0.0, total = 0.0, max_out = 0.0, max_in = 0.0;
  int vertices = 0;
};

struct MeasuredRegion {
  ClosedPatch patch;
  // Its triangles' area vectors come from the whole surface's loop (each triangle then in no other
  // region: the preset's first rule that takes a triangle keeps it); otherwise it is summed on its own.
  bool with_whole = false;
};

struct PreparedPart {
  const MeshPart* mesh = nullptr;
  const MeasuredPart* weights = nullptr;
  VolumeSurface surface;
  std::vector<MeasuredRegion> regions;  // one per measured region
  std::vector<int> region_of_triangle;  // per whole-surface triangle: the with_whole region holding it, or -1
  // The whole surface's triangles ordered by region, in runs of one region (or none); each corner as
  // its first Float4 in the pass's planar positions (3 w for welded vertex w), which spares the loop
  // over every triangle and frame a multiplication and a sign extension per corner.
  std::vector<std::array<std::uint32_t, 3>> ordered_corners;
  struct Run {
    size_t begin = 0, end = 0;
    int region = -1;
  };
  std::vector<Run> runs;
  SkinningBatch batch;
  std::vector<int> welded_of_lane;  // kSkinLanes per group: the welded vertex, -1: measured for the error only
  // Per part vertex: the lane (kSkinLanes * group + lane) that skins it, or an exact copy of it.
  std::vector<std::uint32_t> lane_of_vertex;
  int approximations = 0;
  // Per approximation, for the error's rounding bound: max over vertices of (|p - c| + 1) sum_k |w_k|,
  // and the most joints a vertex's difference of weights has.
  std::array<double, kMaxApproximations> error_scale{};
  std::array<int, kMaxApproximations> widest{};
  std::vector<std::vector<MuscleSkinVertex>> muscle_skin;  // muscleSkin(): the muscles' skin, welded
};

struct FrameVolumes {
  double body[3] = {0, 0, 0};  // input, dual quaternion, rig
  std::vector<std::array<double, 3>> regions;
};

// What one worker reuses from frame to frame.
struct Scratch {
  FloatSkinFrame frame;
  std::vector<Float4> planar;  // 3 per welded vertex: x, y, z, a skinning per lane
  std::array<std::vector<float>, kMaxApproximations> squared;  // per lane: its squared error
  std::vector<PlanarPosition> region_origin;
  std::vector<LaneSum> region_sum;
  std::vector<Eigen::Vector3d> normals;
  std::vector<char> moved;  // welded vertices whose skin move is measured at this frame
  std::vector<int> moved_vertices;
  std::vector<Eigen::Vector3d> input, rig;  // their double-precision posed positions
  std::vector<int> moved_index;  // welded vertex -> index into moved_vertices
};

bool sameSlots(const InfluenceSet& set, size_t a, size_t b) {
  const size_t slots = static_cast<size_t>(set.slots_per_vertex);
  for (size_t k = 0; k < slots; ++k) {
    if (set.joints[a * slots + k] != set.joints[b * slots + k] || set.weights[a * slots + k] != set.weights[b * slots + k])
      return false;
  }
  return true;
}

}  // namespace

std::vector<std::vector<MuscleSkinVertex>> muscleSkin(const InfluenceSet& rig, const std::vector<int>& vertex_of_weld,
                                                      int joint_count, int muscle_count) {
  std::vector<std::vector<MuscleSkinVertex>> skin(static_cast<size_t>(std::max(muscle_count, 0)));
  const size_t slots = static_cast<size_t>(rig.slots_per_vertex);
  for (size_t w = 0; w < vertex_of_weld.size(); ++w) {
    const size_t first = static_cast<size_t>(vertex_of_weld[w]) * slots;
    for (size_t k = 0; k < slots; ++k) {
      const int joint = rig.joints[first + k];
      const int m = joint - joint_count;
      if (m < 0 || m >= muscle_count) continue;
      // A joint named in more than one slot is summed once, at its first slot, in slot order.
      bool named_before = false;
      for (size_t j = 0; j < k && !named_before; ++j) named_before = rig.joints[first + j] == joint;
      if (named_before) continue;
      double weight = 0.0;
      for (size_t j = k; j < slots; ++j)
        if (rig.joints[first + j] == joint) weight += rig.weights[first + j];
      if (weight >= kMuscleSkinWeight) skin[static_cast<size_t>(m)].push_back({static_cast<int>(w), weight});
    }
  }
  return skin;
}

Eigen::Vector3d skinCentre(const Character& character, const std::vector<MeasuredPart>& parts) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (const MeasuredPart& part : parts) {
    for (const Eigen::Vector3d& p : character.meshes[part.mesh_part].positions) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
  }
  return low.allFinite() && high.allFinite() ? Eigen::Vector3d(0.5 * (low + high)) : Eigen::Vector3d::Zero();
}

namespace {

// Welds each part once and cuts each region the figures measure out of it and closes it (quality only;
// otherwise the weld alone). Regions too flat to enclose a meaningful volume are left out of the
// figures (and listed); `kept` gets the measured regions' indices.
std::vector<PreparedPart> prepareSurfaces(const Character& character, const std::vector<BodyRegion>& regions,
                                          const std::vector<MeasuredPart>& parts, bool quality, double weld_tolerance, int threads,
                                          std::vector<size_t>* kept, DeformationQuality* figures) {
  std::vector<PreparedPart> prepared(parts.size());
  if (!quality) {
    for (size_t p = 0; p < parts.size(); ++p) prepared[p].surface = buildVolumeSurface(character.meshes[parts[p].mesh_part], weld_tolerance);
    return prepared;
  }
  std::vector<int> mesh_parts;
  for (const MeasuredPart& part : parts) mesh_parts.push_back(part.mesh_part);
  std::vector<std::vector<std::vector<int>>> region_triangles;
  for (const BodyRegion& region : regions) region_triangles.push_back(region.triangles);
  MeasuredSurfaces measured = measuredSurfaces(character, mesh_parts, region_triangles, weld_tolerance, threads);
  for (size_t r = 0; r < regions.size(); ++r) {
    if (measured.region_measured[r]) {
      kept->push_back(r);
      figures->regions.push_back(regions[r].name);
    } else {
      figures->unmeasured_regions.push_back(regions[r].name);
    }
  }
  for (size_t p = 0; p < parts.size(); ++p) {
    PreparedPart& part = prepared[p];
    part.surface = std::move(measured.surfaces[p]);
    std::vector<int> whole_of_part(character.meshes[parts[p].mesh_part].triangles.size(), -1);
    for (size_t t = 0; t < part.surface.part_triangle.size(); ++t) whole_of_part[part.surface.part_triangle[t]] = static_cast<int>(t);
    // Which closed region each triangle is in; a triangle two regions claim leaves both to be summed
    // on their own.
    part.region_of_triangle.assign(part.surface.whole.triangles.size(), -1);
    std::vector<char> shared(kept->size(), 0);
    for (size_t k = 0; k < kept->size(); ++k) {
      const size_t r = (*kept)[k];
      MeasuredRegion region;
      region.patch = std::move(measured.regions[p][r]);
      region.with_whole = true;
      if (p < regions[r].triangles.size()) {
        for (int t : regions[r].triangles[p]) {
          const int i = whole_of_part[t];
          if (i < 0) continue;
          int& owner = part.region_of_triangle[static_cast<size_t>(i)];
          if (owner >= 0 && owner != static_cast<int>(k)) shared[k] = shared[static_cast<size_t>(owner)] = 1;
          owner = static_cast<int>(k);
        }
      }
      part.regions.push_back(std::move(region));
    }
    for (size_t k = 0; k < kept->size(); ++k) {
      if (!shared[k]) continue;
      part.regions[k].with_whole = false;
    }
    for (int& owner : part.region_of_triangle)
      if (owner >= 0 && !part.regions[static_cast<size_t>(owner)].with_whole) owner = -1;
  }
  return prepared;
}

// The part's vertices for the pass, in one skinning batch: the welded ones (volumes), and for the error
// every other vertex whose position or weights differ from its welded vertex's (an exact copy has the
// same error); each lane's welded vertex, each vertex's lane, and the error's rounding bound's inputs.
void prepareBatch(const std::vector<std::vector<ErrorWeights>>& errors, size_t p, bool quality, const Eigen::Vector3d& centre,
                  int joint_count, DualQuaternionPivots* pivots, int threads, PreparedPart* part) {
  const int approximations = part->approximations;
  const std::vector<Eigen::Vector3d>& positions = part->mesh->positions;
  const VolumeSurface& surface = part->surface;
  std::vector<int> vertices;
  std::vector<char> dual_quaternion;
  std::vector<int> skinned_as(positions.size(), -1);  // the vertex whose lane holds this one's figures
  for (size_t v = 0; v < positions.size(); ++v) {
    const size_t first = static_cast<size_t>(surface.vertex_of_weld[surface.weld_of_vertex[v]]);
    bool copy = first != v;
    if (copy && approximations == 0) continue;
    if (copy) {
      copy = positions[v] == positions[first];
      for (int a = 0; a < approximations && copy; ++a)
        copy = sameSlots(*errors[a][p].reference, v, first) && sameSlots(*errors[a][p].approximation, v, first);
    }
    skinned_as[v] = static_cast<int>(copy ? first : v);
    if (copy) continue;
    vertices.push_back(static_cast<int>(v));
    dual_quaternion.push_back(quality && first == v);
  }
  std::array<SetWeights, kSkinSets> sets;
  if (quality) {
    sets[kInputSet].plus = &part->weights->input;
    sets[kRigSet].plus = &part->weights->rig;
  }
  for (int a = 0; a < approximations; ++a) {
    sets[kFirstErrorSet + a].plus = errors[a][p].reference;
    sets[kFirstErrorSet + a].minus = errors[a][p].approximation;
  }
  part->batch = buildSkinningBatch(positions, vertices, centre, sets, dual_quaternion, joint_count, pivots, threads);
  const SkinningBatch& batch = part->batch;
  std::vector<std::uint32_t> lane_of_skinned(positions.size(), 0);
  part->welded_of_lane.reserve(kSkinLanes * batch.groups());  // lives through the pass: no slack
  for (size_t g = 0; g < batch.groups(); ++g) {
    for (size_t lane = 0; lane < kSkinLanes; ++lane) {
      const int v = batch.vertex[kSkinLanes * g + lane];
      const bool welded = quality && v >= 0 && surface.vertex_of_weld[surface.weld_of_vertex[v]] == v;
      part->welded_of_lane.push_back(welded ? surface.weld_of_vertex[v] : -1);
      if (v < 0) continue;
      lane_of_skinned[static_cast<size_t>(v)] = static_cast<std::uint32_t>(kSkinLanes * g + lane);
      const double size = (positions[static_cast<size_t>(v)] - centre).norm() + 1.0;
      for (int a = 0; a < approximations; ++a) {
        double sum = 0.0;
        int count = 0;
        for (std::uint32_t slot = batch.first_slot[g]; slot < batch.first_slot[g + 1]; ++slot) {
          const float weight = batch.weights[kSkinSets * slot + kFirstErrorSet + a].v[lane];
          sum += std::abs(weight);
          count += weight != 0.0f;
        }
        part->error_scale[a] = std::max(part->error_scale[a], size * sum);
        part->widest[a] = std::max(part->widest[a], count);
      }
    }
  }
  if (approximations > 0) {
    part->lane_of_vertex.resize(positions.size());
    for (size_t v = 0; v < positions.size(); ++v) part->lane_of_vertex[v] = lane_of_skinned[static_cast<size_t>(skinned_as[v])];
  }
}

// The whole surface's triangles in runs of one region (PreparedPart::ordered_corners): stable by
// region (-1, none, first), a counting sort, the order std::stable_sort gives (it took 9 ms of the 100k
// sample's set-up on one core).
void orderTrianglesByRegion(size_t region_count, PreparedPart* part) {
  const VolumeSurface& surface = part->surface;
  std::vector<size_t> first_of_region(region_count + 2, 0);
  for (int region : part->region_of_triangle) ++first_of_region[static_cast<size_t>(region + 2)];
  for (size_t k = 1; k < first_of_region.size(); ++k) first_of_region[k] += first_of_region[k - 1];
  std::vector<size_t> order(surface.whole.triangles.size());
  for (size_t i = 0; i < order.size(); ++i) order[first_of_region[static_cast<size_t>(part->region_of_triangle[i] + 1)]++] = i;
  part->ordered_corners.reserve(order.size());
  for (size_t i : order) {
    const int region = part->region_of_triangle[i];
    if (part->runs.empty() || part->runs.back().region != region)
      part->runs.push_back({part->ordered_corners.size(), part->ordered_corners.size(), region});
    const std::array<int, 3>& t = surface.whole.triangles[i];
    part->ordered_corners.push_back({3u * static_cast<std::uint32_t>(t[0]), 3u * static_cast<std::uint32_t>(t[1]),
                                     3u * static_cast<std::uint32_t>(t[2])});
    part->runs.back().end = part->ordered_corners.size();
  }
}

// Bind volumes, in double from the bind positions themselves.
FrameVolumes bindVolumes(const std::vector<PreparedPart>& prepared, size_t region_count, bool quality, DeformationQuality* figures) {
  FrameVolumes bind;
  bind.regions.assign(region_count, {0, 0, 0});
  if (!quality) return bind;
  for (const PreparedPart& part : prepared) {
    const std::vector<Eigen::Vector3d>& welded = part.surface.bind;
    const double body = enclosedVolume(part.surface.whole, welded);
    for (int k = 0; k < 3; ++k) bind.body[k] += body;
    for (size_t r = 0; r < region_count; ++r) {
      const double region = enclosedVolume(part.regions[r].patch, welded);
      for (int k = 0; k < 3; ++k) bind.regions[r][k] += region;
    }
  }
  figures->body_volume = bind.body[0];
  for (size_t r = 0; r < region_count; ++r) figures->region_volumes.push_back(bind.regions[r][0]);
  return bind;
}

double volumeChange(double volume, double reference) { return reference != 0.0 ? volume / reference - 1.0 : 0.0; }

// Every clip's frames in one list, and each muscle's most compressed and most stretched sample over
// every clip, whose skin moves the pass measures on those frames.
struct FramePlan {
  struct Sample {
    int clip = -1, frame = -1;
    double ratio = 1.0;
  };
  std::vector<std::pair<size_t, size_t>> clip_frame;  // (clip, frame) in clip order
  std::vector<size_t> first_frame;                    // per clip
  std::vector<Sample> most_compressed, most_stretched;  // per muscle
  std::vector<std::vector<int>> moves_at;             // muscles measured at each frame
};

FramePlan planFrames(const std::vector<MeasuredClip>& clips, int muscle_count, bool quality) {
  FramePlan plan;
  for (size_t c = 0; c < clips.size(); ++c) {
    plan.first_frame.push_back(plan.clip_frame.size());
    for (size_t t = 0; t < clips[c].times.size(); ++t) plan.clip_frame.emplace_back(c, t);
  }
  plan.most_compressed.resize(muscle_count);
  plan.most_stretched.resize(muscle_count);
  plan.moves_at.resize(plan.clip_frame.size());
  if (!quality) return plan;
  for (size_t c = 0; c < clips.size(); ++c) {
    for (size_t t = 0; t < clips[c].times.size(); ++t) {
      for (int m = 0; m < muscle_count; ++m) {
        const double ratio = clips[c].ratio[t][m];
        if (ratio < plan.most_compressed[m].ratio) plan.most_compressed[m] = {static_cast<int>(c), static_cast<int>(t), ratio};
        if (ratio > plan.most_stretched[m].ratio) plan.most_stretched[m] = {static_cast<int>(c), static_cast<int>(t), ratio};
      }
    }
  }
  for (int m = 0; m < muscle_count; ++m) {
    for (const FramePlan::Sample* sample : {&plan.most_compressed[m], &plan.most_stretched[m]}) {
      if (sample->clip < 0) continue;
      std::vector<int>& at = plan.moves_at[plan.first_frame[sample->clip] + static_cast<size_t>(sample->frame)];
      if (std::find(at.begin(), at.end(), m) == at.end()) at.push_back(m);
    }
  }
  return plan;
}

// The pass over the frames: each frame skins every part's entries, keeps the welded positions (about
// the centre), sums the volumes, the errors and the skin moves asked for there. Every frame writes only
// its own figures.
class DeformationPass {
 public:
  DeformationPass(const std::vector<MeasuredClip>& clips, const std::vector<PreparedPart>& prepared, const FramePlan& plan,
                  const Eigen::Vector3d& centre, const DualQuaternionPivots& pivots, bool quality, int joint_count,
                  size_t region_count)
      : clips_(clips), prepared_(prepared), plan_(plan), centre_(centre), pivots_(pivots), quality_(quality),
        joint_count_(joint_count), region_count_(region_count) {}

  std::vector<FrameVolumes> volumes;                                      // per frame
  std::vector<std::vector<MoveSums>> moves;                               // per frame
  std::vector<std::vector<std::vector<ScreenedError>>>* screened = nullptr;  // [a][f][p]

  void measureFrame(size_t f, Scratch& scratch);

 private:
  void skinPart(const PreparedPart& part, const FloatSkinFrame& frame, Scratch& scratch);
  void measureErrors(const PreparedPart& part, size_t f, size_t p, const FloatSkinFrame& frame, const Scratch& scratch);
  void sumVolumes(const PreparedPart& part, Scratch& scratch, FrameVolumes* frame_volumes);
  void measureSkinMoves(const PreparedPart& part, const SkinFrame& skin, Scratch& scratch, std::vector<MoveSums>* frame_moves);

  const std::vector<MeasuredClip>& clips_;
  const std::vector<PreparedPart>& prepared_;
  const FramePlan& plan_;
  const Eigen::Vector3d& centre_;
  const DualQuaternionPivots& pivots_;
  const bool quality_;
  const int joint_count_;
  const size_t region_count_;
};

// Skins the part at the frame: the welded vertices' three skinnings into scratch.planar (quality), each
// lane's squared error per approximation into scratch.squared.
void DeformationPass::skinPart(const PreparedPart& part, const FloatSkinFrame& frame, Scratch& scratch) {
  const SkinningBatch& batch = part.batch;
  const bool quality = quality_;
  if (quality) scratch.planar.resize(3 * static_cast<size_t>(part.surface.weldedCount()));
  Float4* planar = scratch.planar.data();
  // The errors: each lane's squared distance, then summed and searched in vertex order (so that the
  // figures of one approximation do not depend on what else is skinned with it).
  for (int a = 0; a < part.approximations; ++a) scratch.squared[a].resize(kSkinLanes * batch.groups());
  auto visit = [&](size_t g, const SkinnedGroup& group) {
    if (quality) {
      // Per vertex the stored lanes are (input, dual quaternion, rig, -): a transpose of the
      // group's lanes.
      for (int c = 0; c < 3; ++c) {
        const __m128 bind = c == 0 ? group.x : c == 1 ? group.y : group.z;
        __m128 input = _mm_add_ps(bind, group.offset[kInputSet][c]);
        __m128 dual_quaternion = group.dual_quaternion[c];
        __m128 rig = _mm_add_ps(bind, group.offset[kRigSet][c]);
        __m128 unused = _mm_setzero_ps();
        _MM_TRANSPOSE4_PS(input, dual_quaternion, rig, unused);
        const __m128 lanes[kSkinLanes] = {input, dual_quaternion, rig, unused};
        for (size_t lane = 0; lane < kSkinLanes; ++lane) {
          const int w = part.welded_of_lane[kSkinLanes * g + lane];
          if (w >= 0) _mm_store_ps(planar[3 * static_cast<size_t>(w) + static_cast<size_t>(c)].v, lanes[lane]);
        }
      }
    }
    for (int a = 0; a < part.approximations; ++a) {
      const __m128* offset = group.offset[kFirstErrorSet + a];
      const __m128 squared = _mm_add_ps(_mm_add_ps(_mm_mul_ps(offset[0], offset[0]), _mm_mul_ps(offset[1], offset[1])),
                                        _mm_mul_ps(offset[2], offset[2]));
      _mm_storeu_ps(&scratch.squared[a][kSkinLanes * g], squared);
    }
  };
  const size_t groups = batch.groups();
  switch (part.approximations * 2 + (quality ? 1 : 0)) {
    case 0: break;
    case 1: skinSkinningBatch<0x3>(batch, frame, 0, groups, visit); break;
    case 2: skinSkinningBatch<0x4>(batch, frame, 0, groups, visit); break;
    case 3: skinSkinningBatch<0x7>(batch, frame, 0, groups, visit); break;
    case 4: skinSkinningBatch<0xC>(batch, frame, 0, groups, visit); break;
    default: skinSkinningBatch<0xF>(batch, frame, 0, groups, visit); break;
  }
}

void DeformationPass::measureErrors(const PreparedPart& part, size_t f, size_t p, const FloatSkinFrame& frame, const Scratch& scratch) {
  for (int a = 0; a < part.approximations; ++a) {
    const float* squared = scratch.squared[a].data();
    double sum_squared = 0.0;
    float largest = 0.0f;
    int largest_vertex = -1;
    const int vertex_count = static_cast<int>(part.lane_of_vertex.size());
    for (int v = 0; v < vertex_count; ++v) {
      const float s = squared[part.lane_of_vertex[static_cast<size_t>(v)]];
      sum_squared += static_cast<double>(s);
      if (s > largest) {
        largest = s;
        largest_vertex = v;
      }
    }
    ScreenedError& screened_error = (*screened)[static_cast<size_t>(a)][f][p];
    DeformationError& error = screened_error.error;
    error.vertex_count = vertex_count;
    error.max_displacement = std::sqrt(static_cast<double>(largest));
    error.max_vertex = largest_vertex;
    if (vertex_count > 0) error.rms_displacement = std::sqrt(sum_squared / vertex_count);
    // Rounding of the single-precision offsets (skinning_batch.h): each d_k within 8 units of
    // roundoff of reach (|p - c| + 1), the blend within one more per slot, the length within 4.
    const double unit = std::ldexp(1.0, -24);
    screened_error.bound = 2.0 * ((part.widest[a] + 10) * unit * frame.reach * part.error_scale[a] +
                                  4.0 * unit * error.max_displacement);
  }
}

// Volumes: the whole surface about its first vertex, each region about its own (so a region's terms are
// the size of the region, not of the body), as skin_volume.cpp sums them; a triangle's area vector
// serves the body and its region.
void DeformationPass::sumVolumes(const PreparedPart& part, Scratch& scratch, FrameVolumes* frame_volumes) {
  const size_t region_count = region_count_;
  const Float4* planar = scratch.planar.data();
  const ClosedPatch& whole = part.surface.whole;
  const PlanarPosition zero{_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()};
  const PlanarPosition whole_origin = whole.triangles.empty() ? zero : loadPlanar(planar, whole.triangles[0][0]);
  scratch.region_origin.resize(region_count);
  scratch.region_sum.assign(region_count, LaneSum());
  for (size_t r = 0; r < region_count; ++r) {
    const ClosedPatch& patch = part.regions[r].patch;
    scratch.region_origin[r] = patch.triangles.empty() ? zero : loadPlanar(planar, patch.triangles[0][0]);
  }
  // Runs of one region: the body's and the region's sums in registers, eight terms at a time.
  LaneSum body;
  for (const PreparedPart::Run& run : part.runs) {
    LaneSum* region_sum = run.region >= 0 ? &scratch.region_sum[static_cast<size_t>(run.region)] : nullptr;
    const PlanarPosition& region_origin = run.region >= 0 ? scratch.region_origin[static_cast<size_t>(run.region)] : zero;
    for (size_t block = run.begin; block < run.end; block += LaneSum::kBlock) {
      const size_t block_end = std::min(run.end, block + LaneSum::kBlock);
      __m128 body_terms = _mm_setzero_ps(), region_terms = _mm_setzero_ps();
      for (size_t i = block; i < block_end; ++i) {
        const std::array<std::uint32_t, 3>& t = part.ordered_corners[i];
        const PlanarPosition a = loadPlanarAt(planar + t[0]);
        const PlanarPosition area = areaVector(a, loadPlanarAt(planar + t[1]), loadPlanarAt(planar + t[2]));
        body_terms = _mm_add_ps(body_terms, dot(minus(a, whole_origin), area));
        if (region_sum != nullptr) region_terms = _mm_add_ps(region_terms, dot(minus(a, region_origin), area));
      }
      body.addBlock(body_terms);
      if (region_sum != nullptr) region_sum->addBlock(region_terms);
    }
  }
  addCaps(whole, planar, whole_origin, &body);
  const std::array<double, 4> body_sum = body.total();
  for (int k = 0; k < kSkinnings; ++k) frame_volumes->body[k] += body_sum[k] / 6.0;
  for (size_t r = 0; r < region_count; ++r) {
    const MeasuredRegion& region = part.regions[r];
    if (region.patch.triangles.empty()) continue;
    LaneSum& sum = scratch.region_sum[r];
    const PlanarPosition& own = scratch.region_origin[r];
    if (!region.with_whole) {
      for (const auto& t : region.patch.triangles)
        sum.add(tetrahedron(minus(loadPlanar(planar, t[0]), own), minus(loadPlanar(planar, t[1]), own),
                            minus(loadPlanar(planar, t[2]), own)));
    }
    addCaps(region.patch, planar, own, &sum);
    const std::array<double, 4> region_sum = sum.total();
    for (int k = 0; k < kSkinnings; ++k) frame_volumes->regions[r][k] += region_sum[k] / 6.0;
  }
}

// The skin's move along the input skinning's normal where a muscle is measured at this frame, in double
// as skin_volume.cpp and skinning.cpp compute it: only the muscles' vertices and the triangles around
// them, each normal summed over its triangles in the same order.
void DeformationPass::measureSkinMoves(const PreparedPart& part, const SkinFrame& skin, Scratch& scratch,
                                       std::vector<MoveSums>* frame_moves) {
  const ClosedPatch& whole = part.surface.whole;
  const int welded_count = part.surface.weldedCount();
  scratch.moved.assign(static_cast<size_t>(welded_count), 0);
  for (const MoveSums& move : *frame_moves)
    for (const MuscleSkinVertex& vertex : part.muscle_skin[static_cast<size_t>(move.muscle)]) scratch.moved[vertex.welded] = 1;
  scratch.moved_index.assign(static_cast<size_t>(welded_count), -1);
  scratch.moved_vertices.clear();
  auto need = [&](int w) {
    if (scratch.moved_index[w] >= 0) return;
    scratch.moved_index[w] = static_cast<int>(scratch.moved_vertices.size());
    scratch.moved_vertices.push_back(part.surface.vertex_of_weld[w]);
  };
  for (const auto& t : whole.triangles) {
    if (!scratch.moved[t[0]] && !scratch.moved[t[1]] && !scratch.moved[t[2]]) continue;
    for (int k = 0; k < 3; ++k) need(t[k]);
  }
  for (int w = 0; w < welded_count; ++w)
    if (scratch.moved[w]) need(w);
  skinLinearBlend(part.mesh->positions, part.weights->input, skin, scratch.moved_vertices, &scratch.input);
  skinLinearBlend(part.mesh->positions, part.weights->rig, skin, scratch.moved_vertices, &scratch.rig);
  scratch.normals.assign(scratch.moved_vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& t : whole.triangles) {
    if (!scratch.moved[t[0]] && !scratch.moved[t[1]] && !scratch.moved[t[2]]) continue;
    const Eigen::Vector3d& a = scratch.input[scratch.moved_index[t[0]]];
    const Eigen::Vector3d area = (scratch.input[scratch.moved_index[t[1]]] - a).cross(scratch.input[scratch.moved_index[t[2]]] - a);
    for (int k = 0; k < 3; ++k) scratch.normals[scratch.moved_index[t[k]]] += area;
  }
  for (MoveSums& move : *frame_moves) {
    for (const MuscleSkinVertex& vertex : part.muscle_skin[static_cast<size_t>(move.muscle)]) {
      const size_t i = static_cast<size_t>(scratch.moved_index[vertex.welded]);
      Eigen::Vector3d normal = scratch.normals[i];
      const double length = normal.norm();
      if (length > 0) normal /= length;
      const double along = (scratch.rig[i] - scratch.input[i]).dot(normal);
      move.weighted += vertex.weight * along;
      move.total += vertex.weight;
      move.max_out = std::max(move.max_out, along);
      move.max_in = std::max(move.max_in, -along);
      ++move.vertices;
    }
  }
}

void DeformationPass::measureFrame(size_t f, Scratch& scratch) {
  const SkinFrame& skin = (*clips_[plan_.clip_frame[f].first].frames)[plan_.clip_frame[f].second];
  prepareFloatSkinFrame(skin, centre_, quality_ ? joint_count_ : 0, pivots_, &scratch.frame);
  const FloatSkinFrame& frame = scratch.frame;
  const std::vector<int>& moved_muscles = plan_.moves_at[f];
  std::vector<MoveSums>& frame_moves = moves[f];
  for (int m : moved_muscles) frame_moves.push_back(MoveSums{m});
  for (size_t p = 0; p < prepared_.size(); ++p) {
    const PreparedPart& part = prepared_[p];
    skinPart(part, frame, scratch);
    measureErrors(part, f, p, frame, scratch);
    if (!quality_) continue;
    sumVolumes(part, scratch, &volumes[f]);
    if (!moved_muscles.empty()) measureSkinMoves(part, skin, scratch, &frame_moves);
  }
}

// Each clip's extremes in frame order.
void clipExtremes(const std::vector<MeasuredClip>& clips, const FramePlan& plan, const std::vector<FrameVolumes>& all_volumes,
                  const FrameVolumes& bind, size_t region_count, DeformationQuality* figures) {
  for (size_t c = 0; c < clips.size(); ++c) {
    const MeasuredClip& clip = clips[c];
    ClipQuality clip_figures;
    clip_figures.clip = clip.name;
    clip_figures.regions.resize(region_count);
    double worst = -1.0;
    const FrameVolumes* clip_volumes = all_volumes.data() + plan.first_frame[c];
    for (size_t t = 0; t < clip.times.size(); ++t) {
      const FrameVolumes& volumes = clip_volumes[t];
      const double time = clip.times[t];
      keepExtreme(volumeChange(volumes.body[0], bind.body[0]), time, &clip_figures.body.input);
      keepExtreme(volumeChange(volumes.body[1], bind.body[1]), time, &clip_figures.body.dual_quaternion);
      const double rig_change = volumeChange(volumes.body[2], bind.body[2]);
      keepExtreme(rig_change, time, &clip_figures.body.rig);
      if (std::abs(rig_change) > worst) {
        worst = std::abs(rig_change);
        clip_figures.worst_frame = static_cast<int>(t);
      }
      for (size_t r = 0; r < region_count; ++r) {
        keepExtreme(volumeChange(volumes.regions[r][0], bind.regions[r][0]), time, &clip_figures.regions[r].input);
        keepExtreme(volumeChange(volumes.regions[r][1], bind.regions[r][1]), time, &clip_figures.regions[r].dual_quaternion);
        keepExtreme(volumeChange(volumes.regions[r][2], bind.regions[r][2]), time, &clip_figures.regions[r].rig);
      }
    }
    figures->clips.push_back(std::move(clip_figures));
  }
}

// Where each region that loses beyond plain skinning in a clip loses it (pipeline/region_loss_place.h),
// at the rig's extreme sample; one task per clip and region, so the same at any thread count.
// `full`: per part, the weights before the cut and the rounding (the first approximation's reference),
// or null.
void locateRegionLosses(const Character& character, const std::vector<MeasuredPart>& parts, const std::vector<MeasuredClip>& clips,
                        const std::vector<PreparedPart>& prepared, const std::vector<ErrorWeights>* full, int threads,
                        DeformationQuality* figures) {
  const size_t region_count = figures->regions.size();
  std::vector<std::pair<size_t, size_t>> tasks;  // (clip, region)
  for (size_t c = 0; c < figures->clips.size(); ++c) {
    figures->clips[c].region_places.assign(region_count, RegionLossPlace{});
    for (size_t k = 0; k < region_count; ++k)
      if (regionLossBeyondInput(figures->clips[c].regions[k]) > 0.0) tasks.emplace_back(c, k);
  }
  std::vector<RegionLossScratch> scratch(std::max<size_t>(1, parallelWorkerCount(threads, tasks.size(), 1)));
  parallelForWorkers(threads, tasks.size(), 1, [&](size_t worker, size_t, size_t i, size_t) {
    const auto [c, k] = tasks[i];
    const MeasuredClip& clip = clips[c];
    const double time = figures->clips[c].regions[k].rig.time;
    const auto at = std::find(clip.times.begin(), clip.times.end(), time);
    if (at == clip.times.end()) return;
    std::vector<RegionPiece> pieces;
    for (size_t p = 0; p < prepared.size(); ++p)
      pieces.push_back(RegionPiece{parts[p].mesh_part, &prepared[p].surface, &prepared[p].regions[k].patch, &parts[p].input,
                                   &parts[p].rig, full ? (*full)[p].reference : nullptr});
    figures->clips[c].region_places[k] =
        regionLossPlace(character, pieces, (*clip.frames)[static_cast<size_t>(at - clip.times.begin())], figures->region_volumes[k],
                        time, &scratch[worker]);
  });
}

// A muscle's skin move at its sample, when `wanted` (compressed or stretched there).
MuscleSkinMove skinMoveAt(const std::vector<MeasuredClip>& clips, const FramePlan& plan,
                          const std::vector<std::vector<MoveSums>>& all_moves, int m, const FramePlan::Sample& sample, bool wanted) {
  MuscleSkinMove move;
  if (!wanted || sample.clip < 0) return move;
  const size_t f = plan.first_frame[sample.clip] + static_cast<size_t>(sample.frame);
  for (const MoveSums& sums : all_moves[f]) {
    if (sums.muscle != m) continue;
    if (sums.vertices == 0) return MuscleSkinMove{};
    move.measured = true;
    move.clip = clips[sample.clip].name;
    move.time = clips[sample.clip].times[sample.frame];
    move.ratio = sample.ratio;
    move.mean = sums.weighted / sums.total;
    move.max_out = sums.max_out;
    move.max_in = sums.max_in;
    move.vertices = sums.vertices;
  }
  return move;
}

}  // namespace

DeformationMeasures measureDeformation(const Character& character, const std::vector<BodyRegion>& regions,
                                       const std::vector<MeasuredPart>& parts, const MuscleSet& muscles,
                                       const std::vector<MeasuredClip>& clips, bool quality,
                                       const std::vector<std::vector<ErrorWeights>>& errors, int threads) {
  const Skeleton& skeleton = character.skeleton;
  const int joint_count = skeleton.size();
  const int muscle_count = static_cast<int>(muscles.parts.size());
  const int approximations = static_cast<int>(errors.size());
  assert(approximations <= kMaxApproximations);
  DeformationMeasures measures;
  DeformationQuality& figures = measures.quality;
  const double weld_tolerance = bodyWeldTolerance(muscles.body_height);
  std::vector<size_t> kept;
  std::vector<PreparedPart> prepared = prepareSurfaces(character, regions, parts, quality, weld_tolerance, threads, &kept, &figures);
  const size_t region_count = kept.size();

  const Eigen::Vector3d centre = skinCentre(character, parts);
  DualQuaternionPivots pivots;
  size_t widest_surface = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    PreparedPart& part = prepared[p];
    part.mesh = &character.meshes[parts[p].mesh_part];
    part.weights = &parts[p];
    part.approximations = approximations;
    prepareBatch(errors, p, quality, centre, joint_count, &pivots, threads, &part);
    if (quality) orderTrianglesByRegion(kept.size(), &part);
    if (quality) part.muscle_skin = muscleSkin(part.weights->rig, part.surface.vertex_of_weld, joint_count, muscle_count);
    widest_surface = std::max(widest_surface, static_cast<size_t>(part.surface.weldedCount()));
  }
  const FrameVolumes bind = bindVolumes(prepared, region_count, quality, &figures);
  const FramePlan plan = planFrames(clips, muscle_count, quality);
  const size_t frame_count = plan.clip_frame.size();

  DeformationPass pass(clips, prepared, plan, centre, pivots, quality, joint_count, region_count);
  pass.volumes.resize(frame_count);
  for (FrameVolumes& volumes : pass.volumes) volumes.regions.assign(region_count, {0, 0, 0});
  pass.moves.resize(frame_count);
  measures.screened.assign(static_cast<size_t>(approximations),
                           std::vector<std::vector<ScreenedError>>(frame_count, std::vector<ScreenedError>(parts.size())));
  pass.screened = &measures.screened;
  // Frames in chunks of a few, each worker reusing its scratch.
  constexpr size_t kFramesPerChunk = 2;
  std::vector<Scratch> scratch(std::max<size_t>(1, parallelWorkerCount(threads, frame_count, kFramesPerChunk)));
  for (Scratch& s : scratch) s.planar.reserve(3 * widest_surface);
  parallelForWorkers(threads, frame_count, kFramesPerChunk, [&](size_t worker, size_t, size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) pass.measureFrame(f, scratch[worker]);
  });
  if (!quality) return measures;

  clipExtremes(clips, plan, pass.volumes, bind, region_count, &figures);
  locateRegionLosses(character, parts, clips, prepared, errors.empty() ? nullptr : &errors[0], threads, &figures);
  for (int m = 0; m < muscle_count; ++m) {
    MuscleQuality muscle;
    muscle.muscle = muscles.parts[m].fullName();
    muscle.kind = muscles.parts[m].kind;
    muscle.compressed = skinMoveAt(clips, plan, pass.moves, m, plan.most_compressed[m], plan.most_compressed[m].ratio < 1.0);
    muscle.stretched = skinMoveAt(clips, plan, pass.moves, m, plan.most_stretched[m], plan.most_stretched[m].ratio > 1.0);
    figures.muscles.push_back(std::move(muscle));
  }
  return measures;
}


DeformationQuality measureDeformationQuality(const Character& character, const std::vector<BodyRegion>& regions,
                                             const std::vector<MeasuredPart>& parts, const MuscleSet& muscles,
                                             const std::vector<MeasuredClip>& clips, int threads) {
  return measureDeformation(character, regions, parts, muscles, clips, true, {}, threads).quality;
}

}  // namespace rigbake
