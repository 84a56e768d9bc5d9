// The checks of `rigbake validate`. Organised like the Khronos glTF-Validator (stable issue codes with
// a default severity, every check always runs, each result says where): a CI job can gate on error
// severity and keep the warnings as a trend. The muscle checks follow the God of War Ragnarök talk's
// muscle joint group: a muscle's length ratio L / L_rest is clamped to [compression, stretch]
// ("Muscle Joint Group", createFromAttachObjs), so a clip that leaves that band shows a muscle that
// stops following its attach joints. The influence checks are the glTF 2.0 skinning rules (3.7.3.3:
// weights sum to one, none negative, indices inside the skin) plus the talk's packed 0.001 layout
// ("Increase Bone Influences per Vertex"), whose cost is measured as a deformation error.
#include "pipeline/checks.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "anatomy/surface_distance.h"
#include "pipeline/deformation_error.h"
#include "pipeline/influences.h"
#include "pipeline/muscle_joint.h"
#include "pipeline/parallel.h"
#include "pipeline/pose.h"

namespace rigbake {

const char* severityName(Severity severity) {
  switch (severity) {
    case Severity::kError: return "error";
    case Severity::kWarning: return "warning";
    case Severity::kInfo: return "info";
  }
  return "error";
}

const char* statusName(CheckStatus status) {
  switch (status) {
    case CheckStatus::kPass: return "pass";
    case CheckStatus::kFail: return "fail";
    case CheckStatus::kSkipped: return "skipped";
  }
  return "fail";
}

bool parseSeverity(const std::string& name, Severity* severity) {
  for (Severity s : {Severity::kError, Severity::kWarning, Severity::kInfo}) {
    if (name == severityName(s)) {
      *severity = s;
      return true;
    }
  }
  return false;
}

const std::vector<CheckDefinition>& checkDefinitions() {
  // Thresholds relative to body height keep one default meaningful for a 1.2 m robot and a 1.9 m
  // soldier, whatever the file's units.
  static const std::vector<CheckDefinition> kDefinitions = {
      {"LANDMARKS_RESOLVED", Severity::kError, 0.0, Comparison::kAtMost, "landmarks",
       "Required canonical landmarks that match no joint and cannot be derived"},
      {"LOCATOR_SYMMETRY", Severity::kWarning, 0.02, Comparison::kAtMost, "x body height",
       "Largest distance between a left locator mirrored across the sagittal plane and its right twin"},
      {"LOCATOR_NEAR_SURFACE", Severity::kError, 0.1, Comparison::kAtMost, "x body height",
       "Largest distance from a muscle locator (origin, insertion, driver) to the body surface"},
      // A warning by default: past its band the skinned joint saturates, as the talk's clamp intends,
      // so the file is usable; a studio that wants every clip inside sets it to error in --config.
      {"MUSCLE_RATIO_IN_RANGE", Severity::kWarning, 0.0, Comparison::kAtLeast, "ratio",
       "Smallest margin of a muscle's length ratio inside [compression, stretch] over every clip sample"},
      {"WEIGHTS_SUM", Severity::kError, 0.001, Comparison::kAtMost, "weight",
       "Largest |sum of a vertex's WEIGHTS_n - 1|"},
      {"WEIGHTS_NON_NEGATIVE", Severity::kError, 0.0, Comparison::kAtLeast, "weight",
       "Smallest skin weight in WEIGHTS_n"},
      {"JOINT_INDEX_IN_RANGE", Severity::kError, 0.0, Comparison::kAtMost, "indices",
       "JOINTS_n and packed joint indices at or above the skin's joint count"},
      {"INFLUENCE_COUNT", Severity::kError, 10.0, Comparison::kAtMost, "influences",
       "Most non-zero influences on one vertex"},
      {"PACKED_DEFORMATION_ERROR", Severity::kError, 0.0005, Comparison::kAtMost, "m",
       "Largest displacement between skinning with the packed weights and with WEIGHTS_n, over every clip sample"},
      {"JIGGLE_WITHIN_CLAMP", Severity::kError, 1e-6, Comparison::kAtMost, "deg",
       "Largest amount by which a baked jiggle's angle exceeds its cone's half-angle, over every clip sample"},
      // Deformation quality (docs/deformation-quality.md), on the file's own clips and any --rom clips.
      {"SKIN_REGION_VOLUME_LOSS", Severity::kError, 1.0, Comparison::kAtMost, "points of volume",
       "Largest volume a body region loses under the baked rig beyond what the input skinning loses, per clip"},
      {"SKIN_SEAM_OPEN", Severity::kError, 0.05, Comparison::kAtMost, "mm",
       "Largest amount by which skin vertices sharing a bind position move apart under the rig beyond the input skinning, per clip"},
      {"SKIN_ROUGHNESS_RISE", Severity::kWarning, 1.2, Comparison::kAtMost, "x plain skinning's",
       "Largest ratio, per clip, of the rig's roughness rise over the bind pose (95th percentile of the moving skin) to the input skinning's"},
      {"SKIN_BODY_VOLUME", Severity::kWarning, 0.0, Comparison::kAtMost, "points of volume",
       "Largest amount by which the rig's whole-body volume change exceeds the input skinning's, per clip"},
      {"MUSCLE_BULGE_OUTWARD", Severity::kWarning, -0.0005, Comparison::kAtLeast, "x body height",
       "Smallest mean move of a muscle's skin along the normal at its most compressed sample (positive: out)"},
      {"MUSCLE_STRETCH_NO_HOLLOW", Severity::kWarning, -0.001, Comparison::kAtLeast, "x body height",
       "Smallest mean move of a muscle's skin along the normal at its most stretched sample (negative: a hollow)"},
      // Issue 31: tools that do not know rigbake (gltfpack, glTF-Transform without rigbake's config) drop
      // the extension or cut the influences without an error; a CI gate must see it.
      {"RIG_EXTENSION_MISSING", Severity::kError, 0.0, Comparison::kAtMost, "joints",
       "Muscle joints that neither the RIGBAKE_muscle_rig extension nor every clip's channels drive (a tool stripped the rig)"},
      {"INFLUENCES_TRUNCATED", Severity::kError, 0.0, Comparison::kAtMost, "vertices",
       "Vertices whose JOINTS_n/WEIGHTS_n hold fewer influences than the packed buffers (a tool cut them)"},
      {"GLTF_STRUCTURE", Severity::kError, 0.0, Comparison::kAtMost, "issues",
       "Structural problems: accessor counts and types, skins, muscle joint nodes and their animation"},
      {"KHRONOS_VALIDATOR", Severity::kError, 0.0, Comparison::kAtMost, "errors",
       "Errors the Khronos glTF-Validator reports"},
  };
  return kDefinitions;
}

const CheckDefinition* findCheckDefinition(const std::string& code) {
  for (const CheckDefinition& definition : checkDefinitions()) {
    if (code == definition.code) return &definition;
  }
  return nullptr;
}

bool Report::passed() const {
  for (const CheckResult& check : checks) {
    if (check.severity == Severity::kError && check.status == CheckStatus::kFail) return false;
  }
  return true;
}

namespace {

CheckResult startCheck(const std::string& code, const ValidationConfig& config) {
  const CheckDefinition* definition = findCheckDefinition(code);
  assert(definition);
  CheckResult result;
  result.code = code;
  result.title = definition->title;
  result.severity = definition->severity;
  result.threshold = definition->threshold;
  result.comparison = definition->comparison;
  result.unit = definition->unit;
  auto severity = config.severity.find(code);
  if (severity != config.severity.end()) result.severity = severity->second;
  auto threshold = config.threshold.find(code);
  if (threshold != config.threshold.end()) result.threshold = threshold->second;
  return result;
}

bool withinThreshold(const CheckResult& result, double value) {
  return result.comparison == Comparison::kAtMost ? value <= result.threshold : value >= result.threshold;
}

CheckResult skipped(CheckResult result, const std::string& reason) {
  result.status = CheckStatus::kSkipped;
  result.message = reason;
  return result;
}

// Records `value` at `location` as a finding and keeps the worst value as the check's measurement.
class Measurement {
 public:
  explicit Measurement(CheckResult* result) : result_(result) {}

