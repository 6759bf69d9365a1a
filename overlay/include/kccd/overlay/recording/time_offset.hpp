// The video clock (each frame's time) and the search for the offset between the video's clock
// and a state log's (log time = video time + offset).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

class FrameSource;

/// Frame i's time on the video clock, in seconds: the i-th entry of a frame-times list (NaN past
/// its end or where it has none), or i / fps without one.
class FrameClock {
 public:
  /// `frame_times` (may be empty) wins over `fps`; without either, every time is NaN.
  FrameClock(std::vector<double> frame_times, double fps);
  double operator()(std::size_t index) const;
  /// The frame rate to write a video at: the declared fps, else 1 / the median step of the frame
  /// times, else 25.
  double nominalFps() const;
  bool fromFrameTimes() const { return !times_.empty(); }

 private:
  std::vector<double> times_;
  double fps_;
};

/// No offset in the range makes the video follow the log, or too few frames to tell. One line
/// starting with the label given to findTimeOffset.
class TimeOffsetError : public InputError {
 public:
  using InputError::InputError;
};

/// What the search found: the offset (seconds), its Pearson correlation and the number of frame
/// pairs it rests on.
struct TimeOffset {
  double offset = 0.0;
  double correlation = 0.0;
  std::size_t pairs = 0;
};

/// Finds the offset in [lo, hi] at which the image motion between consecutive frames (mean
/// absolute difference of grey frames downscaled 8×) best follows the robot's motion in the log
/// between the same two instants (sum of the absolute changes of the state values): the largest
/// Pearson correlation on a grid of half the smaller of the frame and log periods. Reads `video`
/// to its end (a frame that cannot be decoded ends the reading). `max_gap` is the largest log gap
/// bridged (stateAt). Throws TimeOffsetError naming `label` when fewer than 11 frames have
/// times, the grid exceeds 200,000 steps or the best correlation is below 0.3.
TimeOffset findTimeOffset(FrameSource& video, const FrameClock& clock, const StateLog& log, double max_gap, double lo,
                          double hi, const std::string& label);

}  // namespace kccd::overlay
