// Putting a rendered layer onto a camera frame.
#pragma once

#include <span>

#include <opencv2/core.hpp>

namespace kccd::render {

/// Blends a straight-alpha BGRA layer (Frame::bgra) over a BGR frame of the same size, in place:
/// out = layer * a + frame * (1 - a), a = alpha / 255, rounded to nearest. Throws
/// std::invalid_argument when the types (CV_8UC3, CV_8UC4) or sizes do not match.
void compositeOver(cv::Mat& frame_bgr, const cv::Mat& layer_bgra);
/// The same where the layer is known to be transparent outside the disjoint rectangles `drawn`
/// (Frame::drawn): only those are touched; the result is the whole blend's.
void compositeOver(cv::Mat& frame_bgr, const cv::Mat& layer_bgra, std::span<const cv::Rect> drawn);

}  // namespace kccd::render
