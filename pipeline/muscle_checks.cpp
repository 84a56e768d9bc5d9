// The muscle checks of `rigbake validate` (pipeline/checks.h): the landmarks, the muscle locators'
// symmetry and distance to the skin, the muscles' length ratios against their band, the jiggles against
// their cones, and the muscles' skin under compression and stretch. They follow the God of War Ragnarök
// talk's muscle joint group: a muscle's length ratio L / L_rest is clamped to [compression, stretch]
// ("Muscle Joint Group", createFromAttachObjs), so a clip that leaves that band shows a muscle that
// stops following its attach joints.
#include <algorithm>
#include <cmath>
#include <limits>

#include "anatomy/surface_distance.h"
#include "pipeline/check_support.h"
#include "pipeline/parallel.h"

namespace rigbake {
namespace {

struct NamedLocator {
  const char* role;
  const MuscleLocator& (*get)(const MusclePart&);
};

const std::vector<NamedLocator>& locatorRoles() {
  static const std::vector<NamedLocator> kRoles = {
      {"origin", [](const MusclePart& p) -> const MuscleLocator& { return p.origin; }},
      {"insertion", [](const MusclePart& p) -> const MuscleLocator& { return p.insertion; }},
      {"driver", [](const MusclePart& p) -> const MuscleLocator& { return p.driver; }},
  };
  return kRoles;
}

// A muscle's skin along the normal at its most compressed (or most stretched) sample.
CheckResult checkMuscleMove(const ValidationInputs& inputs, const ValidationConfig& config, const CheckDefinition& definition,
                            bool compressed) {
  CheckResult result = startCheck(definition, config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skippedCheck(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.muscles.empty()) return skippedCheck(result, "the file has no RIGBAKE_muscle_rig extension to read muscle lengths from");
  const double height = bodyHeightOf(inputs);
  CheckMeasurement measurement(&result);
  int measured = 0;
  for (const MuscleQuality& muscle : quality.muscles) {
    const MuscleSkinMove& move = compressed ? muscle.compressed : muscle.stretched;
    // A corrective moves its skin in or out as the volume asks: neither check is about it.
    if (!move.measured || muscle.kind == PartKind::kCorrective) continue;
    ++measured;
    measurement.add(move.mean / height, muscle.muscle,
                    "mean " + fixedDecimals(1000.0 * move.mean, 2) + " mm (out " + fixedDecimals(1000.0 * move.max_out, 2) + ", in " +
                        fixedDecimals(1000.0 * move.max_in, 2) + " mm) at length ratio " + fixedDecimals(move.ratio, 3) + ", " +
                        move.clip + " " + fixedDecimals(move.time, 2) + " s");
  }
  if (!result.has_measured) return skippedCheck(result, compressed ? "no muscle is compressed in any clip" : "no muscle is stretched in any clip");
  measurement.finish(std::to_string(measured) + " muscles, smallest mean move " +
                     fixedDecimals(1000.0 * result.measured * height, 2) + " mm");
  return result;
}

}  // namespace

CheckResult checkLandmarksResolved(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("LANDMARKS_RESOLVED")>(), config);
  CheckMeasurement measurement(&result);
  if (!inputs.landmarks) {
    measurement.add(1.0, "", inputs.landmark_problem);
    measurement.finish(inputs.landmark_problem);
    return result;
  }
  int from_joints = 0, derived = 0, unresolved = 0;
  std::string missing;
  for (const auto& [name, landmark] : inputs.landmarks->landmarks) {
    if (!landmark.resolved) {
      ++unresolved;
      missing += (missing.empty() ? "" : ", ") + name;
    } else if (landmark.derived.empty()) {
      ++from_joints;
    } else {
      ++derived;
    }
  }
  // resolveLandmarks() fails on a missing required landmark, so the ones left unresolved are optional.
  measurement.add(0.0, "", "every required landmark resolved");
  measurement.finish(std::to_string(from_joints) + " landmarks from joints, " + std::to_string(derived) +
                     " derived (map " + inputs.landmarks->map_name + ")" +
                     (unresolved ? "; optional ones unresolved: " + missing : std::string()));
  return result;
}

CheckResult checkLocatorSymmetry(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("LOCATOR_SYMMETRY")>(), config);
  if (!inputs.muscles) return skippedCheck(result, kNoMuscleFile);
  if (!inputs.landmarks) return skippedCheck(result, "landmarks did not resolve, so there is no sagittal plane");
  const BodyFrame& body = inputs.landmarks->body;
  const double height = bodyHeightOf(inputs);
  CheckMeasurement measurement(&result);
  int pairs = 0;
  for (const MusclePart& left : inputs.muscles->parts) {
    if (left.side != "Left") continue;
    for (const MusclePart& right : inputs.muscles->parts) {
      if (right.side != "Right" || right.name != left.name) continue;
      ++pairs;
      for (const NamedLocator& role : locatorRoles()) {
        const double distance = (body.mirror(role.get(left).world) - role.get(right).world).norm() / height;
        measurement.add(distance, right.fullName() + "/" + role.role,
                        "mirrored " + left.fullName() + " " + role.role + " is " + fixedDecimals(distance * height, 4) +
                            " from it");
      }
    }
  }
  if (pairs == 0) return skippedCheck(result, "the muscle file has no left/right pairs");
  measurement.finish(std::to_string(pairs) + " left/right pairs, worst " + fixedDecimals(result.measured * 100.0, 2) +
                     "% of body height");
  return result;
}

