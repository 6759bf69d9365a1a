#include "kccd/input_error.hpp"

#include <utility>

namespace kccd {
namespace {

// Length of the UTF-8 sequence starting at s[i] (0 when it is not valid UTF-8).
std::size_t utf8Length(std::string_view s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t n = 0;
  if (c >= 0xC2 && c <= 0xDF)
    n = 2;
  else if (c >= 0xE0 && c <= 0xEF)
    n = 3;
  else if (c >= 0xF0 && c <= 0xF4)
    n = 4;
  else
    return 0;
  if (i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  // No overlong forms, no surrogates (U+D800 ... U+DFFF), nothing above U+10FFFF.
  const unsigned char second = byte(i + 1);
  if ((c == 0xE0 && second < 0xA0) || (c == 0xED && second > 0x9F) || (c == 0xF0 && second < 0x90) ||
      (c == 0xF4 && second > 0x8F))
    return 0;
  return n;
}

// A message: the location's text, then the problem.
std::string joined(const std::string& where, const std::string& problem) {
  return where.empty() ? problem : where + ": " + problem;
}

}  // namespace

std::string InputLocation::text() const {
  std::string out = source;
  if (line > 0) {
    out.append(1, ':').append(std::to_string(line));
    if (column > 0) out.append(1, ':').append(std::to_string(column));
  }
  if (!field.empty()) out.append(out.empty() ? "" : ": ").append(field);
  return out;
}

InputError::InputError(const std::string& message)
    : std::runtime_error(message), data_(std::make_shared<const Data>(Data{{}, message})) {}

InputError::InputError(InputLocation where, const std::string& problem)
    : std::runtime_error(joined(where.text(), problem)),
      data_(std::make_shared<const Data>(Data{std::move(where), problem})) {}

std::optional<std::string> rangeProblem(double value, double lo, double hi) {
  if (value >= lo && value <= hi) return std::nullopt;
  return "must be in [" + messageNumber(lo) + ", " + messageNumber(hi) + "], got " + messageNumber(value);
}

std::string InputError::messageFrom(std::string_view source) const {
  InputLocation where = location();
  where.source = source;
  return joined(where.text(), problem());
}

bool isUtf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    if (static_cast<unsigned char>(text[i]) < 0x80) {
      ++i;
      continue;
    }
    const std::size_t n = utf8Length(text, i);
    if (n == 0) return false;
    i += n;
  }
  return true;
}

std::string printable(std::string_view text, std::size_t max_bytes) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    if (out.size() >= max_bytes) {
      out += "...";
      break;
    }
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
      ++i;
      continue;
    }
    const std::size_t n = c >= 0x80 ? utf8Length(text, i) : 0;
    if (n > 0) {
      out.append(text.substr(i, n));
      i += n;
      continue;
    }
    out += "\\x";
    out += hex[c >> 4];
    out += hex[c & 15];
    ++i;
  }
  return out;
}

}  // namespace kccd
