// The skin checks of `rigbake validate` (pipeline/checks.h): the influences as the glTF 2.0 skinning
// rules want them (3.7.3.3: weights sum to one, none negative, indices inside the skin), the talk's
// packed 0.001 layout ("Increase Bone Influences per Vertex"), whose cost is measured as a deformation
// error, and the deformation quality of the baked rig against the input skinning
// (docs/deformation-quality.md).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/check_support.h"

namespace rigbake {

CheckResult checkWeightsSum(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("WEIGHTS_SUM")>(), config);
  if (inputs.file->skins.empty()) return skippedCheck(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  CheckMeasurement measurement(&result);
  int vertices = 0;
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    // One finding per primitive: its worst vertex.
    double worst = -1.0;
    int worst_vertex = -1;
    const int count = skin.slots ? static_cast<int>(skin.weights.size()) / skin.slots : 0;
    for (int v = 0; v < count; ++v) {
      double sum = 0.0;
      for (int k = 0; k < skin.slots; ++k) sum += skin.weights[static_cast<size_t>(v) * skin.slots + k];
      const double deviation = std::abs(sum - 1.0);
      if (deviation > worst) {
        worst = deviation;
        worst_vertex = v;
      }
    }
    vertices += count;
    if (worst_vertex >= 0)
      measurement.add(worst, skin.pointer + "/attributes/WEIGHTS_0", "vertex " + std::to_string(worst_vertex) +
                                                                          " sums to 1 " + (worst >= 0 ? "+/- " : "") +
                                                                          fixedDecimals(worst, 6));
  }
  measurement.finish(std::to_string(vertices) + " vertices, largest |sum - 1| " + fixedDecimals(result.measured, 6));
  return result;
}

CheckResult checkWeightsNonNegative(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("WEIGHTS_NON_NEGATIVE")>(), config);
  if (inputs.file->skins.empty()) return skippedCheck(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  CheckMeasurement measurement(&result);
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    double lowest = std::numeric_limits<double>::max();
    size_t at = 0;
    for (size_t i = 0; i < skin.weights.size(); ++i) {
      if (skin.weights[i] < lowest) {
        lowest = skin.weights[i];
        at = i;
      }
    }
    if (skin.weights.empty()) continue;
    const int set = static_cast<int>((at % skin.slots) / 4);
    measurement.add(lowest, skin.pointer + "/attributes/WEIGHTS_" + std::to_string(set),
                    "vertex " + std::to_string(at / skin.slots) + " slot " + std::to_string(at % skin.slots) +
                        " weighs " + fixedDecimals(lowest, 6));
  }
  measurement.finish("smallest weight " + fixedDecimals(result.measured, 6));
  return result;
}

CheckResult checkJointIndexInRange(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("JOINT_INDEX_IN_RANGE")>(), config);
  if (inputs.file->skins.empty()) return skippedCheck(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  CheckMeasurement measurement(&result);
  int largest = -1;
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    auto count = [&](const std::vector<int>& joints, const std::string& where) {
      int out_of_range = 0, first = -1;
      for (size_t i = 0; i < joints.size(); ++i) {
        largest = std::max(largest, joints[i]);
        if (joints[i] < 0 || joints[i] >= skin.skin_joint_count) {
          if (first < 0) first = static_cast<int>(i);
          ++out_of_range;
        }
      }
      measurement.add(out_of_range, where,
                      out_of_range == 0 ? "every index below the skin's " + std::to_string(skin.skin_joint_count) + " joints"
                                        : std::to_string(out_of_range) + " indices outside the skin's " +
                                              std::to_string(skin.skin_joint_count) + " joints, first in slot " +
                                              std::to_string(first));
    };
    count(skin.joints, skin.pointer + "/attributes/JOINTS_0");
    if (skin.has_packed) {
      // The packed decoder itself rejects out-of-range indices; read them raw so they are counted.
      std::vector<int> packed_joints;
      const int stride = packedIndexStride(skin.packed.influences, skin.packed.index_bytes);
      for (int v = 0; v < skin.packed.vertex_count; ++v) {
        for (int k = 0; k < skin.packed.influences; ++k) {
          const size_t at = static_cast<size_t>(v) * stride + static_cast<size_t>(k) * skin.packed.index_bytes;
          int index = skin.packed.indices[at];
          if (skin.packed.index_bytes == 2) index |= skin.packed.indices[at + 1] << 8;
          packed_joints.push_back(index);
        }
      }
      count(packed_joints, skin.pointer + "/attributes/_RIGBAKE_PACKED_JOINTS_0");
    }
  }
  measurement.finish("largest joint index " + std::to_string(largest));
  return result;
}

