#include "core/error.h"

#include <utility>

namespace rigbake {

namespace {
std::string format(const std::string& code, const std::string& where, const std::string& message) {
  return where.empty() ? code + ": " + message : code + " " + where + ": " + message;
}
}  // namespace

size_t utf8SequenceAt(const std::string& text, size_t i) {
  const auto byte = [&](size_t k) { return k < text.size() ? static_cast<unsigned char>(text[k]) : 0u; };
  const unsigned lead = byte(i);
  auto continues = [&](size_t k, unsigned low, unsigned high) { return byte(k) >= low && byte(k) <= high; };
  if (lead < 0x80) return 1;
  if (lead >= 0xC2 && lead <= 0xDF) return continues(i + 1, 0x80, 0xBF) ? 2 : 0;
  if (lead >= 0xE0 && lead <= 0xEF) {
    const unsigned low = lead == 0xE0 ? 0xA0 : 0x80, high = lead == 0xED ? 0x9F : 0xBF;
    return continues(i + 1, low, high) && continues(i + 2, 0x80, 0xBF) ? 3 : 0;
  }
  if (lead >= 0xF0 && lead <= 0xF4) {
    const unsigned low = lead == 0xF0 ? 0x90 : 0x80, high = lead == 0xF4 ? 0x8F : 0xBF;
    return continues(i + 1, low, high) && continues(i + 2, 0x80, 0xBF) && continues(i + 3, 0x80, 0xBF) ? 4 : 0;
  }
  return 0;
}

std::string printableLine(const std::string& text) {
  static const char kHex[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const size_t length = utf8SequenceAt(text, i);
    if (length == 0 || c < 0x20 || c == 0x7F) {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
      ++i;
      continue;
    }
    out.append(text, i, length);
    i += length;
  }
  return out;
}

// The text of an error comes in part from the input (a parser's "last read: ..." quotes the file's
// bytes, a path is whatever bytes the file system holds): made one printable line of valid UTF-8, so
// that it is one line on a terminal and a JSON string in build summaries and --json output.
Error::Error(const ErrorCode& code, std::string where, const std::string& message)
    : std::runtime_error(printableLine(format(code.name, where, message))),
      code_(&code),
      name_(code.name),
      where_(printableLine(where)) {}

void fail(const ErrorCode& code, const std::string& where, const std::string& message) {
  throw Error(code, where, message);
}

InvalidOption::InvalidOption(const std::string& field, const std::string& problem)
    : Error(errc::USAGE, field, problem), field_(field), problem_(problem) {}

void failOption(const std::string& field, const std::string& problem) { throw InvalidOption(field, problem); }

FixableByOption::FixableByOption(const ErrorCode& code, std::string where, const std::string& message, std::string field)
    : Error(code, std::move(where), message), field_(std::move(field)), message_(message) {}

}  // namespace rigbake
