// The RIGBAKE_muscle_rig extension's JSON read without a JSON library. Sources: RFC 8259 (the JSON
// grammar this reader accepts, nothing more), docs/extensions/RIGBAKE_muscle_rig.md (the members and
// what a reader checks), formats/muscle_rig_extension.cpp (the reader whose rig this one must equal).
//
// Numbers: every literal goes through strtod, which is correctly rounded in glibc and musl
// (emscripten), so it gives what nlohmann (under tinygltf) gives: its own strtod call for a literal
// with a fraction or exponent, and for an integer literal the correctly rounded double of the exact
// integer it reads (with "-0" read as +0, as an integer has no sign of zero), with the '.'
// replaced by the locale's decimal point first, as nlohmann does, so that a host program that set a
// locale (Blender does) still reads 0.5 as 0.5.
#include "runtime/rig_json.h"

#include <clocale>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <utility>

namespace rigbake::runtime {
namespace {

struct Json {
  enum Type { kNull, kBool, kNumber, kString, kArray, kObject };
  Type type = kNull;
  bool boolean = false;
  bool integer = false;  // a number written without fraction or exponent
  double number = 0;
  std::string text;
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> members;

  const Json* member(const char* key) const {
    if (type != kObject) return nullptr;
    for (const auto& [name, value] : members) {
      if (name == key) return &value;
    }
    return nullptr;
  }
};

class Parser {
 public:
  Parser(const char* text, std::size_t size) : p_(text), end_(text + size), begin_(text) {}

  bool parseDocument(Json* out, std::string* error) {
    skipSpace();
    if (!value(out, 0)) return report(error);
    skipSpace();
    if (p_ != end_) {
      problem_ = "unexpected text after the JSON value";
      return report(error);
    }
    return true;
  }

 private:
  const char* p_;
  const char* end_;
  const char* begin_;
  const char* problem_ = nullptr;

