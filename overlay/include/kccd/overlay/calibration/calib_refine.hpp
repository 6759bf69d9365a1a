// A calibration's pose refined to robot masks of its frames (calib::refineToMasks) or to its
// pictures' edges (calib::refineToEdges): the start chosen (the points' solve, else a rough pose
// from four or more points, else a given camera), the model's volumes placed at each frame's
// state, the result put into the solution with each labelled point's residual under the refined
// pose. The command line, the labelling page and Python build the inputs.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "kccd/calib/edge_refine.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/input_error.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"
#include "kccd/render/visuals.hpp"

namespace kccd::overlay {

/// What a refinement draws of the robot at a state: the model's visuals (what it looks like,
/// loaded once) when `draw` is "auto" and the model has visuals that can be read, or "visuals";
/// else (or "volumes") the collision volumes. `bodies`: those the pictures show (empty: all).
class RobotDrawing {
 public:
  /// Throws CalibInputError for another `draw` or "visuals" without visuals, render::VisualError
  /// for "visuals" that cannot be read.
  RobotDrawing(const Model& model, std::vector<int> bodies, const std::string& draw = "auto");
  /// The volumes at `state`: with visuals, those of the bodies in frames that carry one (they
  /// stand for the visuals where a fit draws volumes first).
  std::vector<calib::PlacedVolume> volumes(std::span<const double> state) const;
  /// The visuals at `state` as meshes (none without visuals or for an invalid state).
  std::vector<calib::PlacedMesh> meshes(std::span<const double> state) const;
  /// "visual meshes", or "collision volumes" with the reason in brackets when the model has visuals.
  const std::string& drawn() const { return drawn_; }
  const Model& model() const { return model_; }
  const std::vector<int>& bodies() const { return bodies_; }  ///< as given (empty: all)

 private:
  const Model& model_;
  std::vector<int> bodies_, volume_bodies_;
  std::vector<render::LoadedVisual> visuals_;
  std::string drawn_;
};

/// The bodies of `bodies` (empty: all of the model's) that move with a joint: what differs from a
/// fixed camera's background.
std::vector<int> movingBodies(const Model& model, std::span<const int> bodies);

/// A frame of a fixed camera's recording and the robot's state in it.
struct RecordingSample {
  cv::Mat bgr;                ///< 8-bit BGR, the camera's size
  std::vector<double> state;  ///< the model's state size
};

/// What the refinement is given beside the gathered frames.
struct RefineInputs {
  calib::RefineSource source = calib::RefineSource::Masks;  ///< Edges: the gathered frames' pictures
  std::vector<cv::Mat> masks;  ///< with Masks: one per gathered frame (calib::readMask), or none with `recording`
  /// With Masks and no masks: frames of the recording the gathered frames are from (a fixed
  /// camera), spread over it; the masks are the gathered frames' pictures against the background
  /// estimated from these away from the drawn robot (calib/background.hpp), remade as the pose is
  /// refined.
  std::vector<RecordingSample> recording;
  std::vector<std::string> mask_names;  ///< as messages name them
  std::vector<int> bodies;              ///< the model's bodies that are the robot (empty: all)
  /// What is drawn: the model's visuals (what the robot looks like) when it has them and they can
  /// be read ("auto"), only the collision volumes ("volumes"), or the visuals or an error ("visuals").
  std::string draw = "auto";
  std::optional<calib::Camera> rough;  ///< a start when the points do not give one
  FieldSpelling spell;                 ///< how messages name the inputs ("masks" -> "--masks"; default: as they are)
};

/// What the refinement did.
struct Refinement {
  std::string start;  ///< "solve" (the points' solve), "points" (a rough pose from them), "camera" (the given one)
  std::vector<int> bodies;  ///< the bodies drawn (with masks from a recording: those that move)
  std::string drawn;  ///< what was drawn: "visual meshes", or "collision volumes" (and why, when the model has visuals)
  calib::RefineResult result;
  std::vector<std::vector<calib::PlacedMesh>> meshes;  ///< per frame, the visuals drawn (empty: the volumes were)
  std::vector<cv::Mat>
      masks;               ///< masks made from the recording: per frame, as last used (none with given masks or edges)
  std::string masks_from;  ///< how they were made, one line (empty with given masks or edges)
  /// Labelled points the refined pose puts farther from their click than 3 times the outline's
  /// robust rms, 3 times the other clicks' median residual and 4 px: the image disagrees with them.
  std::vector<std::string> disagreeing;
};

/// Refines `solution`'s pose to the masks or the edges. When the result improves the agreement, the solution
/// holds the refined camera (status solved, the covariance and sigmas of the refinement, the
/// residuals of every point under it, the truth error when `truth` is given); otherwise it is left
/// as it was. Throws CalibInputError when no start can be had, a frame has no state of the model's
/// size, the masks do not match the frames, (edges, masks from the recording) a frame has no
/// picture, a recording's sample is not of the camera's size or state, or (draw "visuals") the
/// model has no visuals or they cannot be read.
Refinement refineCalibration(CalibSolution& solution, const Gathered& gathered, const calib::Camera& intrinsics,
                             const Model& model, const RefineInputs& inputs, const calib::Camera* truth = nullptr);

/// The refinement's figures as lines the camera file ends with (keys OpenCV and the camera reader
/// skip): refinement (masks, edges or none), refinement_start, refinement_drawn, refinement_masks
/// (with masks from the recording), then
/// mask_iou_before and mask_iou_after, or edge_share_before and edge_share_after.
std::string refinementText(const Refinement& refinement);

/// The refinement as the JSON report gives it: source, improved, message, start, drawn, masks_from
/// (with masks from the recording), frames
/// (iou_before and iou_after, or edge_share_before and edge_share_after; rms_px,
/// outline_points), disagreeing.
nlohmann::json refinementJson(const Refinement& refinement);

/// Draws onto a check image of the camera's frame the mask's outline (yellow; none for an empty
/// mask) and the robot's drawn outline at `camera` (magenta: the meshes when given, else the
/// volumes), so where they part shows.
void drawMaskAgreement(cv::Mat& bgr, const calib::Camera& camera, const cv::Mat& mask,
                       std::span<const calib::PlacedVolume> volumes, std::span<const calib::PlacedMesh> meshes = {});

}  // namespace kccd::overlay
