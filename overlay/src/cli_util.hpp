// Helpers shared by the kccd subcommands: one-line errors, number lists, JSON conversions.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "kccd/model.hpp"

namespace kccd::cli {

/// A user error: printed as one line, exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `text` as one printable line (control bytes escaped, line breaks as spaces), for messages.
std::string oneLine(const std::string& text);

/// A command-line parser message made readable: one line, huge bounds (DBL_MAX) written short.
std::string optionMessage(const std::string& text);

/// An option validator: a finite number in [lo, hi] (NaN and infinities are refused).
CLI::Validator finiteIn(double lo, double hi);

/// Parses "a,b,c" into numbers; `option` names the flag in error messages.
std::vector<double> parseList(const std::string& text, const std::string& option);

/// The interval box from `--state` (a single configuration) or `--lower`/`--upper`, each checked
/// against the model's state size; `missing` is the message when neither is complete. With
/// `finite`, NaN and infinite values are rejected too (else they reach the query as a status).
struct StateBox {
  std::vector<double> lower, upper;
  bool point = false;  ///< given with --state
};
StateBox parseStateBox(const Model& m, const std::string& state, const std::string& lower, const std::string& upper,
                       const std::string& missing, bool finite);

/// Checks a `--points` value (the number of core points of a fit).
void checkCorePoints(int k);

/// A non-finite value as JSON null, otherwise the number.
nlohmann::json number(double value);
nlohmann::json vec3(const Vec3& v);

/// Loads a model, turning every failure into one line on stderr (throws UsageError); with `text`,
/// also returns the file's text as it was read.
Model loadOrExplain(const std::string& path, std::string* text = nullptr);

}  // namespace kccd::cli

namespace kccd::cli {

/// Progress of long work on stderr: a bar on a terminal, a line every few seconds otherwise,
/// nothing when quiet.
class Progress {
 public:
  Progress(std::string what, bool quiet);
  ~Progress();
  /// Reports the fraction done (0 ... 1).
  void update(double fraction);
  /// Ends the display (also done by the destructor).
  void finish();

 private:
  std::string what_;
  bool quiet_, tty_, shown_ = false, finished_ = false;
  double last_ = -1.0;
  double last_time_ = 0.0;
};

/// Writes `text` to `path` through a new uniquely named file in the same folder and a rename:
/// readers never see a partial file. A symbolic link stays a link (its target is replaced) and an
/// existing file keeps its mode. Throws UsageError naming the path.
void writeFileAtomically(const std::string& path, const std::string& text);

/// Replaces the text of the file at `path` by `edit(text)`, atomically, holding an exclusive lock
/// (flock) on the file from the read to the rename, so concurrent edits of one file apply one after
/// the other and none is lost. With `expected`, the edit is refused when the file no longer holds
/// that text. A std::runtime_error from `edit` or a failed read or write becomes a UsageError
/// naming the file, and the file stays as it was.
void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected = nullptr);

/// Prints a number with `digits` significant digits (nearest).
std::string format(double value, int digits = 10);

}  // namespace kccd::cli
