#include "calib_drawing.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "cli_args.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/model_view.hpp"

namespace kccd::cli {
namespace {

const cv::Scalar kInlier(60, 200, 60);     // BGR
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
  return {static_cast<int>(std::lround(std::clamp(p.x, -1e6, 1e6))), static_cast<int>(std::lround(std::clamp(p.y, -1e6, 1e6)))};
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

cv::Mat checkVolumes(const Model& model, const calib::Camera& camera, std::span<const double> state,
                     const std::string& camera_name, std::string& renderer_name) {
  try {
    render::ModelView view(model, camera);
    render::ModelViewRequest request;
    request.state = state;
    request.tight_volumes = false;
    request.mask = false;
    request.style.labels = model.bodies.size() <= 12;  // names of many bodies only cover each other
    renderer_name = view.renderer().rendererString();
    return view.draw(request).images.bgra;
  } catch (const calib::CameraError& e) {
    throw UsageError(camera_name + ": " + e.what());
  }
}

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
    if (!s.empty()) text(img, s, at(p.pixel + cv::Point2d(ink.radius + 2, -ink.radius - 2)), ink, p.inlier ? kInlier : kRejected);
  }
  // The headline band at the bottom (the volumes' legend is at the top left).
  const int line_h = static_cast<int>(std::lround(30 * ink.font)) + 4;
  const int band = line_h * static_cast<int>(headline.size()) + 8;
  if (band < img.rows) {
    cv::Mat strip = img.rowRange(img.rows - band, img.rows);
    strip.convertTo(strip, -1, 0.35, 0);
    for (std::size_t i = 0; i < headline.size(); ++i)
      text(img, headline[i], {8, img.rows - band + line_h * static_cast<int>(i + 1) - 2}, ink, cv::Scalar(255, 255, 255));
  }
  return img;
}

cv::Mat drawSheet(const cv::Mat& frame, const std::vector<calib::TagDetection>& tags, const std::vector<bool>& known,
                  const std::vector<SheetPoint>& candidates, const std::vector<SheetPoint>& model_points) {
  cv::Mat img = frame.clone();
  const Ink ink(img.size());
  for (std::size_t t = 0; t < tags.size(); ++t) {
    const calib::TagDetection& d = tags[t];
    const cv::Scalar colour = t < known.size() && known[t] ? kInlier : kUnknownTag;
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
  for (const SheetPoint& p : candidates) {
    cv::circle(img, at(p.pixel), ink.radius, kCandidate, ink.thick, cv::LINE_AA);
    text(img, p.name, at(p.pixel + cv::Point2d(ink.radius + 2, -ink.radius - 2)), ink, kCandidate);
  }
  for (const SheetPoint& p : model_points) {
    cross(img, p.pixel, ink.radius, kModel, ink.thick);
    text(img, p.name, at(p.pixel + cv::Point2d(ink.radius + 2, ink.radius * 3)), ink, kModel);
  }
  return img;
}

std::vector<cv::Point2d> candidateCorners(const cv::Mat& gray, const std::vector<calib::TagDetection>& tags, int count) {
  std::vector<cv::Point2f> found;
  const double spacing = std::max(12.0, gray.cols / 50.0);
  cv::goodFeaturesToTrack(gray, found, std::max(1, count * 3), 0.02, spacing);
  if (!found.empty())
    cv::cornerSubPix(gray, found, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
  std::vector<cv::Point2d> out;
  for (const cv::Point2f& f : found) {
    if (static_cast<int>(out.size()) >= count) break;
    bool near_tag = false;
    for (const calib::TagDetection& d : tags) {
      std::vector<cv::Point2f> quad;
      cv::Point2d c(0, 0);
      for (const cv::Point2d& p : d.corners) c += p * 0.25;
      // The quad grown by 15 % around its centre: tag corners and the code inside are left out.
      for (const cv::Point2d& p : d.corners) quad.emplace_back(c + 1.15 * (p - c));
      near_tag = near_tag || cv::pointPolygonTest(quad, f, false) >= 0;
    }
    // OpenCV's corner coordinates already use pixel centres at integers.
    if (!near_tag) out.emplace_back(f.x, f.y);
  }
  return out;
}

}  // namespace kccd::cli
