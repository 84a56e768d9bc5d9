// report.json of `rigbake validate`: every check with its code, severity, threshold, measured value,
// status and location, then the data the HTML report plots. Deterministic: keys in a fixed order, no
// timestamps, no directories (the character is named by its file name).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "pipeline/check_report.h"

namespace rigbake {

constexpr int kReportJsonVersion = 1;

nlohmann::ordered_json reportJsonValue(const Report& report);
// reportJsonValue() as text, two-space indented and newline-terminated.
std::string reportJson(const Report& report);

}  // namespace rigbake
