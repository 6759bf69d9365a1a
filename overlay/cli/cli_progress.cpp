#include "cli_progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <mutex>

#include "kccd/calib/image_file.hpp"

namespace kccd::cli {

namespace {
double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Progress::Progress(std::string what, bool quiet)
    : what_(std::move(what)), quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0), last_time_(nowSeconds()) {}

Progress::~Progress() { finish(); }

void Progress::update(double fraction, const std::string& detail) {
  if (quiet_ || finished_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const double t = nowSeconds();
  if (tty_) {
    // At most 1 % steps, and with a detail at most every 0.2 s (it changes every frame).
    if (fraction - last_ < 0.01 && fraction < 1.0 && (detail.empty() || t - last_time_ < 0.2)) return;
    last_time_ = t;
    const int width = 30, filled = static_cast<int>(fraction * width);
    std::string line = what_ + " [" + std::string(filled, '#') + std::string(width - filled, ' ') + "] " +
                       std::to_string(static_cast<int>(fraction * 100)) + "%" + (detail.empty() ? "" : " " + detail);
    const std::size_t len = line.size();
    if (len < shown_width_) line += std::string(shown_width_ - len, ' ');
    shown_width_ = std::max(shown_width_, len);
    {
      const std::lock_guard<std::mutex> lock(calib::stderrLock());  // frames may be decoded meanwhile
      std::cerr << "\r" << line << std::flush;
    }
    shown_ = true;
  } else if (t - last_time_ >= 5.0) {
    const std::lock_guard<std::mutex> lock(calib::stderrLock());
    std::cerr << what_ << ": " << static_cast<int>(fraction * 100) << "%" << (detail.empty() ? "" : " " + detail)
              << "\n";
    last_time_ = t;
  }
  last_ = fraction;
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!shown_) return;
  const std::lock_guard<std::mutex> lock(calib::stderrLock());
  std::cerr << "\r" << std::string(std::max(what_.size() + 40, shown_width_), ' ') << "\r" << std::flush;
}

}  // namespace kccd::cli
