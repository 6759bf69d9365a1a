// What the kccd subcommands print: one-line messages, numbers, JSON values, progress.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "kccd/format_number.hpp"
#include "kccd/ssch.hpp"

namespace kccd::cli {

/// `text` as one printable line (control bytes escaped, line breaks as spaces), for messages.
std::string oneLine(const std::string& text);

/// A non-finite value as JSON null, otherwise the number.
nlohmann::json number(double value);
nlohmann::json vec3(const Vec3& v);

/// Progress of long work on stderr: a bar on a terminal, a line every few seconds otherwise,
/// nothing when quiet.
class Progress {
 public:
  Progress(std::string what, bool quiet);
  ~Progress();
  /// Reports the fraction done (0 ... 1); `detail` (e.g. rate and time left) follows the bar.
  void update(double fraction, const std::string& detail = {});
  /// Ends the display (also done by the destructor).
  void finish();

 private:
  std::string what_;
  bool quiet_, tty_, shown_ = false, finished_ = false;
  double last_ = -1.0;
  double last_time_ = 0.0;
  std::size_t shown_width_ = 0;
};

/// kccd::formatNumber under the name the commands knew it by (`digits` significant digits).
inline std::string format(double value, int digits = 10) { return formatNumber(value, digits); }

}  // namespace kccd::cli
