#include "formats/report_junit.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"

namespace rigbake {

std::string xmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    // XML 1.0 allows neither bytes that are not UTF-8 (a file name's, say) nor most control
    // characters: each becomes U+FFFD, so the report stays well-formed whatever the input was called.
    const size_t length = utf8SequenceAt(text, i);
    if (length > 1) {
      out.append(text, i, length);
      i += length;
      continue;
    }
    const unsigned char c = static_cast<unsigned char>(text[i++]);
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        if (length == 0 || (c < 0x20 && c != '\t' && c != '\n' && c != '\r')) out += "\xEF\xBF\xBD";
        else out += static_cast<char>(c);
    }
  }
  return out;
}

namespace {

std::string formatNumber(double value) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof(text), "%.6g", value);
  return text;
}

// "measured 0.0004 <= 0.001 weight at /meshes/0/primitives/0/attributes/WEIGHTS_0"
std::string verdict(const CheckResult& check) {
  std::string text = check.message;
  if (check.has_measured) {
    text += "\nmeasured " + formatNumber(check.measured) + " " + check.unit + ", required " +
            (check.comparison == Comparison::kAtMost ? "<= " : ">= ") + formatNumber(check.threshold);
    if (!check.location.empty()) text += " at " + check.location;
  }
  for (const CheckFinding& finding : check.findings) {
    text += "\n  " + finding.location + ": " + finding.message;
  }
  return text;
}

bool isFailure(const CheckResult& check) {
  return check.status == CheckStatus::kFail && check.severity == Severity::kError;
}

}  // namespace

std::string reportJunit(const std::vector<Report>& reports) {
  int tests = 0, failures = 0, skipped = 0;
  for (const Report& report : reports) {
    for (const CheckResult& check : report.checks) {
      ++tests;
      failures += isFailure(check);
      skipped += check.status == CheckStatus::kSkipped;
    }
  }
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  xml += "<testsuites name=\"rigbake validate\" tests=\"" + std::to_string(tests) + "\" failures=\"" +
         std::to_string(failures) + "\" errors=\"0\" skipped=\"" + std::to_string(skipped) + "\">\n";
  for (const Report& report : reports) {
    int suite_failures = 0, suite_skipped = 0;
    for (const CheckResult& check : report.checks) {
      suite_failures += isFailure(check);
      suite_skipped += check.status == CheckStatus::kSkipped;
    }
    const std::string name = xmlEscape(report.character);
    xml += "  <testsuite name=\"" + name + "\" tests=\"" + std::to_string(report.checks.size()) + "\" failures=\"" +
           std::to_string(suite_failures) + "\" errors=\"0\" skipped=\"" + std::to_string(suite_skipped) + "\">\n";
    for (const CheckResult& check : report.checks) {
      xml += "    <testcase classname=\"rigbake.validate." + name + "\" name=\"" + xmlEscape(check.code) + "\"";
      const std::string body = xmlEscape(verdict(check));
      if (check.status == CheckStatus::kSkipped) {
        xml += ">\n      <skipped message=\"" + xmlEscape(check.message) + "\"/>\n    </testcase>\n";
      } else if (isFailure(check)) {
        xml += ">\n      <failure type=\"" + xmlEscape(check.code) + "\" message=\"" +
               xmlEscape(check.code + ": " + check.message) + "\">" + body + "</failure>\n    </testcase>\n";
      } else {
        const std::string prefix = check.status == CheckStatus::kFail
                                       ? std::string(severityName(check.severity)) + " (not failing the build): "
                                       : std::string("pass: ");
        xml += ">\n      <system-out>" + xmlEscape(prefix) + body + "</system-out>\n    </testcase>\n";
      }
    }
    xml += "  </testsuite>\n";
  }
  xml += "</testsuites>\n";
  return xml;
}

}  // namespace rigbake
