// The text on the colour layer (internal): body names at the projected volume centres and the
// colour legend of the statuses in the top-left corner.
#pragma once

#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/render/projection.hpp"
#include "kccd/render/render_types.hpp"

namespace kccd::render::detail {

/// Draws names and the legend on camera images of one projection (which must outlive it); the
/// legend is drawn once per image height and copied afterwards.
class Legend {
 public:
  /// For volumes seen through `projection`; names of centres nearer than `near` are not drawn.
  Legend(const Projection& projection, double near);
  /// Draws on `bgra` (the straight-alpha camera image) what `style` asks: the names of the drawn
  /// volumes (Style::labels) and the legend (Style::legend); returns the rectangle it drew in.
  cv::Rect draw(cv::Mat& bgra, std::span<const Volume> volumes, const std::vector<Visibility>& visibility,
                const Style& style);
  /// Where the legend goes on an image of `size` (empty when the image shows none of it).
  cv::Rect legendBox(cv::Size size);
  /// Composites the legend over `bgr` (CV_8UC3) as draw() and compositeOver() would; returns its box.
  cv::Rect compositeLegend(cv::Mat& bgr);

 private:
  const Projection& projection_;
  Pose world_to_camera_;
  double near_;
  cv::Mat legend_;
  cv::Rect legend_box_;
  int legend_rows_ = 0;
};

}  // namespace kccd::render::detail
