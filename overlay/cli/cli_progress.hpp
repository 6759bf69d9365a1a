// Progress of a subcommand's long work on stderr.
#pragma once

#include <cstddef>
#include <string>

namespace kccd::cli {

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

}  // namespace kccd::cli