CheckResult checkInfluenceCount(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("INFLUENCE_COUNT")>(), config);
  if (inputs.file->skins.empty()) return skippedCheck(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  CheckMeasurement measurement(&result);
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    int most = 0, at = -1;
    const int count = skin.slots ? static_cast<int>(skin.weights.size()) / skin.slots : 0;
    for (int v = 0; v < count; ++v) {
      int n = 0;
      for (int k = 0; k < skin.slots; ++k) n += skin.weights[static_cast<size_t>(v) * skin.slots + k] != 0.0;
      if (n > most) {
        most = n;
        at = v;
      }
    }
    measurement.add(most, skin.pointer, std::to_string(skin.slots) + " slots, vertex " + std::to_string(at) + " uses " +
                                            std::to_string(most));
  }
  measurement.finish("at most " + fixedDecimals(result.measured, 0) + " influences per vertex");
  return result;
}

CheckResult checkPackedDeformationError(const ValidationInputs& inputs, const std::vector<ClipDeformation>& per_clip,
                                        const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("PACKED_DEFORMATION_ERROR")>(), config);
  bool any_packed = false;
  for (const FileSkinAttributes& skin : inputs.file->skins) any_packed = any_packed || skin.has_packed;
  if (!any_packed) return skippedCheck(result, "the file has no decodable _RIGBAKE_PACKED_* attributes");
  if (per_clip.empty()) return skippedCheck(result, "no primitive has in-range joint indices to skin with");
  CheckMeasurement measurement(&result);
  for (const ClipDeformation& clip : per_clip) {
    measurement.add(clip.max_displacement, clip.clip,
                    "max " + fixedDecimals(clip.max_displacement * 1000.0, 4) + " mm, rms " +
                        fixedDecimals(clip.rms_displacement * 1000.0, 4) + " mm over " + std::to_string(clip.samples) +
                        " samples");
  }
  measurement.finish(std::to_string(per_clip.size()) + " clips, largest displacement " +
                     fixedDecimals(result.measured * 1000.0, 4) + " mm");
  return result;
}

CheckResult checkRegionVolumeLoss(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("SKIN_REGION_VOLUME_LOSS")>(), config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skippedCheck(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.regions.empty()) return skippedCheck(result, "no body region is measurable on this mesh");
  CheckMeasurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    for (size_t r = 0; r < clip.regions.size(); ++r) {
      const SkinningVolumes& v = clip.regions[r];
      const std::string place = r < clip.region_places.size() ? regionLossPlaceText(clip.region_places[r]) : "";
      measurement.add(regionLossBeyondInput(v), clip.clip + "/" + quality.regions[r],
                      "input skinning " + fixedDecimals(100.0 * v.input.change, 2) + " %, dual quaternions " +
                          fixedDecimals(100.0 * v.dual_quaternion.change, 2) + " %, rig " + fixedDecimals(100.0 * v.rig.change, 2) +
                          " % at " + fixedDecimals(v.rig.time, 2) + " s" + (place.empty() ? "" : "; " + place));
    }
  }
  measurement.finish(std::to_string(quality.regions.size()) + " regions over " + std::to_string(quality.clips.size()) +
                     " clips, largest loss beyond the input's " + fixedDecimals(result.measured, 2) + " points");
  return result;
}

CheckResult checkSeamOpening(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("SKIN_SEAM_OPEN")>(), config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skippedCheck(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.seam_places == 0) return skippedCheck(result, "no two skinned vertices share a bind position");
  CheckMeasurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    // What the rig opens beyond the input: where the input itself gives a place two skins, it opens too.
    measurement.add(1000.0 * std::max(0.0, clip.seams.rig - clip.seams.input), clip.clip,
                    "input skinning " + fixedDecimals(1000.0 * clip.seams.input, 4) + " mm, rig " + fixedDecimals(1000.0 * clip.seams.rig, 4) +
                        " mm at " + fixedDecimals(clip.seams.time, 2) + " s");
  }
  measurement.finish(std::to_string(quality.seam_places) + " shared places over " + std::to_string(quality.clips.size()) +
                     " clips, largest opening beyond the input's " + fixedDecimals(result.measured, 4) + " mm");
  return result;
}

