#include "legend.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "kccd/render/composite.hpp"
#include "kccd/render/status_legend.hpp"
#include "kccd/render/text_metrics.hpp"

namespace kccd::render {

cv::Scalar statusColour(SafetyStatus status) {
  switch (status) {
    case SafetyStatus::Clear:
      return {60, 200, 40};
    case SafetyStatus::WithinMargin:
      return {0, 180, 255};
    case SafetyStatus::Colliding:
      return {40, 40, 230};
    case SafetyStatus::NoState:
      return {160, 160, 160};
  }
  return {255, 255, 255};
}

namespace detail {

Legend::Legend(const Projection& projection, double near)
    : projection_(projection), world_to_camera_(projection.camera().worldToCamera()), near_(near) {}

cv::Rect Legend::draw(cv::Mat& bgra, std::span<const Volume> volumes, const std::vector<Visibility>& visibility,
                      const Style& style) {
  const cv::Rect image(0, 0, bgra.cols, bgra.rows);
  cv::Rect touched;
  const TextMetrics m = textMetrics(bgra.rows);
  auto text = [&](const std::string& s, cv::Point at) {
    cv::putText(bgra, s, at, m.font, m.scale, cv::Scalar(0, 0, 0, 255), m.thickness + 2, cv::LINE_AA);
    cv::putText(bgra, s, at, m.font, m.scale, cv::Scalar(255, 255, 255, 255), m.thickness, cv::LINE_AA);
  };
  if (style.labels) {
    for (std::size_t i = 0; i < volumes.size(); ++i) {
      const Volume& v = volumes[i];
      if (visibility[i] != Visibility::Drawn || v.label.empty() || v.points.empty()) continue;
      Vec3 centre = Vec3::Zero();
      for (const Vec3& p : v.points) centre += p;
      centre = v.pose * (centre / static_cast<double>(v.points.size()));
      if ((world_to_camera_ * centre).z() <= near_) continue;
      const Eigen::Vector2d px = projection_.project(centre);
      // Centres far outside the image have no visible label (and would overflow int).
      if (!(px.x() > -bgra.cols && px.x() < 2.0 * bgra.cols && px.y() > -bgra.rows && px.y() < 2.0 * bgra.rows))
        continue;
      text(v.label,
           cv::Point(static_cast<int>(px.x()) - m.width(v.label) / 2, static_cast<int>(px.y()) + m.height / 2));
      touched = image;  // names are rare in overlays: not worth a tighter box
    }
  }
  if (style.legend) {
    const cv::Rect box = legendBox(bgra.size());
    if (!box.empty()) {  // an image a few pixels high shows none of it
      legend_(box - legend_box_.tl()).copyTo(bgra(box));
      touched |= box;
    }
  }
  return touched;
}

cv::Rect Legend::legendBox(cv::Size size) {
  // Drawn once per image height and copied afterwards; its box a margin from the top-left corner.
  if (legend_.empty() || legend_rows_ != size.height) {
    const TextMetrics m = textMetrics(size.height);
    legend_rows_ = size.height;
    legend_ = statusLegend(m);
    legend_box_ = cv::Rect(m.margin, m.margin, legend_.cols, legend_.rows);
  }
  return legend_box_ & cv::Rect(0, 0, size.width, size.height);
}

cv::Rect Legend::compositeLegend(cv::Mat& bgr) {
  const cv::Rect box = legendBox(bgr.size());
  if (box.empty()) return box;
  cv::Mat part = bgr(box);
  compositeOver(part, legend_(box - legend_box_.tl()));
  return box;
}

}  // namespace detail
}  // namespace kccd::render
