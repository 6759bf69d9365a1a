// A calibration's pose refined to robot masks of its frames (calib::refineToMasks): the start
// chosen (the points' solve, else a rough pose from four or more points, else a given camera),
// the model's volumes placed at each frame's state, the result put into the solution with each
// labelled point's residual under the refined pose. The command line and Python build the inputs.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "kccd/calib/mask_refine.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"

namespace kccd::overlay {

/// What the refinement is given beside the gathered frames.
struct MaskInputs {
  std::vector<cv::Mat> masks;          ///< one per gathered frame (calib::readMask)
  std::vector<std::string> mask_names; ///< as messages name them
  std::vector<int> bodies;             ///< the model's bodies that are the robot (empty: all)
  std::optional<calib::Camera> rough;  ///< a start when the points do not give one
};

/// What the refinement did.
struct MaskRefinement {
  std::string start;       ///< "solve" (the points' solve), "points" (a rough pose from them), "camera" (the given one)
  std::string drawn;       ///< what was drawn: "collision volumes"
  calib::RefineResult result;
  /// Labelled points the refined pose puts farther from their click than 3 times the outline's
  /// robust rms, 3 times the other clicks' median residual and 4 px: the image disagrees with them.
  std::vector<std::string> disagreeing;
};

/// Refines `solution`'s pose to the masks. When the result improves the agreement, the solution
/// holds the refined camera (status solved, the covariance and sigmas of the refinement, the
/// residuals of every point under it, the truth error when `truth` is given); otherwise it is left
/// as it was. Throws CalibInputError when no start can be had, a frame has no state of the model's
/// size, or the masks do not match the frames.
MaskRefinement refineCalibrationToMasks(CalibSolution& solution, const Gathered& gathered, const calib::Camera& intrinsics,
                                        const Model& model, const MaskInputs& inputs, const calib::Camera* truth = nullptr);

/// The refinement's figures as lines the camera file ends with (keys OpenCV and the camera reader
/// skip): refinement, refinement_start, refinement_drawn, mask_iou_before, mask_iou_after.
std::string refinementText(const MaskRefinement& refinement);

/// The refinement as the JSON report gives it: improved, message, start, drawn, frames
/// (iou_before, iou_after, rms_px, outline_points), disagreeing.
nlohmann::json refinementJson(const MaskRefinement& refinement);

/// Draws onto a check image of the camera's frame the mask's outline (yellow) and the robot's
/// drawn outline at `camera` (magenta), so where they part shows.
void drawMaskAgreement(cv::Mat& bgr, const calib::Camera& camera, const cv::Mat& mask, std::span<const calib::PlacedVolume> volumes);

}  // namespace kccd::overlay
