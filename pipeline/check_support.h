// What every check of `rigbake validate` (pipeline/checks.h) starts from and reports through: its
// definition with the config's overrides, the measurement that keeps the worst value and the worst
// findings, and the text of its numbers. Internal to pipeline/muscle_checks.cpp, skin_checks.cpp and
// checks.cpp.
#pragma once

#include <string>
#include <vector>

#include "pipeline/checks.h"

namespace rigbake {

// A result for `definition` with the config's severity and threshold for its code, if it sets them.
CheckResult startCheck(const CheckDefinition& definition, const ValidationConfig& config);

// Whether `value` passes the result's threshold.
bool withinThreshold(const CheckResult& result, double value);

// `result` skipped, `reason` as its message.
CheckResult skippedCheck(CheckResult result, const std::string& reason);

// Records `value` at `location` as a finding and keeps the worst value as the check's measurement.
class CheckMeasurement {
 public:
  explicit CheckMeasurement(CheckResult* result) : result_(result) {}

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

// `value` with `decimals` digits after the point ("%.*f").
std::string fixedDecimals(double value, int decimals);

// The landmarks' body height, 1 (scene units) when they did not resolve.
double bodyHeightOf(const ValidationInputs& inputs);

// Why a deformation-quality check cannot run, or "" when it can.
std::string qualitySkip(const ValidationInputs& inputs);

}  // namespace rigbake
