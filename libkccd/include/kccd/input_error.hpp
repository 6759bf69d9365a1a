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

/// `text` made safe to quote in a one-line message: control bytes, DEL and bytes that are not
/// UTF-8 become \xNN, and text longer than `max_bytes` is cut with "...".
std::string printable(std::string_view text, std::size_t max_bytes = 80);

}  // namespace kccd
