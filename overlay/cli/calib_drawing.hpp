// The pictures of `kccd calib`: the check image an operator accepts a pose by, and the labelling
// sheet that helps them pick points.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/model.hpp"

namespace kccd::cli {

/// One correspondence as the check image shows it.
struct CheckPoint {
  cv::Point2d pixel;      ///< where it was seen
  cv::Point2d projected;  ///< its world point under the solved pose (NaN: behind the camera)
  double residual_px = 0.0;
  bool inlier = true;
  std::string label;      ///< written next to it (empty: not written; rejected points always are)
};

/// The volumes of `model` at `state` as the solved `camera` sees them, for the check image: a
/// BGRA layer coloured by a query at the state, with body names when there are at most 12 bodies
/// (more only cover each other); `renderer_name` gets the GL renderer's name. A camera the
/// renderer cannot draw is a UsageError naming `camera_name`.
cv::Mat checkVolumes(const Model& model, const calib::Camera& camera, std::span<const double> state,
                     const std::string& camera_name, std::string& renderer_name);

/// The check image: `frame` (BGR, or a grey canvas when empty) with the solved volumes layer
/// (`volumes`, BGRA, may be empty) composited, then every point: a circle where it was seen, a
/// cross where the pose projects it, the residual vector magnified `magnify` times (rejected points:
/// to scale, in red, with name and residual); `headline` (lines) in a band at the bottom.
cv::Mat drawCheck(const cv::Mat& frame, cv::Size size, const cv::Mat& volumes, const std::vector<CheckPoint>& points,
                  const std::vector<std::string>& headline, double magnify);

/// A candidate point for labelling.
struct SheetPoint {
  std::string name;
  cv::Point2d pixel;
};

/// The labelling sheet: `frame` with every detected tag outlined (green when the layout places it,
/// orange otherwise), its id and corner numbers 0..3, numbered candidate points (magenta) and
/// projected model points (blue crosses, with names).
cv::Mat drawSheet(const cv::Mat& frame, const std::vector<calib::TagDetection>& tags, const std::vector<bool>& known,
                  const std::vector<SheetPoint>& candidates, const std::vector<SheetPoint>& model_points);

/// Strong, well separated corners of a grey image (sub-pixel), at most `count`, none inside or
/// within a few pixels of a detected tag (tag corners are offered by the tags themselves).
std::vector<cv::Point2d> candidateCorners(const cv::Mat& gray, const std::vector<calib::TagDetection>& tags, int count);

}  // namespace kccd::cli
