// The one error type for input that cannot be used (models, camera files, parts, URDFs, ...).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "kccd/format_number.hpp"

namespace kccd {

/// Where in an input a problem lies. Every part may be unknown (empty, or 0).
struct InputLocation {
  std::string source;      ///< the input as messages show it: a file name, or an option such as "--video x"
  std::size_t line = 0;    ///< 1-based line; 0 when unknown
  std::size_t column = 0;  ///< 1-based column; 0 when unknown (or no line is known)
  std::string field;       ///< the field as messages name it ("joints[2].axis", "column 'time'", "file")

  /// "source[:line[:column]][: field]", the start of a message (empty when nothing is known).
  std::string text() const;
};

/// Input that cannot be used. The message is one line: "file[:line[:column]]: field: problem";
/// the location and the problem are kept as data beside it. A request's field out of range (an
/// option, an argument) has a field and no source: a front end says the field in its own spelling
/// (`--fps` on the command line, `fps=` in Python).
class InputError : public std::runtime_error {
 public:
  /// An error whose message is `message` as given: the location is unknown, the problem is the message.
  explicit InputError(const std::string& message);
  explicit InputError(const char* message) : InputError(std::string(message)) {}
  /// An error at `where`: the message is where.text() and `problem` joined by ": ".
  InputError(InputLocation where, const std::string& problem);

  /// Where the problem lies (as given to the constructor).
  const InputLocation& location() const noexcept { return data_->location; }
  /// The message without its location.
  const std::string& problem() const noexcept { return data_->problem; }
  /// The same message with `source` shown as its source, e.g. a camera file's name where the
  /// error says "camera" (an error without a location gets `source` in front).
  std::string messageFrom(std::string_view source) const;

 private:
  struct Data {
    InputLocation location;
    std::string problem;
  };
  std::shared_ptr<const Data> data_;  // shared: copying an exception must not throw
};

/// How a front end spells a request's field in messages ("fps" -> "--fps" on the command line). An
/// empty one leaves the field as it is (Python's keyword, a manifest's key).
using FieldSpelling = std::function<std::string(const std::string& field)>;
/// `field` as `spell` spells it.
inline std::string spelledField(const FieldSpelling& spell, const std::string& field) {
  return spell ? spell(field) : field;
}

/// A problem with a request's field `spelled` (as the front end spells it): an InputError with that
/// field and no source.
inline InputError requestFieldError(const std::string& spelled, const std::string& problem) {
  return InputError(InputLocation{{}, 0, 0, spelled}, problem);
}

/// What is wrong with a request's number `value` that must lie in [lo, hi]: "must be in [lo, hi],
/// got value" (NaN is outside), or none. The one wording of every front end's range checks.
std::optional<std::string> rangeProblem(double value, double lo, double hi);

/// `value` as messages print it: printf's %g with `digits` significant digits (formatNumber).
inline std::string messageNumber(double value, int digits = 10) { return formatNumber(value, digits); }

/// True when `text` is valid UTF-8: no stray or truncated sequences, overlong forms, surrogates or
/// code points above U+10FFFF (what JSON output needs of every name it prints).
bool isUtf8(std::string_view text);

/// `text` made safe to quote in a one-line message: control bytes, DEL and bytes that are not
/// UTF-8 become `\xNN`, and text longer than `max_bytes` is cut with "...".
std::string printable(std::string_view text, std::size_t max_bytes = 80);

}  // namespace kccd
