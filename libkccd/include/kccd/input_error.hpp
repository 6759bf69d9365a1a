// The one error type for input that cannot be used (models, camera files, parts, URDFs, ...).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace kccd {

/// Input that cannot be used. The message is one line: "file[:line[:column]]: field: problem".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `value` as messages print it: printf's %g with `digits` significant digits ("0.137", "1e+300").
std::string messageNumber(double value, int digits = 10);

/// True when `text` is valid UTF-8: no stray or truncated sequences, overlong forms, surrogates or
/// code points above U+10FFFF (what JSON output needs of every name it prints).
bool isUtf8(std::string_view text);

/// `text` made safe to quote in a one-line message: control bytes, DEL and bytes that are not
/// UTF-8 become \xNN, and text longer than `max_bytes` is cut with "...".
std::string printable(std::string_view text, std::size_t max_bytes = 80);

}  // namespace kccd
