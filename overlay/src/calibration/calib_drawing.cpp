#include "kccd/overlay/calibration/calib_drawing.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "kccd/render/composite.hpp"

namespace kccd::overlay {
namespace {

const cv::Scalar kInlier(60, 200, 60);  // BGR
const cv::Scalar kRejected(40, 40, 230);
const cv::Scalar kProjected(230, 200, 40);
const cv::Scalar kVector(0, 220, 255);
const cv::Scalar kCandidate(220, 60, 220);
const cv::Scalar kModel(230, 120, 30);
const cv::Scalar kUnknownTag(0, 150, 255);

// Text and line sizes that read at any image size (tuned for 1280 x 720).
struct Ink {
  double font;
  int thick;
  int radius;
  explicit Ink(cv::Size size)
      : font(std::clamp(size.width / 1600.0, 0.35, 2.0)),
        thick(std::max(1, static_cast<int>(std::lround(size.width / 900.0)))),
        radius(std::max(3, static_cast<int>(std::lround(size.width / 250.0)))) {}
};

cv::Point at(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(std::clamp(p.x, -1e6, 1e6))),
          static_cast<int>(std::lround(std::clamp(p.y, -1e6, 1e6)))};
}

bool finite(const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// Text with a dark outline, readable on any background.
void text(cv::Mat& img, const std::string& s, cv::Point org, const Ink& ink, const cv::Scalar& colour) {
  cv::putText(img, s, org, cv::FONT_HERSHEY_SIMPLEX, ink.font, cv::Scalar(0, 0, 0), ink.thick + 2, cv::LINE_AA);
  cv::putText(img, s, org, cv::FONT_HERSHEY_SIMPLEX, ink.font, colour, ink.thick, cv::LINE_AA);
}

void cross(cv::Mat& img, const cv::Point2d& p, int r, const cv::Scalar& colour, int thick) {
  cv::line(img, at(p + cv::Point2d(-r, 0)), at(p + cv::Point2d(r, 0)), colour, thick, cv::LINE_AA);
  cv::line(img, at(p + cv::Point2d(0, -r)), at(p + cv::Point2d(0, r)), colour, thick, cv::LINE_AA);
}

cv::Mat canvas(const cv::Mat& frame, cv::Size size) {
  if (frame.empty()) return cv::Mat(size, CV_8UC3, cv::Scalar(96, 96, 96));
  return frame.clone();
}

}  // namespace

cv::Mat drawCheck(const cv::Mat& frame, cv::Size size, const cv::Mat& volumes, const std::vector<CheckPoint>& points,
                  const std::vector<std::string>& headline, double magnify) {
  cv::Mat img = canvas(frame, size);
  if (!volumes.empty()) render::compositeOver(img, volumes);
  const Ink ink(img.size());
  // Vectors first, markers on top, names last.
  for (const CheckPoint& p : points) {
    if (!finite(p.projected)) continue;
    // Rejected points are far off already: their vector is drawn to scale.
    const cv::Point2d tip = p.projected + (p.inlier ? magnify : 1.0) * (p.pixel - p.projected);
    cv::line(img, at(p.projected), at(tip), p.inlier ? kVector : kRejected, ink.thick, cv::LINE_AA);
  }
  for (const CheckPoint& p : points) {
    cv::circle(img, at(p.pixel), ink.radius, p.inlier ? kInlier : kRejected, ink.thick, cv::LINE_AA);
    if (finite(p.projected)) cross(img, p.projected, ink.radius, kProjected, ink.thick);
  }
  for (const CheckPoint& p : points) {
    std::string s = p.label;
    if (!p.inlier) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f px", p.residual_px);
      s += (s.empty() ? "" : ": ") + std::string(std::isfinite(p.residual_px) ? buf : "behind camera");
    }
    if (!s.empty())
      text(img, s, at(p.pixel + cv::Point2d(ink.radius + 2, -ink.radius - 2)), ink, p.inlier ? kInlier : kRejected);
  }
  // The headline band at the bottom (the volumes' legend is at the top left).
  const int line_h = static_cast<int>(std::lround(30 * ink.font)) + 4;
  const int band = line_h * static_cast<int>(headline.size()) + 8;
  if (band < img.rows) {
    cv::Mat strip = img.rowRange(img.rows - band, img.rows);
    strip.convertTo(strip, -1, 0.35, 0);
    for (std::size_t i = 0; i < headline.size(); ++i)
      text(img, headline[i], {8, img.rows - band + line_h * static_cast<int>(i + 1) - 2}, ink,
           cv::Scalar(255, 255, 255));
  }
  return img;
}

cv::Mat drawSheet(const cv::Mat& frame, const LabellingCandidates& candidates) {
  cv::Mat img = frame.clone();
  const Ink ink(img.size());
  for (const TagCandidate& d : candidates.tags) {
    const cv::Scalar colour = d.placed ? kInlier : kUnknownTag;
    cv::Point2d centre(0, 0);
    for (std::size_t k = 0; k < 4; ++k) {
      cv::line(img, at(d.corners[k]), at(d.corners[(k + 1) % 4]), colour, ink.thick, cv::LINE_AA);
      centre += d.corners[k] * 0.25;
    }
    for (std::size_t k = 0; k < 4; ++k) {
      // Corner numbers just outside the tag, along the diagonal.
      const cv::Point2d out = d.corners[k] + 0.25 * (d.corners[k] - centre);
      cv::circle(img, at(d.corners[k]), std::max(2, ink.radius / 2), colour, cv::FILLED, cv::LINE_AA);
      text(img, std::to_string(k), at(out), ink, colour);
    }
    text(img, "id " + std::to_string(d.id), at(centre + cv::Point2d(-ink.radius * 3, ink.radius)), ink, colour);
  }
  for (const CornerCandidate& p : candidates.corners) {
    cv::circle(img, at(p.pixel), ink.radius, kCandidate, ink.thick, cv::LINE_AA);
    text(img, p.name, at(p.pixel + cv::Point2d(ink.radius + 2, -ink.radius - 2)), ink, kCandidate);
  }
  for (const ModelPointCandidate& p : candidates.model_points) {
    cross(img, p.pixel, ink.radius, kModel, ink.thick);
    text(img, p.name, at(p.pixel + cv::Point2d(ink.radius + 2, ink.radius * 3)), ink, kModel);
  }
  return img;
}

}  // namespace kccd::overlay
