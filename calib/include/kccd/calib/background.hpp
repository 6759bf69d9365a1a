// Robot masks from a fixed camera's recording: the scene without the robot (each pixel's median
// over frames in which the robot, drawn at the logged state, is away from it), and in a frame the
// pixels that differ from it. A robot that rests in one pose most of the time is no ghost in the
// background, as it would be in a plain median: the frames that show it there do not count there.
// What else moves (a person, a door) or changes (lighting beyond a global gain, shadows) is
// foreground too; the mask refinement's cleaning and robust loss take what they can of that.
#pragma once

#include <span>

#include <opencv2/core.hpp>

#include "kccd/calib/silhouette.hpp"
#include "kccd/input_error.hpp"

namespace kccd::calib {

/// One frame of the recording and where the robot may be in it.
struct BackgroundSample {
  cv::Mat bgr;    ///< 8-bit BGR, every sample the same size
  cv::Mat robot;  ///< CV_8UC1 of the same size: non-zero where the robot may be (its drawing, widened by the pose's
                  ///< uncertainty)
};

/// The scene without the robot.
struct Background {
  cv::Mat bgr;      ///< CV_8UC3: each pixel's median colour over the samples that leave it free
  cv::Mat spread;   ///< CV_32F: the robust spread (1.4826 x MAD) of those samples' colour distances to it
  cv::Mat known;    ///< CV_8UC1: 255 where at least `min_samples` samples leave the pixel free, else 0
  int samples = 0;  ///< samples it was made from
};

/// The background of `samples`. Pixels that fewer than `min_samples` samples leave free are
/// unknown. Throws InputError for no sample, or samples not all 8-bit BGR of one size with robot
/// masks of that size.
Background estimateBackground(std::span<const BackgroundSample> samples, int min_samples = 3);

/// Where the robot may be in a picture through `camera`: its volumes' drawing widened by `widen_px`
/// (CV_8UC1, 255 there): a BackgroundSample's robot.
cv::Mat robotRegion(const Camera& camera, std::span<const PlacedVolume> volumes, double widen_px);

/// How a frame's pixels are told from the background.
struct ForegroundOptions {
  double min_difference = 36.0;  ///< colour distance (sum over B, G, R of 0-255) below which a pixel is background
  double spread_factor = 4.0;    ///< ... or below this many times the pixel's spread
};

/// The robot mask of `frame`: 255 where the frame differs from the background (after a global gain
/// that matches their brightness away from `frame.robot`), opened over 1 px and closed over 3 px, else 0;
/// 0 where the background is unknown. Throws InputError for a frame of another size or type.
cv::Mat foregroundMask(const BackgroundSample& frame, const Background& background,
                       const ForegroundOptions& options = {});

}  // namespace kccd::calib