// A per-clip check over the skin's surface figures, which only the clips with samples have:
// `measure(clip, &measurement)` adds a clip's finding, `summary(clips, measured)` is the check's line.
template <typename Measure, typename Summary>
CheckResult surfaceCheck(const CheckDefinition& definition, const ValidationInputs& inputs, const ValidationConfig& config,
                         Measure measure, Summary summary) {
  CheckResult result = startCheck(definition, config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skippedCheck(result, why);
  CheckMeasurement measurement(&result);
  int measured = 0;
  for (const ClipQuality& clip : inputs.quality->quality.clips) {
    if (!clip.surface.measured) continue;
    ++measured;
    measure(clip, &measurement);
  }
  if (measured == 0) return skippedCheck(result, "no clip was measured");
  measurement.finish(summary(measured, result.measured));
  return result;
}

// A surface figure of the four skinnings for a finding: "input 1.234 mm, dual quaternions ..., rig ...".
std::string perSkinning(const double (&figure)[kSurfaceSkinnings], double scale, int decimals, const std::string& unit) {
  static const char* const kNames[kSurfaceSkinnings] = {"input ", ", dual quaternions ", ", centres of rotation ", ", rig "};
  std::string text;
  for (int s = 0; s < kSurfaceSkinnings; ++s) text += kNames[s] + fixedDecimals(scale * figure[s], decimals) + " " + unit;
  return text;
}

CheckResult checkRoughnessRise(const ValidationInputs& inputs, const ValidationConfig& config) {
  return surfaceCheck(
      checkAt<checkIndex("SKIN_ROUGHNESS_RISE")>(), inputs, config,
      [](const ClipQuality& clip, CheckMeasurement* measurement) {
        measurement->add(roughnessRatio(clip.surface), clip.clip,
                         "roughness rise (95th percentile) " + perSkinning(clip.surface.roughness_rise, 1000.0, 3, "mm") +
                             (clip.surface.lumpiest.at.found ? "; " + lumpPlaceText(clip.surface.lumpiest) : std::string()));
      },
      [](int clips, double measured) {
        return std::to_string(clips) + " clips, the rig's roughness rise at most " + fixedDecimals(measured, 2) + " x the input skinning's";
      });
}

// Skin stretched or squashed where plain skinning keeps it (docs/deformation-quality.md, "Strain"): the
// larger of the edge-length and triangle-area ratios.
CheckResult checkStrain(const ValidationInputs& inputs, const ValidationConfig& config) {
  return surfaceCheck(
      checkAt<checkIndex("SKIN_STRAIN")>(), inputs, config,
      [](const ClipQuality& clip, CheckMeasurement* measurement) {
        measurement->add(strainRatio(clip.surface), clip.clip,
                         "strain (95th percentile) of edge lengths " + perSkinning(clip.surface.edge_strain, 100.0, 2, "%") +
                             "; of triangle areas " + perSkinning(clip.surface.area_strain, 100.0, 2, "%"));
      },
      [](int clips, double measured) {
        return std::to_string(clips) + " clips, the rig's strain at most " + fixedDecimals(measured, 2) + " x the input skinning's";
      });
}

CheckResult checkBodyVolume(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("SKIN_BODY_VOLUME")>(), config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skippedCheck(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  CheckMeasurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    const SkinningVolumes& v = clip.body;
    measurement.add(100.0 * (std::abs(v.rig.change) - std::abs(v.input.change)), clip.clip,
                    "input skinning " + fixedDecimals(100.0 * v.input.change, 2) + " %, dual quaternions " +
                        fixedDecimals(100.0 * v.dual_quaternion.change, 2) + " %, rig " + fixedDecimals(100.0 * v.rig.change, 2) + " %");
  }
  measurement.finish(std::to_string(quality.clips.size()) + " clips, rig against input skinning at most " +
                     fixedDecimals(result.measured, 2) + " points");
  return result;
}

// The whole body's volume counting each point inside the skin once: the signed volume above counts skin
// pushed into a fold twice, so a rig can keep it by swelling into the fold (docs/deformation-quality.md,
// "Occupied volume").
CheckResult checkOccupiedVolume(const ValidationInputs& inputs, const ValidationConfig& config) {
  return surfaceCheck(
      checkAt<checkIndex("SKIN_OCCUPIED_VOLUME")>(), inputs, config,
      [](const ClipQuality& clip, CheckMeasurement* measurement) {
        const VolumeExtreme* v = clip.surface.occupied;
        measurement->add(100.0 * (std::abs(v[3].change) - std::abs(v[0].change)), clip.clip,
                         "occupied volume input skinning " + fixedDecimals(100.0 * v[0].change, 2) + " %, dual quaternions " +
                             fixedDecimals(100.0 * v[1].change, 2) + " %, centres of rotation " + fixedDecimals(100.0 * v[2].change, 2) +
                             " %, rig " + fixedDecimals(100.0 * v[3].change, 2) + " % at " + fixedDecimals(v[3].time, 2) +
                             " s (signed: input " + fixedDecimals(100.0 * clip.body.input.change, 2) + " %, rig " +
                             fixedDecimals(100.0 * clip.body.rig.change, 2) + " %)");
      },
      [](int clips, double measured) {
        return std::to_string(clips) + " clips, rig against input skinning at most " + fixedDecimals(measured, 2) + " points";
      });
}

}  // namespace rigbake
