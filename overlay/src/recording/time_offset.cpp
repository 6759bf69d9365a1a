#include "kccd/overlay/recording/time_offset.hpp"

#include "kccd/overlay/recording/frame_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/format_number.hpp"
#include "kccd/overlay/recording/video_source.hpp"

namespace kccd::overlay {

FrameClock::FrameClock(std::vector<double> frame_times, double fps) : times_(std::move(frame_times)), fps_(fps) {}

double FrameClock::operator()(std::size_t index) const {
  if (!times_.empty()) return index < times_.size() ? times_[index] : std::numeric_limits<double>::quiet_NaN();
  return fps_ > 0.0 ? static_cast<double>(index) / fps_ : std::numeric_limits<double>::quiet_NaN();
}

double FrameClock::nominalFps() const {
  if (fps_ > 0.0 && fps_ < 1e6) return fps_;
  std::vector<double> steps;
  for (std::size_t i = 1; i < times_.size(); ++i)
    if (std::isfinite(times_[i]) && std::isfinite(times_[i - 1])) steps.push_back(times_[i] - times_[i - 1]);
  if (steps.empty()) return 25.0;
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  const double median = steps[steps.size() / 2];
  return median > 0.0 ? 1.0 / median : 25.0;
}

TimeOffset findTimeOffset(FrameSource& video, const FrameClock& clock, const StateLog& log, double max_gap, double lo,
                          double hi, const std::string& label) {
  // Pair k: frames k and k + 1, their times and the image motion between them.
  std::vector<double> t0, t1, motion;
  cv::Mat frame, grey, small, previous;
  double previous_time = 0.0;
  for (;;) {
    const std::size_t i = video.nextIndex();
    bool got = false;
    try {
      got = video.read(frame);
    } catch (const VideoError&) {
      got = false;  // the frames before it still count; the overlay's own pass reports it
    }
    if (!got) break;
    const double t = clock(i);
    if (frame.channels() == 3)
      cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    else if (frame.channels() == 4)
      cv::cvtColor(frame, grey, cv::COLOR_BGRA2GRAY);
    else
      grey = frame;
    cv::resize(grey, small, cv::Size(std::max(1, grey.cols / 8), std::max(1, grey.rows / 8)), 0, 0, cv::INTER_AREA);
    small.convertTo(small, CV_32F);
    if (!previous.empty() && previous.size() == small.size() && std::isfinite(t) && std::isfinite(previous_time)) {
      t0.push_back(previous_time);
      t1.push_back(t);
      motion.push_back(cv::norm(small, previous, cv::NORM_L1) / static_cast<double>(small.total()));
    }
    std::swap(previous, small);
    previous_time = t;
  }
  if (motion.size() < 10)
    throw TimeOffsetError(label + ": needs at least 11 frames, the video has " + std::to_string(motion.size() + 1));

  const double frame_period = (t1.back() - t0.front()) / static_cast<double>(motion.size());
  const double log_period = log.medianPeriod() > 0 ? log.medianPeriod() : frame_period;
  const double step = 0.5 * std::min(frame_period, log_period);
  const double steps = std::ceil((hi - lo) / step);
  if (!(steps <= 200000))
    throw TimeOffsetError(label + ": the range is more than 200000 steps of " + formatNumber(step, 3) + " s");
  const std::size_t n = log.stateSize();
  std::vector<double> qa(n), qb(n);
  TimeOffset best{lo, -2.0, 0};
  for (long k = 0; k <= static_cast<long>(steps); ++k) {
    const double offset = std::min(hi, lo + static_cast<double>(k) * step);
    std::size_t m = 0;
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (std::size_t p = 0; p < motion.size(); ++p) {
      if (stateAt(log, t0[p] + offset, max_gap, qa) == StateMatch::None ||
          stateAt(log, t1[p] + offset, max_gap, qb) == StateMatch::None)
        continue;
      double d = 0.0;
      for (std::size_t v = 0; v < n; ++v) d += std::fabs(qb[v] - qa[v]);
      const double x = motion[p];
      sx += x, sy += d, sxx += x * x, syy += d * d, sxy += x * d;
      ++m;
    }
    if (m < 10) continue;
    const double mm = static_cast<double>(m);
    const double cov = sxy - sx * sy / mm, vx = sxx - sx * sx / mm, vy = syy - sy * sy / mm;
    if (!(vx > 0 && vy > 0)) continue;
    const double r = cov / std::sqrt(vx * vy);
    if (r > best.correlation) best = {offset, r, m};
  }
  if (best.correlation < 0.3)
    throw TimeOffsetError(label +
                          ": no offset in the range makes the video's motion follow the log's (best correlation " +
                          (best.correlation > -2.0 ? formatNumber(best.correlation, 2)
                                                   : std::string("none: too few frames with a state")) +
                          "); give the offset");
  return best;
}

}  // namespace kccd::overlay