  void add(double value, const std::string& location, const std::string& message) {
    const bool worse = !result_->has_measured || (result_->comparison == Comparison::kAtMost ? value > result_->measured
                                                                                             : value < result_->measured);
    if (worse) {
      result_->has_measured = true;
      result_->measured = value;
      result_->location = location;
    }
    if (!withinThreshold(*result_, value)) ++failing_;
    candidates_.push_back({location, value, message});
  }

  // Sets status and keeps the worst kMaxFindings findings (failing ones sort first because they are worst).
  void finish(const std::string& summary) {
    const bool at_most = result_->comparison == Comparison::kAtMost;
    std::stable_sort(candidates_.begin(), candidates_.end(), [at_most](const CheckFinding& a, const CheckFinding& b) {
      return at_most ? a.measured > b.measured : a.measured < b.measured;
    });
    if (candidates_.size() > static_cast<size_t>(kMaxFindings)) candidates_.resize(kMaxFindings);
    result_->findings = std::move(candidates_);
    result_->status = failing_ == 0 ? CheckStatus::kPass : CheckStatus::kFail;
    result_->message = summary;
    if (failing_ > 0) result_->message += " (" + std::to_string(failing_) + " over the threshold)";
  }

 private:
  CheckResult* result_;
  std::vector<CheckFinding> candidates_;
  int failing_ = 0;
};

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

double bodyHeightOf(const ValidationInputs& inputs) {
  return inputs.landmarks && inputs.landmarks->body.height > 0.0 ? inputs.landmarks->body.height : 1.0;
}

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

Pose poseAt(const Skeleton& skeleton, const SampledClip& clip, double time) {
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

CheckResult checkLandmarksResolved(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("LANDMARKS_RESOLVED", config);
  Measurement measurement(&result);
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
  CheckResult result = startCheck("LOCATOR_SYMMETRY", config);
  if (!inputs.muscles) return skipped(result, "no muscle file given (--muscles)");
  if (!inputs.landmarks) return skipped(result, "landmarks did not resolve, so there is no sagittal plane");
  const BodyFrame& body = inputs.landmarks->body;
  const double height = bodyHeightOf(inputs);
  Measurement measurement(&result);
  int pairs = 0;
  for (const MusclePart& left : inputs.muscles->parts) {
    if (left.side != "Left") continue;
    for (const MusclePart& right : inputs.muscles->parts) {
      if (right.side != "Right" || right.name != left.name) continue;
      ++pairs;
      for (const NamedLocator& role : locatorRoles()) {
        const double distance = (body.mirror(role.get(left).world) - role.get(right).world).norm() / height;
        measurement.add(distance, right.fullName() + "/" + role.role,
                        "mirrored " + left.fullName() + " " + role.role + " is " + fixed(distance * height, 4) +
                            " from it");
      }
    }
  }
  if (pairs == 0) return skipped(result, "the muscle file has no left/right pairs");
  measurement.finish(std::to_string(pairs) + " left/right pairs, worst " + fixed(result.measured * 100.0, 2) +
                     "% of body height");
  return result;
}

CheckResult checkLocatorNearSurface(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("LOCATOR_NEAR_SURFACE", config);
  if (!inputs.muscles) return skipped(result, "no muscle file given (--muscles)");
  if (!inputs.landmarks) return skipped(result, "landmarks did not resolve, so the body height is unknown");
  const double height = bodyHeightOf(inputs);
  // Each locator against every body triangle: the locators on the threads, then read in order.
  const std::vector<NamedLocator>& roles = locatorRoles();
  const std::vector<MusclePart>& parts = inputs.muscles->parts;
  std::vector<double> distances(parts.size() * roles.size());
  parallelForEach(inputs.threads, distances.size(), [&](size_t i) {
    distances[i] = distanceToBodySurface(*inputs.character, roles[i % roles.size()].get(parts[i / roles.size()]).world);
  });
  Measurement measurement(&result);
  size_t next = 0;
  for (const MusclePart& part : parts) {
    for (const NamedLocator& role : roles) {
      const double distance = distances[next++];
      if (!std::isfinite(distance)) return skipped(result, "the character has no body mesh");
      measurement.add(distance / height, part.fullName() + "/" + role.role,
                      fixed(distance, 4) + " from the body surface");
    }
  }
  measurement.finish(std::to_string(inputs.muscles->parts.size() * locatorRoles().size()) + " locators, farthest " +
                     fixed(result.measured * 100.0, 2) + "% of body height from the surface");
  return result;
}

CheckResult checkMuscleRatioInRange(const ValidationInputs& inputs, const std::vector<ClipRatios>& ratios,
                                    const ValidationConfig& config) {
  CheckResult result = startCheck("MUSCLE_RATIO_IN_RANGE", config);
  if (!inputs.muscles) return skipped(result, "no muscle file given (--muscles)");
  if (inputs.muscles->parts.empty()) return skipped(result, "the muscle file has no muscles");
  Measurement measurement(&result);
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
                      "ratio " + fixed(series.ratio[worst_t], 4) + " at t=" + fixed(clip.times[worst_t], 3) +
                          " s, band [" + fixed(series.compression, 3) + ", " + fixed(series.stretch, 3) + "]");
    }
  }
  measurement.finish(std::to_string(inputs.muscles->parts.size()) + " muscles over " + std::to_string(ratios.size()) +
                     " clips (" + std::to_string(samples) + " muscle samples), smallest margin " + fixed(result.measured, 4));
  return result;
}

