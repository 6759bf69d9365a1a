// A camera pose solved from gathered correspondences, with the figures an operator judges it by:
// the pose's own quality, how far the model's volumes may be off in the image, and (for synthetic
// recordings) the error against the known camera.
#pragma once

#include <optional>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"

namespace kccd::overlay {

/// The outcome of solveCalibration.
struct CalibSolution {
  calib::PoseResult pose;                 ///< the solve (calib::solvePose), residuals in Gathered::points order
  std::optional<double> volume_sigma_px;  ///< solved, with a model and the first frame's state: the worst 1-sigma
                                          ///< reprojection of the model's core points (calib::projectedSigmaPx)
  std::optional<calib::PoseDifference> truth_error;  ///< solved, with a known camera: the solved pose against it
  /// True when the pose is solved (pose.camera holds it).
  bool solved() const { return pose.status == calib::PoseStatus::Solved; }
};

/// The pose of the camera with `intrinsics` from `gathered`'s points, then its figures: the model's
/// core points at the first frame's state (when it has one of the model's size) and the difference
/// to `truth` (either may be null).
CalibSolution solveCalibration(const calib::Camera& intrinsics, const Gathered& gathered,
                               const calib::PoseOptions& options, const Model* model = nullptr,
                               const calib::Camera* truth = nullptr);

}  // namespace kccd::overlay
