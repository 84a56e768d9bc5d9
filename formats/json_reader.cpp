#include "formats/json_reader.h"
#include "core/file_name.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "formats/atomic_file.h"

namespace rigbake {

nlohmann::json readJsonFile(const std::string& path) {
  std::string text = readFile(path, kMaxJsonBytes);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // A syntax error (parse_error), or a number too large for a double (out_of_range 406: "1e999").
    // Drop nlohmann's "[json.exception.parse_error.101] " prefix; keep its line and column.
    std::string message = e.what();
    size_t end_of_tag = message.find("] ");
    if (message.rfind("[json.exception", 0) == 0 && end_of_tag != std::string::npos)
      message = message.substr(end_of_tag + 2);
    fail(errc::JSON_PARSE_FAILED, path, message);
  }
}

namespace {
std::string escapePointerToken(const std::string& token) {
  std::string out;
  for (char c : token) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}
}  // namespace

void JsonReader::fail(const std::string& message) const {
  rigbake::fail(*code_, file_ + "#" + (pointer_.empty() ? "/" : pointer_), message);
}

void JsonReader::requireObject() const {
  if (!value_.is_object()) fail("must be a JSON object");
}

void JsonReader::allowKeys(const std::vector<std::string>& allowed) const {
  requireObject();
  for (auto it = value_.begin(); it != value_.end(); ++it) {
    if (std::find(allowed.begin(), allowed.end(), it.key()) == allowed.end()) {
      std::string list;
      for (const std::string& key : allowed) list += (list.empty() ? "" : ", ") + key;
      JsonReader(it.value(), file_, pointer_ + "/" + escapePointerToken(it.key()), *code_)
          .fail("unknown key '" + it.key() + "' (allowed: " + list + ")");
    }
  }
}

bool JsonReader::has(const std::string& key) const { return value_.is_object() && value_.contains(key); }

JsonReader JsonReader::at(const std::string& key) const {
  requireObject();
  if (!value_.contains(key)) fail("missing required key '" + key + "'");
  return JsonReader(value_.at(key), file_, pointer_ + "/" + escapePointerToken(key), *code_);
}

JsonReader JsonReader::at(size_t index) const {
  if (!value_.is_array() || index >= value_.size()) fail("missing array element " + std::to_string(index));
  return JsonReader(value_.at(index), file_, pointer_ + "/" + std::to_string(index), *code_);
}

size_t JsonReader::arraySize() const {
  if (!value_.is_array()) fail("must be an array");
  return value_.size();
}

std::vector<std::string> JsonReader::keys() const {
  requireObject();
  std::vector<std::string> result;
  for (auto it = value_.begin(); it != value_.end(); ++it) result.push_back(it.key());
  return result;
}

std::string JsonReader::asString() const {
  if (!value_.is_string()) fail("must be a string");
  return value_.get<std::string>();
}

double JsonReader::asNumber() const {
  if (!value_.is_number()) fail("must be a number");
  double number = value_.get<double>();
  if (!std::isfinite(number)) fail("must be a finite number");
  return number;
}

double JsonReader::asNumberIn(double min, double max, const std::string& unit) const {
  const double number = asNumber();
  if (number < min || number > max) {
    auto text = [](double value) {
      std::ostringstream out;
      out << std::setprecision(6) << value;
      return out.str();
    };
    const std::string suffix = unit.empty() ? "" : " " + unit;
    fail("must be between " + text(min) + suffix + " and " + text(max) + suffix + " (got " + text(number) + ")");
  }
  return number;
}

int JsonReader::asInt() const {
  if (!value_.is_number_integer()) fail("must be an integer");
  return value_.get<int>();
}

bool JsonReader::asBool() const {
  if (!value_.is_boolean()) fail("must be true or false");
  return value_.get<bool>();
}

std::vector<std::string> JsonReader::asStringList() const {
  if (value_.is_string()) return {value_.get<std::string>()};
  std::vector<std::string> result;
  for (size_t i = 0; i < arraySize(); ++i) result.push_back(at(i).asString());
  return result;
}

std::string fileStem(const std::string& path) {
  const std::string name = fileNameOf(path);
  size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(0, dot);
}

std::string directoryOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

}  // namespace rigbake
