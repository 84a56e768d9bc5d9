// The report of `rigbake validate` (pipeline/checks.h runs the checks): each check's result with its
// stable code, severity, threshold and measured value, in the manner of the Khronos glTF-Validator, and
// the data its plots draw. The report writers (formats/report_json.h, report_html.h, report_junit.h) need
// these types and nothing of the checks themselves. The checks' codes and defaults are
// pipeline/check_registry.h.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pipeline/baked_file.h"
#include "pipeline/deformation_quality.h"
#include "pipeline/memory_table.h"
#include "pipeline/render.h"

namespace rigbake {

enum class Severity { kError, kWarning, kInfo };
enum class CheckStatus { kPass, kFail, kSkipped };
// How the measured value must relate to the threshold for the check to pass.
enum class Comparison { kAtMost, kAtLeast };

const char* severityName(Severity severity);  // "error", "warning", "info"
const char* statusName(CheckStatus status);   // "pass", "fail", "skipped"
// False when `name` is not one of severityName()'s results.
bool parseSeverity(const std::string& name, Severity* severity);

// A check's code, what it measures and its defaults; the table docs/validate.md documents.
struct CheckDefinition {
  const char* code;
  Severity severity;
  double threshold;
  Comparison comparison;
  const char* unit;   // of threshold and measured value
  const char* title;  // what it measures, one line
};

// Per-code overrides from a `--config` file (formats/report_json.h reads it).
struct ValidationConfig {
  std::map<std::string, Severity> severity;
  std::map<std::string, double> threshold;
};

// One offending (or, for a passing check, the worst) item of a check.
struct CheckFinding {
  std::string location;  // JSON pointer into the glTF, or a muscle / landmark name
  double measured = 0.0;
  std::string message;
};

struct CheckResult {
  std::string code;
  std::string title;
  Severity severity = Severity::kError;
  CheckStatus status = CheckStatus::kSkipped;
  Comparison comparison = Comparison::kAtMost;
  double threshold = 0.0;
  std::string unit;
  bool has_measured = false;
  double measured = 0.0;   // the worst value over everything the check looked at
  std::string location;    // where that worst value is
  std::string message;     // a one-line summary, or why the check was skipped
  std::vector<CheckFinding> findings;  // failing items first, worst first, at most kMaxFindings
};

constexpr int kMaxFindings = 20;

// ---- Plot data ----

// Positions in the body's frame (anatomy/landmarks.h BodyFrame) relative to its midline: x towards the
// character's left, y up, z forward. Front view draws (x, y), side view (z, y).
struct FigureSegment {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
};

struct FigureMuscle {
  std::string name;   // LeftBicep
  std::string group;  // Arms
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d driver = Eigen::Vector3d::Zero();
  Eigen::Vector3d insertion = Eigen::Vector3d::Zero();
  bool flagged = false;  // a locator of this muscle failed LOCATOR_NEAR_SURFACE or LOCATOR_SYMMETRY
};

struct FigureLandmark {
  std::string name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

// A silhouette as filled runs of a grid: cells [begin, end) of row `row`, row 0 at the bottom.
struct Silhouette {
  double min_u = 0.0, min_v = 0.0;  // body-frame coordinates of the grid's lower left corner
  double cell = 0.0;                // cell size, scene units
  int columns = 0, rows = 0;
  std::vector<std::array<int, 3>> runs;  // {row, begin, end}
};

struct Figure {
  double height = 0.0;  // body height, scene units
  Silhouette front;     // (x, y)
  Silhouette side;      // (z, y)
  std::vector<FigureSegment> bones;
  std::vector<FigureLandmark> landmarks;
  std::vector<FigureMuscle> muscles;
};

struct MuscleRatioSeries {
  std::string muscle;
  std::string group;
  double compression = 0.0;
  double stretch = 0.0;
  std::vector<double> ratio;  // unclamped L / L_rest at each of the clip's times
};

struct ClipRatios {
  std::string clip;
  std::vector<double> times;
  std::vector<MuscleRatioSeries> muscles;
};

struct ClipDeformation {
  std::string clip;
  int samples = 0;
  double max_displacement = 0.0;  // scene units
  double rms_displacement = 0.0;
};

// Deformation quality of the file (pipeline/baked_quality.h). A picture: the input skinning and the
// baked rig side by side at one sample, framed on one part of the body.
struct QualityPicture {
  std::string title;    // what is shown: a clip's worst region or a muscle at its peak compression
  std::string clip;
  double time = 0.0;
  std::string subject;  // the region or muscle framed
  double scale = 0.0;   // scene units at full heatmap colour
  double max_out = 0.0, max_in = 0.0;  // displacement of the rig along the input's normal, scene units
  // One image: input skinning | baked rig | heatmap of the rig's displacement (red out, blue in), or
  // for a crease the four skinnings side by side (`panels` names them, `note` has the crease's figures).
  RgbImage image;
  std::string panels = "input | rig | move";
  std::string note;
  // A region's picture: what the ring in its panels marks (the place that takes most of the region's
  // volume against the input skinning, pipeline/region_loss_place.h); empty when there is no ring.
  std::string marker;
};

struct BakedQuality {
  bool measured = false;
  std::string skip_reason;  // when not measured
  // The file (name, no directories) whose own weights are the input skinning; empty: the baked file's
  // weights with each muscle's handed back to its carrier.
  std::string input_source;
  DeformationQuality quality;
  std::vector<QualityPicture> pictures;
};

struct Report {
  std::string character;  // file name without directories
  int joints = 0;
  int vertices = 0;       // skinned vertices
  int muscles = 0;        // muscle parts checked (0 without --muscles)
  int influences = 0;     // packed influence count of the bake, 0 when the file has no packed data
  std::vector<CheckResult> checks;
  Figure figure;
  std::vector<ClipRatios> ratios;
  std::vector<std::int64_t> influence_histogram;  // [n] = vertices with n non-zero influences
  std::vector<ClipDeformation> deformation;
  std::vector<SkinLayoutSize> memory;
  // Baked into the clips (read from their extras), else the extension's runtime jiggles evaluated over
  // the file's clips (pipeline/file_jiggle.h); empty when the bake had no --jiggle.
  std::vector<ClipJiggles> jiggles;
  BakedQuality quality;              // measured = false without muscle joints or landmarks

  // True when every check at error severity passed or was skipped.
  bool passed() const;
};

}  // namespace rigbake
