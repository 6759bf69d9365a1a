#include "kccd/overlay/calibration/calib_report.hpp"

#include <cmath>

namespace kccd::overlay {

nlohmann::json calibReport(const Gathered& g, const CalibSolution& s, const CalibOutputs& outputs) {
  const calib::PoseResult& r = s.pose;
  nlohmann::json j;
  j["status"] = calib::toString(r.status);
  j["message"] = r.message;
  j["points"] = g.points.size();
  j["inliers"] = r.inliers;
  j["rejected"] = r.rejected;
  j["unknown_tag_ids"] = g.unknown_tag_ids;
  j["residuals"] = nlohmann::json::array();
  for (const calib::Residual& res : r.residuals)
    j["residuals"].push_back({{"name", res.name},
                              {"px", std::isfinite(res.px) ? nlohmann::json(res.px) : nlohmann::json(nullptr)},
                              {"inlier", res.inlier}});
  j["frames"] = nlohmann::json::array();
  for (const GatheredFrame& f : g.frames)
    j["frames"].push_back({{"image", f.image},
                           {"tag_points", f.tag_points},
                           {"label_points", f.label_points},
                           {"unknown_tag_ids", f.unknown_ids}});
  if (!s.solved()) return j;
  j["output"] = outputs.camera;
  j["reprojection_rms_px"] =
      r.camera.reprojection_rms_px ? nlohmann::json(*r.camera.reprojection_rms_px) : nlohmann::json(nullptr);
  j["rotation_sigma_deg"] = *r.camera.rotation_sigma_deg;
  j["position_sigma_m"] = *r.camera.position_sigma_m;
  j["volume_sigma_px"] = s.volume_sigma_px ? nlohmann::json(*s.volume_sigma_px) : nlohmann::json(nullptr);
  j["rvec"] = {r.camera.rvec[0], r.camera.rvec[1], r.camera.rvec[2]};
  j["tvec"] = {r.camera.tvec[0], r.camera.tvec[1], r.camera.tvec[2]};
  const cv::Vec3d centre = calib::cameraCentre(r.camera);
  j["camera_position"] = {centre[0], centre[1], centre[2]};
  if (!outputs.check.empty()) j["check"] = outputs.check;
  if (!outputs.renderer.empty()) j["renderer"] = outputs.renderer;
  if (s.truth_error)
    j["truth_error"] = {{"rotation_deg", s.truth_error->rotation_deg}, {"position_m", s.truth_error->position_m}};
  return j;
}

}  // namespace kccd::overlay