  bool report(std::string* error) const {
    *error = "JSON syntax at byte " + std::to_string(p_ - begin_) + ": " + (problem_ ? problem_ : "malformed");
    return false;
  }
  bool fail(const char* problem) {
    problem_ = problem;
    return false;
  }
  void skipSpace() {
    while (p_ != end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\n' || *p_ == '\r')) ++p_;
  }
  bool literal(const char* word) {
    const std::size_t n = std::strlen(word);
    if (static_cast<std::size_t>(end_ - p_) < n || std::memcmp(p_, word, n) != 0) return fail("unknown literal");
    p_ += n;
    return true;
  }

  bool value(Json* out, int depth) {
    if (p_ == end_) return fail("unexpected end of text");
    switch (*p_) {
      case '{': return object(out, depth + 1);
      case '[': return array(out, depth + 1);
      case '"': out->type = Json::kString; return string(&out->text);
      case 't': out->type = Json::kBool; out->boolean = true; return literal("true");
      case 'f': out->type = Json::kBool; out->boolean = false; return literal("false");
      case 'n': out->type = Json::kNull; return literal("null");
      default: return number(out);
    }
  }

  bool object(Json* out, int depth) {
    if (depth > kRigJsonMaxDepth) return fail("nested deeper than the reader's limit");
    out->type = Json::kObject;
    ++p_;
    skipSpace();
    if (p_ != end_ && *p_ == '}') {
      ++p_;
      return true;
    }
    for (;;) {
      skipSpace();
      if (p_ == end_ || *p_ != '"') return fail("expected a member name");
      std::string name;
      if (!string(&name)) return false;
      for (const auto& member : out->members) {
        if (member.first == name) return fail("duplicate member name");
      }
      skipSpace();
      if (p_ == end_ || *p_ != ':') return fail("expected ':'");
      ++p_;
      skipSpace();
      out->members.emplace_back(std::move(name), Json());
      if (!value(&out->members.back().second, depth)) return false;
      skipSpace();
      if (p_ != end_ && *p_ == ',') {
        ++p_;
        continue;
      }
      if (p_ != end_ && *p_ == '}') {
        ++p_;
        return true;
      }
      return fail("expected ',' or '}'");
    }
  }

  bool array(Json* out, int depth) {
    if (depth > kRigJsonMaxDepth) return fail("nested deeper than the reader's limit");
    out->type = Json::kArray;
    ++p_;
    skipSpace();
    if (p_ != end_ && *p_ == ']') {
      ++p_;
      return true;
    }
    for (;;) {
      skipSpace();
      out->items.emplace_back();
      if (!value(&out->items.back(), depth)) return false;
      skipSpace();
      if (p_ != end_ && *p_ == ',') {
        ++p_;
        continue;
      }
      if (p_ != end_ && *p_ == ']') {
        ++p_;
        return true;
      }
      return fail("expected ',' or ']'");
    }
  }

  bool hex4(unsigned* code) {
    if (end_ - p_ < 4) return fail("truncated \\u escape");
    *code = 0;
    for (int k = 0; k < 4; ++k) {
      const char c = *p_++;
      unsigned digit;
      if (c >= '0' && c <= '9') digit = static_cast<unsigned>(c - '0');
      else if (c >= 'a' && c <= 'f') digit = static_cast<unsigned>(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F') digit = static_cast<unsigned>(c - 'A' + 10);
      else return fail("bad \\u escape");
      *code = *code * 16 + digit;
    }
    return true;
  }

  static void appendUtf8(unsigned code, std::string* out) {
    if (code < 0x80) {
      out->push_back(static_cast<char>(code));
    } else if (code < 0x800) {
      out->push_back(static_cast<char>(0xC0 | (code >> 6)));
      out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
    } else if (code < 0x10000) {
      out->push_back(static_cast<char>(0xE0 | (code >> 12)));
      out->push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
      out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
    } else {
      out->push_back(static_cast<char>(0xF0 | (code >> 18)));
      out->push_back(static_cast<char>(0x80 | ((code >> 12) & 0x3F)));
      out->push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
      out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
    }
  }

  bool escape(std::string* out) {
    if (p_ == end_) return fail("unterminated string");
    const char c = *p_++;
    switch (c) {
      case '"': case '\\': case '/': out->push_back(c); return true;
      case 'b': out->push_back('\b'); return true;
      case 'f': out->push_back('\f'); return true;
      case 'n': out->push_back('\n'); return true;
      case 'r': out->push_back('\r'); return true;
      case 't': out->push_back('\t'); return true;
      case 'u': break;
      default: return fail("bad escape in a string");
    }
    unsigned code;
    if (!hex4(&code)) return false;
    if (code >= 0xDC00 && code <= 0xDFFF) return fail("lone low surrogate in a string");
    if (code >= 0xD800 && code <= 0xDBFF) {
      unsigned low;
      if (end_ - p_ < 2 || p_[0] != '\\' || p_[1] != 'u') return fail("lone high surrogate in a string");
      p_ += 2;
      if (!hex4(&low)) return false;
      if (low < 0xDC00 || low > 0xDFFF) return fail("lone high surrogate in a string");
      code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
    }
    appendUtf8(code, out);
    return true;
  }

  bool string(std::string* out) {
    ++p_;  // the opening quote
    for (;;) {
      if (p_ == end_) return fail("unterminated string");
      const char c = *p_++;
      if (c == '"') return true;
      if (static_cast<unsigned char>(c) < 0x20) return fail("control character in a string");
      if (c == '\\') {
        if (!escape(out)) return false;
      } else {
        out->push_back(c);
      }
    }
  }

  bool digits() {
    if (p_ == end_ || *p_ < '0' || *p_ > '9') return fail("expected a digit");
    while (p_ != end_ && *p_ >= '0' && *p_ <= '9') ++p_;
    return true;
  }

  bool number(Json* out) {
    const char* start = p_;
    if (*p_ == '-') ++p_;
    if (p_ == end_) return fail("expected a value");
    if (*p_ == '0') {
      ++p_;
    } else if (*p_ >= '1' && *p_ <= '9') {
      digits();
    } else {
      return fail("expected a value");
    }
    bool integer = true;
    if (p_ != end_ && *p_ == '.') {
      ++p_;
      integer = false;
      if (!digits()) return false;
    }
    if (p_ != end_ && (*p_ == 'e' || *p_ == 'E')) {
      ++p_;
      integer = false;
      if (p_ != end_ && (*p_ == '+' || *p_ == '-')) ++p_;
      if (!digits()) return false;
    }
    out->type = Json::kNumber;
    out->integer = integer;
    // The literal, with '.' as the locale writes it, for strtod (which stops at the copy's end).
    std::string literal(start, p_);
    const char point = *std::localeconv()->decimal_point;
    for (char& c : literal) {
      if (c == '.') c = point;
    }
    out->number = std::strtod(literal.c_str(), nullptr);
    // nlohmann reads "-0" as the integer 0: +0, as tinygltf then gives it.
    if (integer && out->number == 0) out->number = 0;
    if (!std::isfinite(out->number)) return fail("number out of range");
    return true;
  }
};

// Reading the extension's members, with the JSON pointer of the object being read for messages.
struct Reader {
  std::string pointer;
  std::string* error;
  int node_count;

  bool fail(const std::string& key, const std::string& message) const {
    *error = pointer + (key.empty() ? "" : "/" + key) + ": " + message;
    return false;
  }
  bool numbers(const Json& object, const char* key, int count, double* out) const {
    const Json* value = object.member(key);
    if (!value || value->type != Json::kArray || value->items.size() != static_cast<std::size_t>(count))
      return fail(key, "must be an array of " + std::to_string(count) + " numbers");
    for (int k = 0; k < count; ++k) {
      if (value->items[k].type != Json::kNumber) return fail(std::string(key) + "/" + std::to_string(k), "must be a number");
      out[k] = value->items[k].number;
    }
    return true;
  }
  bool number(const Json& object, const char* key, double* out) const {
    const Json* value = object.member(key);
    if (!value || value->type != Json::kNumber) return fail(key, "must be a number");
    *out = value->number;
    return true;
  }
  // A node index in [lowest, node_count).
  bool node(const Json& object, const char* key, int lowest, int* out) const {
    const Json* value = object.member(key);
    if (!value || value->type != Json::kNumber || !value->integer) return fail(key, "must be a node index");
    if (value->number < lowest || value->number >= node_count)
      return fail(key, "must be a node index below " + std::to_string(node_count) + (lowest < 0 ? " (or -1)" : ""));
    *out = static_cast<int>(value->number);
    return true;
  }
  bool text(const Json& object, const char* key, std::string* out) const {
    const Json* value = object.member(key);
    if (!value || value->type != Json::kString) return fail(key, "must be a string");
    *out = value->text;
    return true;
  }
  bool keys(const Json& object, const char* key, MuscleRig<double>* rig, int* begin, int* count) const {
    *begin = static_cast<int>(rig->keys.size());
    *count = 0;
    const Json* value = object.member(key);
    if (!value) return true;
    if (value->type != Json::kArray) return fail(key, "must be an array of [at, up, side, scale] keys");
    for (std::size_t k = 0; k < value->items.size(); ++k) {
      const Json& item = value->items[k];
      if (item.type != Json::kArray || item.items.size() != 4) return fail(std::string(key) + "/" + std::to_string(k), "must be [at, up, side, scale]");
      double v[4];
      for (int c = 0; c < 4; ++c) {
        if (item.items[c].type != Json::kNumber) return fail(std::string(key) + "/" + std::to_string(k), "must hold numbers");
        v[c] = item.items[c].number;
      }
      rig->keys.push_back({v[0], v[1], v[2], v[3]});
      ++*count;
    }
    return true;
  }
};

bool readMuscle(const Json& item, const Reader& in, RigFile* out) {
  if (item.type != Json::kObject) return in.fail("", "must be an object");
  RigMuscle<double> muscle;
  std::string name;
  int skinned = -1;
  if (!in.text(item, "name", &name)) return false;
  bool corrective = false;
  if (const Json* kind = item.member("kind")) {
    if (kind->type != Json::kString || (kind->text != "muscle" && kind->text != "corrective"))
      return in.fail("kind", "must be \"muscle\" or \"corrective\"");
    corrective = kind->text == "corrective";
  }
  int helpers[3] = {-1, -1, -1};
  if (const Json* value = item.member("helperNodes")) {
    if (value->type != Json::kArray || value->items.size() != 3) return in.fail("helperNodes", "must be an array of 3 node indices");
    Reader at{in.pointer + "/helperNodes", in.error, in.node_count};
    for (int k = 0; k < 3; ++k) {
      Json wrapper;
      wrapper.type = Json::kObject;
      wrapper.members.emplace_back(std::to_string(k), value->items[k]);
      if (!at.node(wrapper, std::to_string(k).c_str(), 0, &helpers[k])) return false;
    }
  }
  if (!in.node(item, "skinnedNode", 0, &skinned) || !in.node(item, "originNode", 0, &muscle.origin_joint) ||
      !in.node(item, "insertionNode", 0, &muscle.insertion_joint) || !in.node(item, "carrierNode", 0, &muscle.carrier_joint) ||
      !in.numbers(item, "originLocal", 3, muscle.origin_local) || !in.numbers(item, "insertionLocal", 3, muscle.insertion_local) ||
      !in.number(item, "restLength", &muscle.rest_length) || !in.number(item, "compression", &muscle.compression) ||
      !in.number(item, "stretch", &muscle.stretch) || !in.numbers(item, "fibreLocal", 3, muscle.fibre_local) ||
      !in.numbers(item, "upLocal", 3, muscle.up_local) || !in.numbers(item, "twistAxisLocal", 3, muscle.twist_axis_local) ||
      !in.numbers(item, "insertionBindInOrigin", 4, muscle.insertion_bind_in_origin) ||
      !in.number(item, "driverFraction", &muscle.driver_fraction) || !in.numbers(item, "driverOffset", 2, muscle.driver_offset) ||
      !in.numbers(item, "skinnedInCarrier", 16, muscle.skinned_in_carrier) ||
      !in.keys(item, "ratioKeys", &out->rig, &muscle.ratio_key_begin, &muscle.ratio_key_count) ||
      !in.keys(item, "twistKeys", &out->rig, &muscle.twist_key_begin, &muscle.twist_key_count))
    return false;
  out->rig.muscles.push_back(muscle);
  out->muscle_names.push_back(name);
  out->muscle_corrective.push_back(corrective);
  out->skinned_nodes.push_back(skinned);
  out->helper_nodes.insert(out->helper_nodes.end(), helpers, helpers + 3);
  return true;
}

bool readJiggle(const Json& item, const Reader& in, RigFile* out) {
  if (item.type != Json::kObject) return in.fail("", "must be an object");
  JiggleSpec<double> spec;
  std::string name;
  if (!in.text(item, "name", &name) || !in.node(item, "node", 0, &spec.joint) || !in.node(item, "parentNode", -1, &spec.parent) ||
      !in.node(item, "rootNode", -1, &spec.root) || !in.number(item, "stiffness", &spec.stiffness) ||
      !in.number(item, "damping", &spec.damping) || !in.number(item, "clampMajorDeg", &spec.clamp_major_deg) ||
      !in.number(item, "clampMinorDeg", &spec.clamp_minor_deg) || !in.numbers(item, "aimAxis", 3, spec.aim_axis) ||
      !in.numbers(item, "majorAxis", 3, spec.major_axis) || !in.numbers(item, "rootUp", 3, spec.root_up) ||
      !in.number(item, "length", &spec.length))
    return false;
  // The float rig an engine runs must accept it too: a double spec at the edge of a limit could
  // round across it.
  JiggleSpec<float> narrow;
  narrow.joint = spec.joint;
  narrow.parent = spec.parent;
  narrow.root = spec.root;
  for (int k = 0; k < 3; ++k) {
    narrow.aim_axis[k] = static_cast<float>(spec.aim_axis[k]);
    narrow.major_axis[k] = static_cast<float>(spec.major_axis[k]);
    narrow.root_up[k] = static_cast<float>(spec.root_up[k]);
  }
  narrow.length = static_cast<float>(spec.length);
  narrow.stiffness = static_cast<float>(spec.stiffness);
  narrow.damping = static_cast<float>(spec.damping);
  narrow.clamp_major_deg = static_cast<float>(spec.clamp_major_deg);
  narrow.clamp_minor_deg = static_cast<float>(spec.clamp_minor_deg);
  const char* problem = jiggleSpecProblem(spec, in.node_count);
  if (!*problem) problem = jiggleSpecProblem(narrow, in.node_count);
  if (*problem) return in.fail("", problem);
  out->jiggles.push_back(spec);
  out->jiggle_names.push_back(name);
  return true;
}

}  // namespace

bool readRigJson(const char* text, std::size_t size, int node_count, RigFile* out, std::string* error) {
  *out = RigFile();
  if (!text) {
    *error = "no JSON text";
    return false;
  }
  if (size > kRigJsonMaxBytes) {
    *error = "JSON text larger than the reader's limit of " + std::to_string(kRigJsonMaxBytes) + " bytes";
    return false;
  }
  if (node_count <= 0) {
    *error = "the node count must be positive";
    return false;
  }
  Json root;
  if (!Parser(text, size).parseDocument(&root, error)) return false;
  Reader in{"", error, node_count};
  if (root.type != Json::kObject) return in.fail("", "the extension must be a JSON object");
  const Json* version = root.member("version");
  if (!version || version->type != Json::kNumber || !version->integer || version->number != 1) return in.fail("version", "must be 1");
  const Json* muscles = root.member("muscles");
  if (!muscles || muscles->type != Json::kArray) return in.fail("muscles", "must be an array");
  out->rig.joint_count = node_count;
  for (std::size_t m = 0; m < muscles->items.size(); ++m) {
    if (!readMuscle(muscles->items[m], Reader{"/muscles/" + std::to_string(m), error, node_count}, out)) return false;
  }
  const char* problem = rigProblem(out->rig);
  if (*problem) return in.fail("muscles", problem);
  if (const Json* jiggles = root.member("jiggles")) {
    if (jiggles->type != Json::kArray) return in.fail("jiggles", "must be an array");
    for (std::size_t j = 0; j < jiggles->items.size(); ++j) {
      if (!readJiggle(jiggles->items[j], Reader{"/jiggles/" + std::to_string(j), error, node_count}, out)) return false;
    }
  }
  prepareMuscleRig(&out->rig);
  return true;
}

}  // namespace rigbake::runtime
