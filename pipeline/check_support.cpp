// The checks' shared start, measurement and number text (pipeline/check_support.h).
#include "pipeline/check_support.h"

#include <algorithm>
#include <cstdio>

namespace rigbake {

CheckResult startCheck(const CheckDefinition& definition, const ValidationConfig& config) {
  CheckResult result;
  result.code = definition.code;
  result.title = definition.title;
  result.severity = definition.severity;
  result.threshold = definition.threshold;
  result.comparison = definition.comparison;
  result.unit = definition.unit;
  auto severity = config.severity.find(result.code);
  if (severity != config.severity.end()) result.severity = severity->second;
  auto threshold = config.threshold.find(result.code);
  if (threshold != config.threshold.end()) result.threshold = threshold->second;
  return result;
}

bool withinThreshold(const CheckResult& result, double value) {
  return result.comparison == Comparison::kAtMost ? value <= result.threshold : value >= result.threshold;
}

CheckResult skippedCheck(CheckResult result, const std::string& reason) {
  result.status = CheckStatus::kSkipped;
  result.message = reason;
  return result;
}

std::string fixedDecimals(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

double bodyHeightOf(const ValidationInputs& inputs) {
  return inputs.landmarks && inputs.landmarks->body.height > 0.0 ? inputs.landmarks->body.height : 1.0;
}

std::string qualitySkip(const ValidationInputs& inputs) {
  if (!inputs.quality) return inputs.landmarks ? "deformation quality was not measured" : "landmarks did not resolve";
  if (!inputs.quality->measured) return inputs.quality->skip_reason;
  return "";
}

}  // namespace rigbake
