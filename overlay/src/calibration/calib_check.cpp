#include "kccd/overlay/calibration/calib_check.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "kccd/checker.hpp"
#include "kccd/overlay/calibration/calib_drawing.hpp"
#include "kccd/render/model_view.hpp"

namespace kccd::overlay {
namespace {

// The volumes of the model at `state` as a BGRA layer seen by the solved camera.
cv::Mat volumesLayer(const Model& m, const calib::Camera& cam, std::span<const double> state,
                     const std::string& camera_name, std::string& renderer_name) {
  try {
    render::ModelView view(m, cam);
    render::ModelViewRequest request;
    request.state = state;
    request.tight_volumes = false;
    request.mask = false;
    request.style.labels = m.bodies.size() <= 12;  // names of many bodies only cover each other
    renderer_name = view.renderer().rendererString();
    return view.draw(request).images.bgra;
  } catch (const calib::CameraError& e) {
    throw calib::CameraError(camera_name + ": " + e.what());
  }
}

// The points of frame `frame` as the check image shows them.
std::vector<CheckPoint> checkPoints(const Gathered& g, const calib::PoseResult& r, std::size_t frame) {
  cv::Matx33d rot;
  cv::Rodrigues(r.camera.rvec, rot);
  std::vector<CheckPoint> pts;
  for (std::size_t i = 0; i < g.points.size(); ++i) {
    if (g.sources[i].frame != frame) continue;
    CheckPoint p;
    p.pixel = g.points[i].pixel;
    p.residual_px = r.residuals[i].px;
    p.inlier = r.residuals[i].inlier;
    p.label = g.sources[i].label;
    const cv::Point3d& w = g.points[i].world;
    const cv::Vec3d c = rot * cv::Vec3d(w.x, w.y, w.z) + r.camera.tvec;
    if (c[2] > 1e-9) {
      std::vector<cv::Point2d> proj;
      cv::projectPoints(std::vector<cv::Point3d>{w}, r.camera.rvec, r.camera.tvec, r.camera.camera_matrix,
                        r.camera.distortion, proj);
      p.projected = proj[0];
    } else {
      p.projected = cv::Point2d(std::nan(""), std::nan(""));
    }
    pts.push_back(p);
  }
  return pts;
}

}  // namespace

CheckImage checkImage(const Gathered& g, const CalibSolution& s, std::size_t frame, const Model* model,
                      const CheckImageOptions& options) {
  if (!s.solved()) throw std::invalid_argument("checkImage: the calibration is not solved");
  if (frame >= g.frames.size()) throw std::invalid_argument("checkImage: no frame " + std::to_string(frame));
  const calib::PoseResult& r = s.pose;
  CheckImage out;
  cv::Mat layer;
  if (model && static_cast<int>(g.frames[frame].state.size()) == model->stateSize())
    layer = volumesLayer(*model, r.camera, g.frames[frame].state, options.camera_name, out.renderer);
  const std::vector<std::string> head{
      (g.points.empty() || !r.camera.reprojection_rms_px
           ? "kccd calib: the pose of " + options.pose_source + ", no points"
           : "kccd calib: " + std::to_string(r.inliers) + " of " + std::to_string(g.points.size()) +
                 " points agree, RMS " + messageNumber(*r.camera.reprojection_rms_px, 3) + " px") +
          (g.frames.size() > 1 ? " (frame " + std::to_string(frame + 1) + " of " + std::to_string(g.frames.size()) + ")"
                               : ""),
      "1 sigma: rotation " + messageNumber(*r.camera.rotation_sigma_deg, 3) + " deg, position " +
          messageNumber(*r.camera.position_sigma_m * 1000, 3) + " mm" +
          (s.volume_sigma_px ? ", volumes " + messageNumber(*s.volume_sigma_px, 3) + " px" : std::string()),
      "o seen  + projected  residual x" + messageNumber(options.magnify, 3) +
          (r.rejected.empty() ? "" : "  red: rejected (to scale)")};
  out.bgr = drawCheck(g.frames[frame].bgr, {r.camera.width, r.camera.height}, layer, checkPoints(g, r, frame), head,
                      options.magnify);
  return out;
}

}  // namespace kccd::overlay
