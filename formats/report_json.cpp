#include "formats/report_json.h"

#include <cmath>

#include "formats/json_text.h"
#include "formats/quality_json.h"

namespace rigbake {
namespace {

// JSON has no NaN or infinity; a value that is not finite is written as null.
nlohmann::ordered_json number(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json checkJson(const CheckResult& check) {
  nlohmann::ordered_json findings = nlohmann::ordered_json::array();
  for (const CheckFinding& finding : check.findings) {
    findings.push_back({{"location", finding.location}, {"measured", number(finding.measured)}, {"message", finding.message}});
  }
  return {
      {"code", check.code},
      {"severity", severityName(check.severity)},
      {"status", statusName(check.status)},
      {"comparison", check.comparison == Comparison::kAtMost ? "<=" : ">="},
      {"threshold", number(check.threshold)},
      {"measured", check.has_measured ? number(check.measured) : nlohmann::ordered_json(nullptr)},
      {"unit", check.unit},
      {"location", check.location},
      {"message", check.message},
      {"title", check.title},
      {"findings", findings},
  };
}

}  // namespace

nlohmann::ordered_json reportJsonValue(const Report& report) {
  int failed_errors = 0, failed_warnings = 0, passed = 0, skipped = 0;
  nlohmann::ordered_json checks = nlohmann::ordered_json::array();
  for (const CheckResult& check : report.checks) {
    checks.push_back(checkJson(check));
    if (check.status == CheckStatus::kPass) ++passed;
    if (check.status == CheckStatus::kSkipped) ++skipped;
    if (check.status == CheckStatus::kFail) ++(check.severity == Severity::kError ? failed_errors : failed_warnings);
  }
  nlohmann::ordered_json ratios = nlohmann::ordered_json::array();
  for (const ClipRatios& clip : report.ratios) {
    nlohmann::ordered_json muscles = nlohmann::ordered_json::array();
    for (const MuscleRatioSeries& series : clip.muscles) {
      nlohmann::ordered_json values = nlohmann::ordered_json::array();
      for (double r : series.ratio) values.push_back(number(r));
      muscles.push_back({{"muscle", series.muscle},
                         {"group", series.group},
                         {"compression", series.compression},
                         {"stretch", series.stretch},
                         {"ratio", values}});
    }
    ratios.push_back({{"clip", clip.clip}, {"times", clip.times}, {"muscles", muscles}});
  }
  nlohmann::ordered_json jiggles = nlohmann::ordered_json::array();
  for (const ClipJiggles& clip : report.jiggles) {
    nlohmann::ordered_json series_list = nlohmann::ordered_json::array();
    for (const JiggleSeries& series : clip.jiggles) {
      nlohmann::ordered_json angles = nlohmann::ordered_json::array(), clamps = nlohmann::ordered_json::array();
      for (double a : series.angle_deg) angles.push_back(number(a));
      for (double c : series.clamp_deg) clamps.push_back(number(c));
      series_list.push_back({{"joint", series.joint}, {"host", series.host}, {"angle_deg", angles}, {"clamp_deg", clamps}});
    }
    jiggles.push_back({{"clip", clip.clip}, {"times", clip.times}, {"jiggles", series_list}});
  }
  nlohmann::ordered_json deformation = nlohmann::ordered_json::array();
  for (const ClipDeformation& clip : report.deformation) {
    deformation.push_back({{"clip", clip.clip},
                           {"samples", clip.samples},
                           {"max_m", number(clip.max_displacement)},
                           {"rms_m", number(clip.rms_displacement)}});
  }
  nlohmann::ordered_json memory = nlohmann::ordered_json::array();
  for (const SkinLayoutSize& layout : report.memory) {
    memory.push_back({{"layout", layout.id},
                      {"influences", layout.influences},
                      {"bytes_per_vertex", layout.bytes_per_vertex},
                      {"total_bytes", layout.total_bytes}});
  }
  // Deformation quality: the figures as `bake --stats` writes them, and what each picture shows (the
  // pictures themselves are in report.html).
  nlohmann::ordered_json quality;
  if (report.quality.measured) {
    quality = nlohmann::ordered_json(deformationQualityJson(report.quality.quality));
    // Whose weights the input skinning is: the character file it was baked from, or null for the baked
    // file's weights with each muscle's handed back to its carrier.
    quality["input_weights_from"] = report.quality.input_source.empty() ? nlohmann::ordered_json(nullptr)
                                                                        : nlohmann::ordered_json(report.quality.input_source);
    nlohmann::ordered_json pictures = nlohmann::ordered_json::array();
    for (const QualityPicture& picture : report.quality.pictures) {
      pictures.push_back({{"title", picture.title},
                          {"clip", picture.clip},
                          {"time_s", number(picture.time)},
                          {"subject", picture.subject},
                          {"panels", picture.panels},
                          {"heatmap_full_scale_mm", number(1000.0 * picture.scale)},
                          {"max_out_mm", number(1000.0 * picture.max_out)},
                          {"max_in_mm", number(1000.0 * picture.max_in)}});
      // A region's picture that rings the place taking most of its loss (pipeline/region_loss_place.h).
      if (!picture.marker.empty()) pictures.back()["ring"] = picture.marker;
    }
    quality["pictures"] = pictures;
  } else {
    quality = {{"measured", false}, {"reason", report.quality.skip_reason}};
  }
  return {
      {"report_version", kReportJsonVersion},
      {"tool", {{"name", "rigbake"}, {"version", RIGBAKE_VERSION}}},
      {"character", report.character},
      {"passed", report.passed()},
      {"summary",
       {{"checks", report.checks.size()},
        {"passed", passed},
        {"failed_errors", failed_errors},
        {"failed_warnings", failed_warnings},
        {"skipped", skipped}}},
      {"character_stats",
       {{"joints", report.joints},
        {"skinned_vertices", report.vertices},
        {"muscles", report.muscles},
        {"packed_influences", report.influences}}},
      {"checks", checks},
      {"deformation_quality", quality},
      {"plots",
       {{"muscle_ratio", ratios},
        {"influence_histogram", report.influence_histogram},
        {"packed_deformation", deformation},
        {"memory_table", memory},
        {"jiggle_angle", jiggles}}},
  };
}

std::string reportJson(const Report& report) { return jsonText(reportJsonValue(report)) + "\n"; }

}  // namespace rigbake
