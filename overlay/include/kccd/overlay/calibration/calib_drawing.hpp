// The pictures of calibration: the check image an operator accepts a pose by, and the labelling
// sheet that helps them pick points.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/overlay/labelling/labelling_candidates.hpp"

namespace kccd::overlay {

/// One correspondence as the check image shows it.
struct CheckPoint {
  cv::Point2d pixel;         ///< where it was seen
  cv::Point2d projected;     ///< its world point under the solved pose (NaN: behind the camera)
  double residual_px = 0.0;  ///< its reprojection residual (NaN: behind the camera)
  bool inlier = true;        ///< agrees with the pose (else drawn in red, to scale)
  std::string label;         ///< written next to it (empty: not written; rejected points always are)
};

/// The check image: `frame` (BGR, or a grey canvas when empty) with the solved volumes layer
/// (`volumes`, BGRA, may be empty) composited, then every point: a circle where it was seen, a
/// cross where the pose projects it, the residual vector magnified `magnify` times (rejected points:
/// to scale, in red, with name and residual); `headline` (lines) in a band at the bottom.
cv::Mat drawCheck(const cv::Mat& frame, cv::Size size, const cv::Mat& volumes, const std::vector<CheckPoint>& points,
                  const std::vector<std::string>& headline, double magnify);

/// The labelling sheet: `frame` with every detected tag outlined (green when the layout places it,
/// orange otherwise), its id and corner numbers 0..3, the numbered strong corners (magenta) and
/// the projected model points (blue crosses, with names).
cv::Mat drawSheet(const cv::Mat& frame, const LabellingCandidates& candidates);

}  // namespace kccd::overlay
