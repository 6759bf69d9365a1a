#include "kccd/overlay/labelling/labelling_candidates.hpp"

#include <algorithm>
#include <initializer_list>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/model_points.hpp"

namespace kccd::overlay {

std::vector<cv::Point2d> strongCorners(const cv::Mat& gray, const std::vector<calib::TagDetection>& tags, int count) {
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

namespace {

// The model's core points at `state` that `cam` sees inside an image of `size`.
std::vector<ModelPointCandidate> projectedModelPoints(const Model& model, const std::vector<double>& state,
                                                      const calib::Camera& cam, cv::Size size) {
  std::vector<ModelPointCandidate> out;
  cv::Matx33d rot;
  cv::Rodrigues(cam.rvec, rot);
  for (const ModelPoint& p : modelPoints(model, state)) {
    const cv::Vec3d c = rot * cv::Vec3d(p.world.x, p.world.y, p.world.z) + cam.tvec;
    if (!(c[2] > 1e-6)) continue;
    std::vector<cv::Point2d> proj;
    cv::projectPoints(std::vector<cv::Point3d>{p.world}, cam.rvec, cam.tvec, cam.camera_matrix, cam.distortion, proj);
    if (!(proj[0].x >= -0.5 && proj[0].y >= -0.5 && proj[0].x < size.width - 0.5 && proj[0].y < size.height - 0.5))
      continue;
    const Body& b = model.bodies[static_cast<std::size_t>(p.body)];
    out.push_back(
        {p.name, b.name, p.point, b.points[static_cast<std::size_t>(p.point)], b.frame == kWorld, p.world, proj[0]});
  }
  return out;
}

}  // namespace

LabellingCandidates labellingCandidates(const cv::Mat& bgr, const CandidateInputs& in) {
  if (in.model && !in.camera)
    throw CalibInputError(in.image + ": the model's points need a camera with a pose to be projected");
  if (in.model && static_cast<int>(in.state.size()) != in.model->stateSize())
    throw CalibInputError(in.image + ": the state has " + std::to_string(in.state.size()) + " values but model '" +
                          in.model->name + "' has " + std::to_string(in.model->stateSize()));
  if (in.camera) checkPicture(bgr, *in.camera, in.image, in.camera_name);
  if (bgr.type() != CV_8UC3) throw CalibInputError(in.image + ": the image is not 8-bit colour (BGR)");
  LabellingCandidates out;
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  const std::vector<calib::TagDetection> tags = calib::detectTags(gray);
  if (in.tags) calib::tagCorrespondences(tags, *in.tags, in.image);  // a tag seen twice is an error here too
  out.layout = in.tags.has_value();
  for (const calib::TagDetection& t : tags)
    out.tags.push_back({t.id, t.corners, in.tags && in.tags->find(t.id) != nullptr});
  int n = 0;
  for (const cv::Point2d& p : strongCorners(gray, tags, in.corners))
    out.corners.push_back({std::string("p").append(std::to_string(++n)), p});
  if (in.model) {
    out.state = in.state;
    out.model_points = projectedModelPoints(*in.model, in.state, *in.camera, bgr.size());
  }
  return out;
}

namespace {

// A YAML flow list of numbers (appended piece by piece: GCC 12 warns about "[" + std::string,
// GCC bug 105329).
std::string yamlList(std::initializer_list<double> values, int digits) {
  std::string out = "[";
  for (double v : values) {
    if (out.size() > 1) out += ", ";
    out += messageNumber(v, digits);
  }
  return out + "]";
}

std::string yamlPixel(const cv::Point2d& p) { return yamlList({p.x, p.y}, 7); }

std::string yamlPoint(const Vec3& v) { return yamlList({v.x(), v.y(), v.z()}, 10); }

}  // namespace

std::string labelsTemplate(const LabellingCandidates& c, const std::string& image, const std::string& sheet) {
  std::string t = "# Labels for " + image + " (made by kccd calib sheet; see the sheet image " + sheet +
                  ").\n"
                  "# Uncomment the points you can identify, give each its world point (metres) or its body and\n"
                  "# point in the body frame, delete the rest, and pass the file to kccd calib --labels.\n"
                  "labels:\n";
  for (const CornerCandidate& p : c.corners)
    t += "#  - {name: " + p.name + ", pixel: " + yamlPixel(p.pixel) + ", world: [X, Y, Z]}\n";
  for (const TagCandidate& tag : c.tags) {
    if (tag.placed) continue;  // the layout places these itself
    for (std::size_t k = 0; k < 4; ++k)
      t += "#  - {name: tag" + std::to_string(tag.id) + ".c" + std::to_string(k) +
           ", pixel: " + yamlPixel(tag.corners[k]) + ", world: [X, Y, Z]}\n";
  }
  std::string state;
  for (double v : c.state) state += (state.empty() ? "" : ", ") + messageNumber(v, 10);
  for (const ModelPointCandidate& p : c.model_points)
    // Points of world-fixed bodies are world points; the others are placed by the state.
    t += "#  - {name: " + p.name + ", pixel: " + yamlPixel(p.pixel) +
         (p.world_fixed ? ", world: " + yamlPoint(p.body_point)
                        : ", body: " + p.body + ", point: " + yamlPoint(p.body_point) +
                              (c.state.empty() ? "" : ", state: [" + state + "]")) +
         "}  # projected: click the real point\n";
  return t;
}

}  // namespace kccd::overlay
