#include "kccd/format_number.hpp"

#include <charconv>
#include <cstdio>

namespace kccd {

std::string formatNumber(double value, int digits) {
  const int size = std::snprintf(nullptr, 0, "%.*g", digits, value);
  std::string text(static_cast<std::size_t>(size > 0 ? size : 0), '\0');
  std::snprintf(text.data(), text.size() + 1, "%.*g", digits, value);
  return text;
}

std::string shortestNumber(double value) {
  char buffer[32];  // the longest shortest form of a double is 24 characters
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return ec == std::errc() ? std::string(buffer, end) : std::string("?");
}

}  // namespace kccd
