#include "legend.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "kccd/render/composite.hpp"

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
namespace {

// The legend image at a text scale: a swatch and a name per status on a dark translucent box.
cv::Mat drawLegend(double scale, int thick) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  auto text = [&](cv::Mat& img, const std::string& s, cv::Point at) {
    cv::putText(img, s, at, font, scale, cv::Scalar(0, 0, 0, 255), thick + 2, cv::LINE_AA);
    cv::putText(img, s, at, font, scale, cv::Scalar(255, 255, 255, 255), thick, cv::LINE_AA);
  };
  cv::Mat bgra;
  {
    const SafetyStatus all[] = {SafetyStatus::Clear, SafetyStatus::WithinMargin, SafetyStatus::Colliding,
                                SafetyStatus::NoState};
    const char* names[] = {"clear", "within margin", "colliding", "no state"};
    int baseline = 0;
    const cv::Size line = cv::getTextSize("within margin", font, scale, thick, &baseline);
    const int pad = std::max(3, line.height / 2), row = line.height + 2 * pad;
    const cv::Rect box(pad, pad, line.width + row + 3 * pad, 4 * row + pad);
    bgra = cv::Mat::zeros(box.br().y, box.br().x, CV_8UC4);
    bgra(box).setTo(cv::Scalar(30, 30, 30, 170));
    for (int i = 0; i < 4; ++i) {
      const int y = box.y + pad + i * row;
      const cv::Scalar c = statusColour(all[i]);
      cv::rectangle(bgra, cv::Rect(box.x + pad, y + pad / 2, row - pad, row - pad), cv::Scalar(c[0], c[1], c[2], 255),
                    cv::FILLED);
      text(bgra, names[i], cv::Point(box.x + row + pad, y + line.height + pad / 2));
    }
  }
  return bgra;
}

}  // namespace

Legend::Legend(const Projection& projection, double near)
    : projection_(projection), world_to_camera_(projection.camera().worldToCamera()), near_(near) {}

cv::Rect Legend::draw(cv::Mat& bgra, std::span<const Volume> volumes, const std::vector<Visibility>& visibility,
                      const Style& style) {
  const cv::Rect image(0, 0, bgra.cols, bgra.rows);
  cv::Rect touched;
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = std::clamp(bgra.rows / 900.0, 0.35, 1.0);
  const int thick = std::max(1, static_cast<int>(std::lround(scale * 2)));
  auto text = [&](const std::string& s, cv::Point at) {
    cv::putText(bgra, s, at, font, scale, cv::Scalar(0, 0, 0, 255), thick + 2, cv::LINE_AA);
    cv::putText(bgra, s, at, font, scale, cv::Scalar(255, 255, 255, 255), thick, cv::LINE_AA);
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
      int baseline = 0;
      const cv::Size size = cv::getTextSize(v.label, font, scale, thick, &baseline);
      text(v.label, cv::Point(static_cast<int>(px.x()) - size.width / 2, static_cast<int>(px.y()) + size.height / 2));
      touched = image;  // names are rare in overlays: not worth a tighter box
    }
  }
  if (style.legend) {
    const cv::Rect box = legendBox(bgra.size());
    if (!box.empty()) {  // an image a few pixels high shows none of it
      legend_(box).copyTo(bgra(box));
      touched |= box;
    }
  }
  return touched;
}

cv::Rect Legend::legendBox(cv::Size size) {
  // Drawn once per image height and copied afterwards.
  if (legend_.empty() || legend_rows_ != size.height) {
    const double scale = std::clamp(size.height / 900.0, 0.35, 1.0);
    const int thick = std::max(1, static_cast<int>(std::lround(scale * 2)));
    legend_rows_ = size.height;
    legend_ = drawLegend(scale, thick);
    cv::Mat alpha;
    cv::extractChannel(legend_, alpha, 3);
    legend_box_ = cv::boundingRect(alpha);
  }
  return legend_box_ & cv::Rect(0, 0, size.width, size.height);
}

cv::Rect Legend::compositeLegend(cv::Mat& bgr) {
  const cv::Rect box = legendBox(bgr.size());
  if (box.empty()) return box;
  cv::Mat part = bgr(box);
  compositeOver(part, legend_(box));
  return box;
}

}  // namespace detail
}  // namespace kccd::render
