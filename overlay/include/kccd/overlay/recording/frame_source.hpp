// A recording's frames, read in order, whatever holds them (a video file, an image sequence, the
// image topic of a robot log): what the overlay and the time-offset search read.
#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace kccd::overlay {

/// Frames read in order.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// The frame rate the recording declares, or 0 when it declares none.
  virtual double fps() const = 0;
  /// The number of frames the recording declares, or 0 when unknown.
  virtual std::size_t declaredFrames() const = 0;
  /// Reads the next frame into `frame` (8-bit BGR, or as decoded); false at the end. Throws an
  /// InputError naming the frame when it cannot be had.
  virtual bool read(cv::Mat& frame) = 0;
  /// Index of the next frame read() returns (0 before the first).
  virtual std::size_t nextIndex() const = 0;
};

/// A frame of a recording and its index (from 0).
struct SampledFrame {
  std::size_t index = 0;
  cv::Mat bgr;
};

/// About `count` (>= 1) frames spread evenly over what is left of `source` (all of them when it has
/// fewer), in order; one pass to its end, holding at most 2 x count frames. Throws what read()
/// throws.
std::vector<SampledFrame> sampleFrames(FrameSource& source, std::size_t count);

}  // namespace kccd::overlay