CheckResult checkJiggleWithinClamp(const ValidationInputs& inputs, const std::vector<ClipJiggles>& clips,
                                   const std::vector<FileIssue>& refused, const ValidationConfig& config) {
  CheckResult result = startCheck("JIGGLE_WITHIN_CLAMP", config);
  if (clips.empty() && refused.empty())
    return skipped(result, inputs.file->rig.jiggles.empty()
                               ? "the file has no jiggle (bake --jiggle): none baked into its clips, none in " +
                                     std::string("RIGBAKE_muscle_rig")
                               : "the file's clips have no motion for its runtime jiggles to follow");
  Measurement measurement(&result);
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
                      "angle " + fixed(series.angle_deg[worst_t], 4) + " deg at t=" + fixed(clip.times[worst_t], 3) +
                          " s, cone half-angle there " + fixed(series.clamp_deg[worst_t], 4) + " deg");
    }
  }
  const bool runtime = inputs.file->jiggles.empty();
  measurement.finish(std::to_string(jiggles) + " jiggle tracks (" + std::to_string(samples) + " samples" +
                     (runtime ? ", the extension's jiggles run by the runtime library" : ", baked into the clips") +
                     (refused.empty() ? "" : "; " + std::to_string(refused.size()) + " refused by the runtime") +
                     "), largest excess over the cone " + fixed(result.measured, 6) + " deg");
  return result;
}