CheckResult checkLocatorNearSurface(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("LOCATOR_NEAR_SURFACE")>(), config);
  if (!inputs.muscles) return skippedCheck(result, kNoMuscleFile);
  if (!inputs.landmarks) return skippedCheck(result, "landmarks did not resolve, so the body height is unknown");
  const double height = bodyHeightOf(inputs);
  // Each locator against every body triangle: the locators on the threads, then read in order.
  const std::vector<NamedLocator>& roles = locatorRoles();
  const std::vector<MusclePart>& parts = inputs.muscles->parts;
  std::vector<double> distances(parts.size() * roles.size());
  parallelForEach(inputs.threads, distances.size(), [&](size_t i) {
    distances[i] = distanceToBodySurface(*inputs.character, roles[i % roles.size()].get(parts[i / roles.size()]).world);
  });
  CheckMeasurement measurement(&result);
  size_t next = 0;
  for (const MusclePart& part : parts) {
    for (const NamedLocator& role : roles) {
      const double distance = distances[next++];
      if (!std::isfinite(distance)) return skippedCheck(result, "the character has no body mesh");
      measurement.add(distance / height, part.fullName() + "/" + role.role,
                      fixedDecimals(distance, 4) + " from the body surface");
    }
  }
  measurement.finish(std::to_string(inputs.muscles->parts.size() * locatorRoles().size()) + " locators, farthest " +
                     fixedDecimals(result.measured * 100.0, 2) + "% of body height from the surface");
  return result;
}

CheckResult checkMuscleRatioInRange(const ValidationInputs& inputs, const std::vector<ClipRatios>& ratios,
                                    const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("MUSCLE_RATIO_IN_RANGE")>(), config);
  if (!inputs.muscles) return skippedCheck(result, kNoMuscleFile);
  if (inputs.muscles->parts.empty()) return skippedCheck(result, "the muscle file has no muscles");
  CheckMeasurement measurement(&result);
  int samples = 0;
  for (const ClipRatios& clip : ratios) {
    for (const MuscleRatioSeries& series : clip.muscles) {
      // One finding per muscle and clip: its worst sample.
      double worst = std::numeric_limits<double>::max();
      size_t worst_t = 0;
      for (size_t t = 0; t < series.ratio.size(); ++t) {
        const double margin = std::min(series.ratio[t] - series.compression, series.stretch - series.ratio[t]);
        if (margin < worst) {
          worst = margin;
          worst_t = t;
        }
        ++samples;
      }
      if (series.ratio.empty()) continue;
      measurement.add(worst, series.muscle + " @ " + clip.clip,
                      "ratio " + fixedDecimals(series.ratio[worst_t], 4) + " at t=" + fixedDecimals(clip.times[worst_t], 3) +
                          " s, band [" + fixedDecimals(series.compression, 3) + ", " + fixedDecimals(series.stretch, 3) + "]");
    }
  }
  measurement.finish(std::to_string(inputs.muscles->parts.size()) + " muscles over " + std::to_string(ratios.size()) +
                     " clips (" + std::to_string(samples) + " muscle samples), smallest margin " + fixedDecimals(result.measured, 4));
  return result;
}

CheckResult checkJiggleWithinClamp(const ValidationInputs& inputs, const std::vector<ClipJiggles>& clips,
                                   const std::vector<FileIssue>& refused, const ValidationConfig& config) {
  CheckResult result = startCheck(checkAt<checkIndex("JIGGLE_WITHIN_CLAMP")>(), config);
  if (clips.empty() && refused.empty())
    return skippedCheck(result, inputs.file->rig.jiggles.empty()
                               ? std::string("the file has no jiggle: none baked into its clips, none in RIGBAKE_muscle_rig")
                               : "the file's clips have no motion for its runtime jiggles to follow");
  CheckMeasurement measurement(&result);
  // A jiggle the runtime refuses has nothing bounding its angle: it fails at the largest angle there is.
  for (const FileIssue& issue : refused) measurement.add(180.0, issue.pointer, issue.message);
  int samples = 0, jiggles = 0;
  for (const ClipJiggles& clip : clips) {
    for (const JiggleSeries& series : clip.jiggles) {
      ++jiggles;
      double worst = std::numeric_limits<double>::lowest();
      size_t worst_t = 0;
      for (size_t t = 0; t < series.angle_deg.size() && t < series.clamp_deg.size(); ++t) {
        const double over = series.angle_deg[t] - series.clamp_deg[t];
        if (over > worst) {
          worst = over;
          worst_t = t;
        }
        ++samples;
      }
      if (series.angle_deg.empty() || worst_t >= clip.times.size()) continue;
      measurement.add(worst, series.joint + " @ " + clip.clip,
                      "angle " + fixedDecimals(series.angle_deg[worst_t], 4) + " deg at t=" + fixedDecimals(clip.times[worst_t], 3) +
                          " s, cone half-angle there " + fixedDecimals(series.clamp_deg[worst_t], 4) + " deg");
    }
  }
  const bool runtime = inputs.file->jiggles.empty();
  measurement.finish(std::to_string(jiggles) + " jiggle tracks (" + std::to_string(samples) + " samples" +
                     (runtime ? ", the extension's jiggles run by the runtime library" : ", baked into the clips") +
                     (refused.empty() ? "" : "; " + std::to_string(refused.size()) + " refused by the runtime") +
                     "), largest excess over the cone " + fixedDecimals(result.measured, 6) + " deg");
  return result;
}

CheckResult checkMuscleBulgeOutward(const ValidationInputs& inputs, const ValidationConfig& config) {
  return checkMuscleMove(inputs, config, checkAt<checkIndex("MUSCLE_BULGE_OUTWARD")>(), true);
}

CheckResult checkMuscleStretchNoHollow(const ValidationInputs& inputs, const ValidationConfig& config) {
  return checkMuscleMove(inputs, config, checkAt<checkIndex("MUSCLE_STRETCH_NO_HOLLOW")>(), false);
}

}  // namespace rigbake
