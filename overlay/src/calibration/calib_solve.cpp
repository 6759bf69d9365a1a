#include "kccd/overlay/calibration/calib_solve.hpp"

#include "kccd/overlay/calibration/model_points.hpp"

namespace kccd::overlay {

CalibSolution solveCalibration(const calib::Camera& intrinsics, const Gathered& gathered,
                               const calib::PoseOptions& options, const Model* model, const calib::Camera* truth) {
  CalibSolution s;
  s.pose = calib::solvePose(intrinsics, gathered.points, options);
  if (!s.solved()) return s;
  // The reprojection uncertainty of the model's volumes at the first frame's state.
  if (model && !gathered.frames.empty() && static_cast<int>(gathered.frames[0].state.size()) == model->stateSize())
    s.volume_sigma_px = calib::projectedSigmaPx(s.pose.camera, s.pose.covariance,
                                                worldPoints(modelPoints(*model, gathered.frames[0].state)));
  if (truth) s.truth_error = calib::poseDifference(s.pose.camera, *truth);
  return s;
}

}  // namespace kccd::overlay