CheckResult checkWeightsSum(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("WEIGHTS_SUM", config);
  if (inputs.file->skins.empty()) return skipped(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  Measurement measurement(&result);
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
                                                                          fixed(worst, 6));
  }
  measurement.finish(std::to_string(vertices) + " vertices, largest |sum - 1| " + fixed(result.measured, 6));
  return result;
}

CheckResult checkWeightsNonNegative(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("WEIGHTS_NON_NEGATIVE", config);
  if (inputs.file->skins.empty()) return skipped(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  Measurement measurement(&result);
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
                        " weighs " + fixed(lowest, 6));
  }
  measurement.finish("smallest weight " + fixed(result.measured, 6));
  return result;
}

CheckResult checkJointIndexInRange(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("JOINT_INDEX_IN_RANGE", config);
  if (inputs.file->skins.empty()) return skipped(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  Measurement measurement(&result);
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
  CheckResult result = startCheck("INFLUENCE_COUNT", config);
  if (inputs.file->skins.empty()) return skipped(result, "the file has no skinned primitive with JOINTS_0/WEIGHTS_0");
  Measurement measurement(&result);
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
  measurement.finish("at most " + fixed(result.measured, 0) + " influences per vertex");
  return result;
}

CheckResult checkPackedDeformationError(const ValidationInputs& inputs, const std::vector<ClipDeformation>& per_clip,
                                        const ValidationConfig& config) {
  CheckResult result = startCheck("PACKED_DEFORMATION_ERROR", config);
  bool any_packed = false;
  for (const FileSkinAttributes& skin : inputs.file->skins) any_packed = any_packed || skin.has_packed;
  if (!any_packed) return skipped(result, "the file has no decodable _RIGBAKE_PACKED_* attributes");
  if (per_clip.empty()) return skipped(result, "no primitive has in-range joint indices to skin with");
  Measurement measurement(&result);
  for (const ClipDeformation& clip : per_clip) {
    measurement.add(clip.max_displacement, clip.clip,
                    "max " + fixed(clip.max_displacement * 1000.0, 4) + " mm, rms " +
                        fixed(clip.rms_displacement * 1000.0, 4) + " mm over " + std::to_string(clip.samples) +
                        " samples");
  }
  measurement.finish(std::to_string(per_clip.size()) + " clips, largest displacement " +
                     fixed(result.measured * 1000.0, 4) + " mm");
  return result;
}

// Why a deformation-quality check cannot run, or "" when it can.
static std::string qualitySkip(const ValidationInputs& inputs) {
  if (!inputs.quality) return inputs.landmarks ? "deformation quality was not measured" : "landmarks did not resolve";
  if (!inputs.quality->measured) return inputs.quality->skip_reason;
  return "";
}

CheckResult checkRegionVolumeLoss(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("SKIN_REGION_VOLUME_LOSS", config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skipped(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.regions.empty()) return skipped(result, "no body region is measurable on this mesh");
  Measurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    for (size_t r = 0; r < clip.regions.size(); ++r) {
      const SkinningVolumes& v = clip.regions[r];
      // Loss beyond the input's own: what the rig loses below min(input change, 0), in points.
      const double loss = std::max(0.0, 100.0 * (std::min(v.input.change, 0.0) - v.rig.change));
      measurement.add(loss, clip.clip + "/" + quality.regions[r],
                      "input skinning " + fixed(100.0 * v.input.change, 2) + " %, dual quaternions " +
                          fixed(100.0 * v.dual_quaternion.change, 2) + " %, rig " + fixed(100.0 * v.rig.change, 2) +
                          " % at " + fixed(v.rig.time, 2) + " s");
    }
  }
  measurement.finish(std::to_string(quality.regions.size()) + " regions over " + std::to_string(quality.clips.size()) +
                     " clips, largest loss beyond the input's " + fixed(result.measured, 2) + " points");
  return result;
}

CheckResult checkSeamOpening(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("SKIN_SEAM_OPEN", config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skipped(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.seam_places == 0) return skipped(result, "no two skinned vertices share a bind position");
  Measurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    // What the rig opens beyond the input: where the input itself gives a place two skins, it opens too.
    measurement.add(1000.0 * std::max(0.0, clip.seams.rig - clip.seams.input), clip.clip,
                    "input skinning " + fixed(1000.0 * clip.seams.input, 4) + " mm, rig " + fixed(1000.0 * clip.seams.rig, 4) +
                        " mm at " + fixed(clip.seams.time, 2) + " s");
  }
  measurement.finish(std::to_string(quality.seam_places) + " shared places over " + std::to_string(quality.clips.size()) +
                     " clips, largest opening beyond the input's " + fixed(result.measured, 4) + " mm");
  return result;
}

// Below this rise (scene units) a clip's plain skinning is as smooth as its bind pose, and a ratio to
// it says nothing: the ratio is taken to at least this.
constexpr double kRoughnessFloor = 1e-5;

CheckResult checkRoughnessRise(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("SKIN_ROUGHNESS_RISE", config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skipped(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  Measurement measurement(&result);
  int measured = 0;
  for (const ClipQuality& clip : quality.clips) {
    if (!clip.surface.measured) continue;
    ++measured;
    const double* rise = clip.surface.roughness_rise;
    measurement.add(rise[3] / std::max(rise[0], kRoughnessFloor), clip.clip,
                    "roughness rise (95th percentile) input " + fixed(1000.0 * rise[0], 3) + " mm, dual quaternions " +
                        fixed(1000.0 * rise[1], 3) + " mm, centres of rotation " + fixed(1000.0 * rise[2], 3) + " mm, rig " +
                        fixed(1000.0 * rise[3], 3) + " mm");
  }
  if (measured == 0) return skipped(result, "no clip was measured");
  measurement.finish(std::to_string(measured) + " clips, the rig's roughness rise at most " + fixed(result.measured, 2) +
                     " x the input skinning's");
  return result;
}

CheckResult checkBodyVolume(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("SKIN_BODY_VOLUME", config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skipped(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  Measurement measurement(&result);
  for (const ClipQuality& clip : quality.clips) {
    const SkinningVolumes& v = clip.body;
    measurement.add(100.0 * (std::abs(v.rig.change) - std::abs(v.input.change)), clip.clip,
                    "input skinning " + fixed(100.0 * v.input.change, 2) + " %, dual quaternions " +
                        fixed(100.0 * v.dual_quaternion.change, 2) + " %, rig " + fixed(100.0 * v.rig.change, 2) + " %");
  }
  measurement.finish(std::to_string(quality.clips.size()) + " clips, rig against input skinning at most " +
                     fixed(result.measured, 2) + " points");
  return result;
}

static CheckResult checkMuscleMove(const ValidationInputs& inputs, const ValidationConfig& config, const char* code, bool compressed) {
  CheckResult result = startCheck(code, config);
  if (const std::string why = qualitySkip(inputs); !why.empty()) return skipped(result, why);
  const DeformationQuality& quality = inputs.quality->quality;
  if (quality.muscles.empty()) return skipped(result, "the file has no RIGBAKE_muscle_rig extension to read muscle lengths from");
  const double height = bodyHeightOf(inputs);
  Measurement measurement(&result);
  int measured = 0;
  for (const MuscleQuality& muscle : quality.muscles) {
    const MuscleSkinMove& move = compressed ? muscle.compressed : muscle.stretched;
    // A corrective moves its skin in or out as the volume asks: neither check is about it.
    if (!move.measured || muscle.kind == PartKind::kCorrective) continue;
    ++measured;
    measurement.add(move.mean / height, muscle.muscle,
                    "mean " + fixed(1000.0 * move.mean, 2) + " mm (out " + fixed(1000.0 * move.max_out, 2) + ", in " +
                        fixed(1000.0 * move.max_in, 2) + " mm) at length ratio " + fixed(move.ratio, 3) + ", " +
                        move.clip + " " + fixed(move.time, 2) + " s");
  }
  if (!result.has_measured) return skipped(result, compressed ? "no muscle is compressed in any clip" : "no muscle is stretched in any clip");
  measurement.finish(std::to_string(measured) + " muscles, smallest mean move " +
                     fixed(1000.0 * result.measured * height, 2) + " mm");
  return result;
}

CheckResult checkMuscleBulgeOutward(const ValidationInputs& inputs, const ValidationConfig& config) {
  return checkMuscleMove(inputs, config, "MUSCLE_BULGE_OUTWARD", true);
}

CheckResult checkMuscleStretchNoHollow(const ValidationInputs& inputs, const ValidationConfig& config) {
  return checkMuscleMove(inputs, config, "MUSCLE_STRETCH_NO_HOLLOW", false);
}

static bool drivenByChannels(const BakedFileData& file, const FileMuscleJoint& joint) {
  return file.animations > 0 && joint.animations_moving_it == file.animations;
}

int undrivenMuscleJoints(const BakedFileData& file) {
  if (file.rig.present) return 0;
  int undriven = 0;
  for (const FileMuscleJoint& joint : file.muscle_joints) undriven += drivenByChannels(file, joint) ? 0 : 1;
  return undriven;
}

CheckResult checkRigExtensionMissing(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("RIG_EXTENSION_MISSING", config);
  const BakedFileData& file = *inputs.file;
  if (file.muscle_joints.empty()) return skipped(result, "the file has no muscle joints (by name or extras.rigbake)");
  const int joints = static_cast<int>(file.muscle_joints.size());
  result.has_measured = true;
  if (file.rig.present) {
    result.status = CheckStatus::kPass;
    result.message = std::to_string(joints) + " muscle joints, driven by the RIGBAKE_muscle_rig extension";
    return result;
  }
  // Without the extension only channels move a muscle joint: a sampled bake animates every one of them
  // in every clip; a runtime bake that lost its extension animates none.
  const int undriven = undrivenMuscleJoints(file);
  for (const FileMuscleJoint& joint : file.muscle_joints) {
    if (drivenByChannels(file, joint)) continue;
    if (result.findings.size() < static_cast<size_t>(kMaxFindings))
      result.findings.push_back({"/nodes/" + std::to_string(joint.node), 1.0,
                                 joint.name + ": no RIGBAKE_muscle_rig, channels in " +
                                     std::to_string(joint.animations_moving_it) + " of " +
                                     std::to_string(file.animations) + " animations"});
  }
  result.measured = undriven;
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  if (undriven == 0) {
    result.message = std::to_string(joints) + " muscle joints, every one animated in every clip (a sampled bake)";
    return result;
  }
  result.location = result.findings.front().location;
  result.message = std::to_string(undriven) + " of " + std::to_string(joints) +
                   " muscle joints without RIGBAKE_muscle_rig or channels: the rig was stripped (gltfpack and "
                   "glTF-Transform without rigbake's config drop it; docs/pipelines.md)";
  return result;
}

CheckResult checkInfluencesTruncated(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("INFLUENCES_TRUNCATED", config);
  bool any_packed = false;
  for (const FileSkinAttributes& skin : inputs.file->skins) any_packed = any_packed || skin.has_packed;
  if (!any_packed) return skipped(result, "the file has no decodable _RIGBAKE_PACKED_* attributes to compare with");
  Measurement measurement(&result);
  int total = 0;
  for (const FileSkinAttributes& skin : inputs.file->skins) {
    const int count = skin.slots ? static_cast<int>(skin.weights.size()) / skin.slots : 0;
    // An index out of range stops the decoder; JOINT_INDEX_IN_RANGE reports it.
    if (!skin.has_packed || skin.packed.vertex_count != count || !packedInfluencesProblem(skin.packed).empty()) continue;
    const QuantizedInfluences packed = unpackInfluences(skin.packed);
    int truncated = 0, worst_vertex = -1, worst_packed = 0, worst_standard = 0;
    for (int v = 0; v < count; ++v) {
      int in_packed = 0, in_standard = 0;
      for (int k = 0; k < packed.slots_per_vertex; ++k)
        in_packed += packed.weights[static_cast<size_t>(v) * packed.slots_per_vertex + k] != 0;
      for (int k = 0; k < skin.slots; ++k) in_standard += skin.weights[static_cast<size_t>(v) * skin.slots + k] != 0.0;
      if (in_standard >= in_packed) continue;
      ++truncated;
      if (worst_vertex < 0 || in_packed - in_standard > worst_packed - worst_standard) {
        worst_vertex = v;
        worst_packed = in_packed;
        worst_standard = in_standard;
      }
    }
    total += truncated;
    measurement.add(truncated, skin.pointer + "/attributes",
                    "packed buffers hold " + std::to_string(skin.packed.influences) + " influences, JOINTS_n/WEIGHTS_n " +
                        std::to_string(skin.slots) + " slots" +
                        (truncated ? "; vertex " + std::to_string(worst_vertex) + " has " + std::to_string(worst_packed) +
                                         " packed and " + std::to_string(worst_standard) + " in WEIGHTS_n"
                                   : std::string()));
  }
  if (!result.has_measured) return skipped(result, "no packed primitive has as many vertices as its WEIGHTS_n");
  measurement.finish(total == 0 ? "every vertex keeps in WEIGHTS_n the influences its packed buffers hold"
                                : std::to_string(total) + " vertices have fewer influences in JOINTS_n/WEIGHTS_n than "
                                  "in the packed buffers: a tool cut them (gltfpack keeps 4, glTF-Transform's optimize without "
                                  "rigbake's config stores 8-bit weights; docs/pipelines.md)");
  return result;
}

CheckResult checkGltfStructure(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("GLTF_STRUCTURE", config);
  std::vector<FileIssue> issues = inputs.file->structure;
  // Muscles the --muscles file names must all have been baked into this file (their skinned joints;
  // the helpers are optional, bake --helper-joints).
  if (inputs.muscles) {
    static const char* kRoles[] = {"skinned"};
    for (const MusclePart& part : inputs.muscles->parts) {
      for (const char* role : kRoles) {
        bool found = false;
        for (const FileMuscleNode& node : inputs.file->muscle_nodes) {
          found = found || (node.muscle == part.fullName() && node.role == role);
        }
        if (!found)
          issues.push_back({"/nodes", "muscle " + part.fullName() + " of the muscle file has no " + role +
                                          " joint node in the baked file"});
      }
    }
  }
  result.has_measured = true;
  result.measured = static_cast<double>(issues.size());
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  for (const FileIssue& issue : issues) {
    if (result.findings.size() >= static_cast<size_t>(kMaxFindings)) break;
    result.findings.push_back({issue.pointer, 1.0, issue.message});
  }
  if (!issues.empty()) result.location = issues.front().pointer;
  result.message = std::to_string(inputs.file->skins.size()) + " skinned primitives, " +
                   std::to_string(inputs.file->muscle_nodes.size()) + " muscle joint nodes, " +
                   std::to_string(issues.size()) + " structural issues";
  return result;
}

CheckResult checkKhronosValidator(const ValidationInputs& inputs, const ValidationConfig& config) {
  CheckResult result = startCheck("KHRONOS_VALIDATOR", config);
  if (!inputs.khronos.ran) return skipped(result, inputs.khronos.skip_reason);
  result.has_measured = true;
  result.measured = inputs.khronos.errors;
  result.status = withinThreshold(result, result.measured) ? CheckStatus::kPass : CheckStatus::kFail;
  for (const FileIssue& issue : inputs.khronos.issues) {
    if (result.findings.size() >= static_cast<size_t>(kMaxFindings)) break;
    result.findings.push_back({issue.pointer, 1.0, issue.message});
  }
  result.message = std::to_string(inputs.khronos.errors) + " errors, " + std::to_string(inputs.khronos.warnings) +
                   " warnings";
  return result;
}

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
      const Pose pose = poseAt(skeleton, clip, t);
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
        frames.push_back(bakedSkinMatrices(character, file, poseAt(skeleton, clip, clip.times[t])));
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

Report validateBakedCharacter(const ValidationInputs& inputs, const ValidationConfig& config) {
  assert(inputs.character && inputs.file);
  const Character& character = *inputs.character;
  const BakedFileData& file = *inputs.file;
  Report report;
  report.character = inputs.character_name;
  report.joints = character.skeleton.size();
  for (const FileSkinAttributes& skin : file.skins) {
    report.vertices += static_cast<int>(character.meshes[skin.mesh_part].positions.size());
    if (skin.has_packed) report.influences = std::max(report.influences, skin.packed.influences);
  }
  report.muscles = inputs.muscles ? static_cast<int>(inputs.muscles->parts.size()) : 0;
  if (inputs.muscles) report.ratios = muscleRatiosOverClips(character, *inputs.muscles);
  report.deformation = packedDeformationPerClip(character, file, inputs.threads);
  report.influence_histogram = influenceHistogram(file);
  report.memory = skinMemoryTable(report.vertices);
  // Jiggle baked into the clips, else the extension's, run by the runtime library.
  RuntimeJiggles runtime_jiggles;
  if (file.jiggles.empty() && !file.rig.jiggles.empty()) runtime_jiggles = simulateFileJiggles(character, file.rig);
  report.jiggles = file.jiggles.empty() ? runtime_jiggles.clips : file.jiggles;
  if (inputs.quality) report.quality = *inputs.quality;

  report.checks.push_back(checkLandmarksResolved(inputs, config));
  report.checks.push_back(checkLocatorSymmetry(inputs, config));
  report.checks.push_back(checkLocatorNearSurface(inputs, config));
  report.checks.push_back(checkMuscleRatioInRange(inputs, report.ratios, config));
  report.checks.push_back(checkWeightsSum(inputs, config));
  report.checks.push_back(checkWeightsNonNegative(inputs, config));
  report.checks.push_back(checkJointIndexInRange(inputs, config));
  report.checks.push_back(checkInfluenceCount(inputs, config));
  report.checks.push_back(checkPackedDeformationError(inputs, report.deformation, config));
  report.checks.push_back(checkJiggleWithinClamp(inputs, report.jiggles, runtime_jiggles.refused, config));
  report.checks.push_back(checkRegionVolumeLoss(inputs, config));
  report.checks.push_back(checkSeamOpening(inputs, config));
  report.checks.push_back(checkRoughnessRise(inputs, config));
  report.checks.push_back(checkBodyVolume(inputs, config));
  report.checks.push_back(checkMuscleBulgeOutward(inputs, config));
  report.checks.push_back(checkMuscleStretchNoHollow(inputs, config));
  report.checks.push_back(checkRigExtensionMissing(inputs, config));
  report.checks.push_back(checkInfluencesTruncated(inputs, config));
  report.checks.push_back(checkGltfStructure(inputs, config));
  report.checks.push_back(checkKhronosValidator(inputs, config));
  assert(report.checks.size() == checkDefinitions().size());

  if (inputs.landmarks) {
    report.figure = bodyFigure(character, *inputs.landmarks, inputs.muscles);
    // Mark the muscles whose locators a locator check found over its threshold.
    for (const CheckResult& check : report.checks) {
      if (check.code != "LOCATOR_NEAR_SURFACE" && check.code != "LOCATOR_SYMMETRY") continue;
      for (const CheckFinding& finding : check.findings) {
        if (withinThreshold(check, finding.measured)) continue;
        const std::string muscle = finding.location.substr(0, finding.location.find('/'));
        for (FigureMuscle& m : report.figure.muscles) m.flagged = m.flagged || m.name == muscle;
      }
    }
  }
  return report;
}

}  // namespace rigbake
