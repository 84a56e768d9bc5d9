#include "formats/validate_config.h"

#include <cmath>

#include "formats/json_reader.h"

namespace rigbake {

ValidationConfig readValidationConfig(const std::string& path) {
  const nlohmann::json json = readJsonFile(path);
  JsonReader root(json, path, "", errc::VALIDATE_CONFIG_INVALID);
  root.requireObject();
  root.allowKeys({"$schema", "description", "checks"});
  ValidationConfig config;
  if (!root.has("checks")) return config;
  JsonReader checks = root.at("checks");
  checks.requireObject();
  for (const std::string& code : checks.keys()) {
    JsonReader check = checks.at(code);
    if (!findCheckDefinition(code)) check.fail("'" + code + "' is not a check code (see docs/validate.md)");
    check.requireObject();
    check.allowKeys({"threshold", "severity"});
    if (check.has("threshold")) {
      const double threshold = check.at("threshold").asNumber();
      if (!std::isfinite(threshold)) check.at("threshold").fail("must be a finite number");
      config.threshold[code] = threshold;
    }
    if (check.has("severity")) {
      Severity severity = Severity::kError;
      if (!parseSeverity(check.at("severity").asString(), &severity))
        check.at("severity").fail("must be \"error\", \"warning\" or \"info\"");
      config.severity[code] = severity;
    }
  }
  return config;
}

}  // namespace rigbake
