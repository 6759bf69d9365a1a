// The check image of a solved calibration, one per frame: the frame, the model's volumes at the
// frame's state seen by the solved camera, every point where it was seen and where the pose
// projects it, and the figures of the solve.
#pragma once

#include <cstddef>
#include <string>

#include <opencv2/core.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"

namespace kccd::overlay {

/// How check images are drawn.
struct CheckImageOptions {
  double magnify = 20.0;                          ///< inliers' residual vectors are drawn this many times longer
  std::string camera_name;                        ///< names the camera in messages
  std::string pose_source = "the robot's masks";  ///< what gave the pose when no points did
};

/// A check image and what drew its volumes.
struct CheckImage {
  cv::Mat bgr;           ///< the camera's size, 8-bit BGR
  std::string renderer;  ///< the GL renderer of the volumes layer; empty when no volumes were drawn
};

/// The check image of frame `frame` of a solved calibration (drawCheck): its picture (a grey canvas
/// for labels only), the volumes of `model` (may be null) when the frame has a state of the model's
/// size, the frame's points with their residuals, and a headline with the inliers, RMS and sigmas.
/// Throws std::invalid_argument when `solution` is not solved or `frame` is out of range,
/// calib::CameraError naming the camera when the renderer cannot draw it, render::GlContextError.
CheckImage checkImage(const Gathered& gathered, const CalibSolution& solution, std::size_t frame, const Model* model,
                      const CheckImageOptions& options);

}  // namespace kccd::overlay
