// The report of a calibration as JSON, what `kccd calib --json` prints: the solve's status and
// message, every point's residual, what each frame gave and, when solved, the pose with its
// quality figures.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"

namespace kccd::overlay {

/// Where a calibration's outputs went.
struct CalibOutputs {
  std::string camera;    ///< the camera file written (when solved)
  std::string check;     ///< the (first) check image written; empty: none
  std::string renderer;  ///< the GL renderer that drew the check images' volumes; empty: none drawn
};

/// The report: status, message, points, inliers, rejected (names), unknown_tag_ids, residuals
/// (name, px or null, inlier), frames (image, tag_points, label_points, unknown_tag_ids); when
/// solved also output, reprojection_rms_px, rotation_sigma_deg, position_sigma_m, volume_sigma_px
/// (or null), rvec, tvec, camera_position, and check, renderer and truth_error when known.
nlohmann::json calibReport(const Gathered& gathered, const CalibSolution& solution, const CalibOutputs& outputs);

}  // namespace kccd::overlay
