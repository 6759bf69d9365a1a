// How large text is on a camera image: one rule for every label, legend and status line, so that
// text stays readable on a small image and keeps its proportion on a large one.
#pragma once

#include <string>

#include <opencv2/imgproc.hpp>

namespace kccd::render {

/// The smallest font scale drawn (letters about 7 px high): smaller Hershey text cannot be read.
inline constexpr double kMinTextScale = 0.3;

/// Hershey simplex text at one size and the spacing that goes with it, in pixels.
struct TextMetrics {
  int font = cv::FONT_HERSHEY_SIMPLEX;  ///< cv::putText's font face
  double scale = 0.8;                   ///< cv::putText's font scale
  int thickness = 2;                    ///< its stroke width
  int height = 18;                      ///< a line's height above the baseline (cv::getTextSize)
  int descent = 8;                      ///< a line's depth below the baseline
  int pad = 9;                          ///< between text and the edge of the box behind it
  int margin = 9;                       ///< between a box and the edge of the image
  /// The width of `text` drawn at this size.
  int width(const std::string& text) const;
};

/// The text size for an image `rows` pixels high: font scale rows / 900 (0.8 at 720 rows, 2.4 at
/// 2160) but at least kMinTextScale, stroke 2 x scale rounded (at least 1), pad and margin half the
/// line height (at least 2).
TextMetrics textMetrics(int rows);

}  // namespace kccd::render
