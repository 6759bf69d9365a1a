// The distortion warp (internal): the pinhole images GL draws carried into the camera image,
// the colour layer bilinearly (and made straight-alpha on the way), the labels at the nearest
// pinhole pixel (and counted on the way). The remap tables are made on first use.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/render/projection.hpp"

namespace kccd::render::detail {

/// The colour layer's way into the camera image through one projection (which must outlive it).
class ColourWarp {
 public:
  explicit ColourWarp(const Projection& projection) : projection_(projection) {}
  /// The camera image (CV_8UC4, straight alpha) of a premultiplied pinhole image; without a warp
  /// the pinhole image itself, straightened in place.
  cv::Mat apply(const cv::Mat& premultiplied);

 private:
  const Projection& projection_;
  cv::Mat map_a_, map_b_;                          // remap tables in fixed point
  std::vector<std::pair<int, int>> source_rows_;   // per output row, the pinhole rows its warp reads
};

/// The labels' way into the camera image through the mask pass's projection (which must outlive it).
class LabelWarp {
 public:
  explicit LabelWarp(const Projection& projection) : projection_(projection) {}
  /// The camera image's labels (CV_8UC1: each pixel the label of its nearest pinhole pixel, 0
  /// outside the pinhole image; without a warp the pinhole labels themselves), and in `counts`
  /// the pixels of each label.
  cv::Mat apply(const cv::Mat& pinhole_labels, std::array<int, 256>& counts);

 private:
  const Projection& projection_;
  cv::Mat map_;                                    // nearest pinhole pixel per output pixel, as integers
  std::vector<std::pair<int, int>> source_rows_;
};

}  // namespace kccd::render::detail
