// Comparing a rendered image with its golden so that no shift is forgiven: the exact pixels first,
// then tolerances in pixels and grey levels that let isolated single-pixel flips pass (an edge
// within rounding of a pixel centre, drawn by another rasteriser) and fail any move of an edge
// along a run of pixels, of a body's centroid or of its area.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace kccd::overlay {

/// Tolerances for label masks (pixels).
struct MaskTolerance {
  int max_cluster_px = 4;               ///< largest 8-connected cluster of changed pixels
  double max_centroid_shift_px = 0.25;  ///< per body, how far its pixels' centroid may move
  /// Per body, how much its area may change per pixel of its boundary (at least 1 px in all).
  double max_area_change_per_boundary_px = 0.25;
};

/// Tolerances for colour layers and overlay frames (grey levels and pixels).
struct ColourTolerance {
  int channel_threshold = 24;  ///< a pixel counts as changed when a channel differs by more than this
  int max_cluster_px = 4;      ///< largest 8-connected cluster of changed pixels
  int max_diff_px = 40;        ///< changed pixels in all
};

/// One body of a mask comparison.
struct BodyChange {
  std::string name;
  int expected_px = 0, actual_px = 0;  ///< the body's pixels in each
  int boundary_px = 0;                 ///< its boundary in the golden (pixels with a 4-neighbour of another label)
  double centroid_shift_px = 0;        ///< how far its centroid moved (0 when absent in either)
  double allowed_area_change_px = 0;   ///< max(1, tolerance × boundary)
};

/// How a comparison ended: passed or not, why (one line), and the measurements behind it.
struct Comparison {
  bool passed = false;
  bool identical = false;          ///< the same pixels (and for masks, the same bodies)
  std::string reason;              ///< empty when identical; what failed, or what was forgiven
  int changed_px = 0;              ///< pixels counted as changed
  int largest_cluster_px = 0;      ///< the largest 8-connected cluster of them
  cv::Rect largest_cluster;        ///< its bounding box (empty: none)
  std::vector<BodyChange> bodies;  ///< masks: per body of the golden
  double worst_centroid_shift_px = 0;
  double worst_area_change_ratio = 0;  ///< masks: the largest |area change| / allowed over the bodies
  cv::Mat changed;                     ///< CV_8UC1, 255 where a pixel counts as changed (empty: sizes differ)
};

/// Compares label masks (CV_8UC1; 0 background, k for body names[k - 1]) whose labels are matched
/// by body name, so the same picture with re-numbered labels is identical. Fails on another size,
/// another set of body names, or a change beyond `tolerance`.
Comparison compareMasks(const cv::Mat& expected, const std::vector<std::string>& expected_names, const cv::Mat& actual,
                        const std::vector<std::string>& actual_names, const MaskTolerance& tolerance = {});

/// Compares two colour images of the same type (8-bit, 1, 3 or 4 channels; alpha is a channel).
Comparison compareColour(const cv::Mat& expected, const cv::Mat& actual, const ColourTolerance& tolerance = {});

/// The evidence as one BGR picture: a grey copy of `expected` with the changed pixels in red
/// (sizes that differ: `actual` alone, converted). Masks are shown in false colour first.
cv::Mat diffPicture(const cv::Mat& expected, const cv::Mat& actual, const Comparison& comparison, bool masks);

/// A crop of `image` around `box` (at least 24 px on a side, within the image) magnified `scale`
/// times with nearest-neighbour pixels; empty when `box` is empty.
cv::Mat magnifiedCrop(const cv::Mat& image, const cv::Rect& box, int scale = 8);

/// A mask shown in false colour (BGR): each label its own colour, background black.
cv::Mat falseColour(const cv::Mat& mask);

/// An image as a person sees it, BGR: a mask (`mask`) in false colour, an image with alpha over a
/// checkerboard so that transparency shows, grey as grey.
cv::Mat picture(const cv::Mat& image, bool mask);

}  // namespace kccd::overlay
