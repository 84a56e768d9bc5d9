// Strict reading of JSON inputs: every error names the file and the JSON pointer of the offending
// value, and unknown keys are errors (a typo in a preset must not be silently ignored).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/error.h"

namespace rigbake {

// Parses a file; throws IO_FILE_NOT_FOUND or JSON_PARSE_FAILED (with line/column).
nlohmann::json readJsonFile(const std::string& path);

class JsonReader {
 public:
  // `error_code`: the code every failure of this reader and the readers it hands out carries.
  JsonReader(const nlohmann::json& value, std::string file, std::string pointer, const ErrorCode& error_code)
      : value_(value), file_(std::move(file)), pointer_(std::move(pointer)), code_(&error_code) {}

  const nlohmann::json& value() const { return value_; }
  const std::string& pointer() const { return pointer_; }
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const std::string& message) const;
  void requireObject() const;
  // Fails naming the first key not in `allowed`.
  void allowKeys(const std::vector<std::string>& allowed) const;
  bool has(const std::string& key) const;
  JsonReader at(const std::string& key) const;  // required member
  JsonReader at(size_t index) const;            // array element
  size_t arraySize() const;                     // requires an array
  std::vector<std::string> keys() const;        // requires an object; sorted

  std::string asString() const;
  double asNumber() const;
  // A finite number in [min, max]; fails naming the range (in `unit`, e.g. "m") otherwise, so that an
  // absurd value (1e300) never reaches geometry.
  double asNumberIn(double min, double max, const std::string& unit = "") const;
  int asInt() const;
  bool asBool() const;
  std::vector<std::string> asStringList() const;  // a string or an array of strings

 private:
  const nlohmann::json& value_;
  std::string file_;
  std::string pointer_;
  const ErrorCode* code_;  // a symbol of core/error.h
};

// "presets/skeletons/mixamo.json" -> "mixamo": the name a preset gets when it gives none.
std::string fileStem(const std::string& path);
// "models/hero.gltf" -> "models", "hero.gltf" -> ".": where a file's relative references start.
std::string directoryOf(const std::string& path);

}  // namespace rigbake
