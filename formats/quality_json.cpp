#include "formats/quality_json.h"

namespace rigbake {
namespace {

nlohmann::json extremeJson(const VolumeExtreme& extreme) {
  return {{"change_percent", 100.0 * extreme.change}, {"time_s", extreme.time}};
}

nlohmann::json volumesJson(const SkinningVolumes& volumes) {
  return {{"input", extremeJson(volumes.input)},
          {"dual_quaternion", extremeJson(volumes.dual_quaternion)},
          {"rig", extremeJson(volumes.rig)}};
}

// A figure of the four skinnings the surface figures compare (fractions), as percent.
nlohmann::json percentPerSkinning(const double (&figure)[kSurfaceSkinnings]) {
  return {{"input", 100.0 * figure[0]}, {"dual_quaternion", 100.0 * figure[1]},
          {"centre_of_rotation", 100.0 * figure[2]}, {"rig", 100.0 * figure[3]}};
}

nlohmann::json moveJson(const MuscleSkinMove& move) {
  if (!move.measured) return nullptr;
  return {{"clip", move.clip},          {"time_s", move.time},
          {"ratio", move.ratio},        {"mean_mm", 1000.0 * move.mean},
          {"max_out_mm", 1000.0 * move.max_out}, {"max_in_mm", 1000.0 * move.max_in},
          {"vertices", move.vertices}};
}

// Where the rig's skin rises most beyond plain skinning's at the roughest sample; null when nowhere.
nlohmann::json lumpJson(const LumpPlace& lump) {
  if (!lump.at.found) return nullptr;
  nlohmann::json out = skinPlaceJson(lump.at);
  out["time_s"] = lump.time;
  out["rig_rise_mm"] = 1000.0 * lump.rig_rise;
  out["input_rise_mm"] = 1000.0 * lump.input_rise;
  return out;
}

// Where the rig takes most of a region's volume against plain skinning, and how much (points of its
// bind volume); beside it the whole difference at that sample, first-order and measured.
nlohmann::json lossPlaceJson(const RegionLossPlace& place) {
  nlohmann::json out = skinPlaceJson(place.at);
  out["time_s"] = place.time;
  out["points"] = place.points;
  out["rig_minus_input_points"] = place.difference_points;
  out["first_order_points"] = place.first_order_points;
  if (place.cut_measured) out["cut_points"] = place.cut_points;
  return out;
}

nlohmann::json contactJson(const CreaseMethodContact& contact) {
  return {{"closest_mm", contact.opposed ? nlohmann::json(1000.0 * contact.closest) : nlohmann::json(nullptr)},
          {"through_vertices", contact.through},
          {"deepest_mm", 1000.0 * contact.deepest}};
}

}  // namespace

nlohmann::json skinPlaceJson(const SkinPlace& place) {
  return {{"mesh", place.mesh},
          {"gltf_mesh", place.gltf_mesh},
          {"primitive", place.gltf_primitive},
          {"vertex", place.vertex},
          {"bind_position", {place.bind.x(), place.bind.y(), place.bind.z()}}};
}

nlohmann::json deformationQualityJson(const DeformationQuality& quality) {
  nlohmann::json body_clips = nlohmann::json::object();
  for (const ClipQuality& clip : quality.clips) body_clips[clip.clip] = volumesJson(clip.body);
  nlohmann::json regions = nlohmann::json::object();
  for (size_t r = 0; r < quality.regions.size(); ++r) {
    nlohmann::json per_clip = nlohmann::json::object();
    for (const ClipQuality& clip : quality.clips) {
      per_clip[clip.clip] = volumesJson(clip.regions[r]);
      if (r < clip.region_places.size() && clip.region_places[r].at.found)
        per_clip[clip.clip]["rig"]["lost_most_at"] = lossPlaceJson(clip.region_places[r]);
    }
    regions[quality.regions[r]] = {{"bind_volume_m3", quality.region_volumes[r]}, {"per_clip", per_clip}};
  }
  nlohmann::json muscles = nlohmann::json::object();
  for (const MuscleQuality& muscle : quality.muscles)
    muscles[muscle.muscle] = {{"kind", partKindName(muscle.kind)},
                              {"compressed", moveJson(muscle.compressed)},
                              {"stretched", moveJson(muscle.stretched)}};
  nlohmann::json seam_clips = nlohmann::json::object();
  for (const ClipQuality& clip : quality.clips)
    seam_clips[clip.clip] = {{"input_mm", 1000.0 * clip.seams.input}, {"rig_mm", 1000.0 * clip.seams.rig}, {"time_s", clip.seams.time}};
  nlohmann::json surface_clips = nlohmann::json::object();
  for (const ClipQuality& clip : quality.clips) {
    if (!clip.surface.measured) continue;
    const double* rise = clip.surface.roughness_rise;
    surface_clips[clip.clip] = {{"roughness_rise_p95_mm",
                                 {{"input", 1000.0 * rise[0]}, {"dual_quaternion", 1000.0 * rise[1]},
                                  {"centre_of_rotation", 1000.0 * rise[2]}, {"rig", 1000.0 * rise[3]}}},
                                {"roughness_floor_mm", 1000.0 * clip.surface.roughness_floor},
                                {"roughness_ratio", roughnessRatio(clip.surface)},
                                {"edge_strain_p95_percent", percentPerSkinning(clip.surface.edge_strain)},
                                {"area_strain_p95_percent", percentPerSkinning(clip.surface.area_strain)},
                                {"centre_of_rotation_volume", extremeJson(clip.surface.centre_of_rotation)},
                                {"lumpiest_at", lumpJson(clip.surface.lumpiest)},
                                {"occupied_volume",
                                 {{"input", extremeJson(clip.surface.occupied[0])},
                                  {"dual_quaternion", extremeJson(clip.surface.occupied[1])},
                                  {"centre_of_rotation", extremeJson(clip.surface.occupied[2])},
                                  {"rig", extremeJson(clip.surface.occupied[3])}}}};
  }
  nlohmann::json crease_clips = nlohmann::json::object();
  for (const ClipQuality& clip : quality.clips) {
    if (clip.creases.empty()) continue;
    nlohmann::json per_crease = nlohmann::json::object();
    for (const CreaseContact& crease : clip.creases) {
      per_crease[crease.crease] = {{"time_s", crease.time},
                                   {"bend_deg", crease.bend * 180.0 / 3.14159265358979323846},
                                   {"input", contactJson(crease.skinning[0])},
                                   {"dual_quaternion", contactJson(crease.skinning[1])},
                                   {"centre_of_rotation", contactJson(crease.skinning[2])},
                                   {"rig", contactJson(crease.skinning[3])}};
    }
    crease_clips[clip.clip] = per_crease;
  }
  nlohmann::json joint_region_clips = nlohmann::json::object();
  for (const ClipQuality& clip : quality.clips) {
    if (clip.joint_regions.size() != quality.joint_regions.size() || clip.joint_regions.empty()) continue;
    nlohmann::json per_joint = nlohmann::json::object();
    for (size_t r = 0; r < clip.joint_regions.size(); ++r) {
      const JointRegionLoss& loss = clip.joint_regions[r];
      per_joint[quality.joint_regions[r]] = {{"input_percent", 100.0 * loss.input},
                                             {"rig_percent", 100.0 * loss.rig},
                                             {"loss_beyond_input_points", 100.0 * loss.loss},
                                             {"time_s", loss.time}};
    }
    joint_region_clips[clip.clip] = per_joint;
  }
  return {{"units", {{"volume", "percent change against the bind pose"},
                     {"skin_move", "mm along the input skinning's normal, + out"},
                     {"seam", "mm, largest distance between skin vertices that share a bind position"},
                     {"roughness", "mm, 95th percentile over the moving skin of |umbrella Laplacian . normal| posed minus bind"},
                     {"joint_region", "the skin whose strongest input joint is the joint, its volume about the joint's posed origin (uncapped): percent change at the sample where the rig loses most beyond the input skinning, and that loss in points"},
                     {"crease", "at the clip's peak bend of each crease: closest approach of opposing skin in mm (null: none within reach), skin vertices through the opposing surface, and the deepest in mm"}}},
          {"seams", {{"places", quality.seam_places}, {"per_clip", seam_clips}}},
          {"surface", {{"per_clip", surface_clips}}},
          {"creases", {{"per_clip", crease_clips}}},
          {"body", {{"bind_volume_m3", quality.body_volume}, {"per_clip", body_clips}}},
          {"regions", regions},
          {"joint_regions", {{"per_clip", joint_region_clips}}},
          {"unmeasured_regions", quality.unmeasured_regions},
          {"muscles", muscles}};
}

}  // namespace rigbake
