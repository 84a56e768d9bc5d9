#include "formats/bake_stats_json.h"

#include <nlohmann/json.hpp>

#include "formats/json_text.h"
#include "formats/quality_json.h"
#include "formats/rom_json.h"
#include "pipeline/memory_table.h"

namespace rigbake {
namespace {

nlohmann::json errorJson(const DeformationError& error) {
  return {{"max", error.max_displacement * 1000.0}, {"rms", error.rms_displacement * 1000.0}};
}

// Where to look in the input file, as every skin place is named (skinPlaceJson(): mesh, primitive,
// vertex and bind position), and when in which clip.
nlohmann::json peakJson(const Character& character, const BakedClip& clip, const ErrorPeak& peak) {
  if (peak.vertex < 0) return nullptr;
  nlohmann::json out = skinPlaceJson(skinPlace(character, peak.mesh_part, peak.vertex));
  out["clip"] = clip.name;
  out["time_s"] = peak.time;
  return out;
}

// max, rms, worst and per_clip of one set of rounded weights.
nlohmann::json deformationJson(const Character& character, const BakeResult& bake, const DeformationFigures& figures) {
  nlohmann::json per_clip = nlohmann::json::object();
  for (size_t c = 0; c < bake.clips.size(); ++c) {
    per_clip[bake.clips[c].name] = errorJson(figures.per_clip[c]);
    per_clip[bake.clips[c].name]["worst"] = peakJson(character, bake.clips[c], figures.peaks[c]);
  }
  nlohmann::json error = errorJson(figures.overall);
  error["worst"] = figures.peak_clip < 0
                       ? nlohmann::json()
                       : peakJson(character, bake.clips[figures.peak_clip], figures.peaks[figures.peak_clip]);
  error["per_clip"] = per_clip;
  return error;
}

}  // namespace

SkinBytesPerVertex skinBytesPerVertex(const BakeResult& bake) {
  SkinBytesPerVertex bytes;
  if (bake.parts.empty()) return bytes;
  const BakedPart& first = bake.parts.front();
  for (const VertexAttributeData& a : first.standard) bytes.gltf += static_cast<int>(a.bytes.size() / a.accessor.count);
  bytes.packed = packedSkinBytesPerVertex(bake.influences, first.packed.index_bytes);
  return bytes;
}

int jointsAdded(const BakeResult& bake) {
  return static_cast<int>(bake.helper_joints ? bake.joints.size() : bake.muscles.parts.size());
}

std::string bakeStatsJson(const BakeStatsInputs& in) {
  const Character& character = *in.character;
  const BakeResult& bake = *in.bake;
  const SkinBytesPerVertex bytes = skinBytesPerVertex(bake);
  nlohmann::json table = nlohmann::json::array();
  for (const SkinLayoutSize& layout : skinMemoryTable(bake.vertex_count)) {
    table.push_back({{"layout", layout.id},
                     {"influences", layout.influences},
                     {"bytes_per_vertex", layout.bytes_per_vertex},
                     {"total_bytes", layout.total_bytes}});
  }
  nlohmann::json stats = {
      {"character", in.character_file},
      {"output", in.output_file},
      {"units", "m"},
      {"influences", bake.influences},
      {"muscle_joints", bake.muscles.parts.size()},
      {"joints_added", jointsAdded(bake)},
      {"vertices", bake.vertex_count},
      {"rigid_piece_vertices", bake.rigid_piece_vertices},
      {"clips", bake.clips.size()},
      {"deformation_error_mm", deformationJson(character, bake, bake.error)},
      {"gltf_weights", gltfWeightsName(bake.gltf_weights)},
      {"bytes_per_vertex", {{"gltf", bytes.gltf}, {"packed", bytes.packed}}},
      {"bytes_total", {{"gltf", static_cast<long long>(bytes.gltf) * bake.vertex_count},
                       {"packed", static_cast<long long>(bytes.packed) * bake.vertex_count}}},
      {"memory_table", table},
  };
  if (bake.gltf_weights == GltfWeights::kUnorm16) stats["gltf_deformation_error_mm"] = deformationJson(character, bake, bake.gltf_error);
  stats["deformation_quality"] = deformationQualityJson(bake.quality);
  if (in.rom) stats["rom"] = romJson(*in.rom, character.skeleton);
  const LegCoverage& legs = *in.legs;
  stats["legs"] = {{"found", legs.legs}, {"covered_by_muscles", legs.covered}, {"largest_turn_deg", legs.largest_turn_deg},
                   {"clip", legs.clip}, {"joint", legs.joint}};
  stats["animation_bytes"] = {{"input", in.file->input_animation_bytes}, {"output", in.file->animation_bytes},
                              {"muscle_motion", muscleMotionName(bake.motion)}};
  return jsonText(stats) + "\n";
}

}  // namespace rigbake
