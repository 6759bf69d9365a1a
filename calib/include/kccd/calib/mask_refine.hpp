// The camera pose refined so that the robot's silhouette, drawn from the model at each frame's
// state (silhouette.hpp), matches robot masks of the frames (any segmentation tool's output:
// non-zero = robot), over all frames together. The intrinsics and lens stay as they are.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/input_error.hpp"

namespace kccd::calib {

/// A mask file that cannot be used: "path: mask: problem".
class MaskError : public InputError {
 public:
  using InputError::InputError;
};

/// A robot mask read from an image file (PNG, JPEG, ...): 255 where any channel is non-zero (for
/// a cut-out with transparency: its alpha), else 0. Throws MaskError for an unreadable file,
/// another size than width x height, and, when `robot_and_background`, a mask with no robot or
/// nothing but robot (a frame's mask in a recording may be either: the robot out of view).
cv::Mat readMask(const std::string& path, int width, int height, bool robot_and_background = true);

/// One frame to fit: its robot mask and the model placed at its state.
struct MaskFrame {
  cv::Mat mask;                       ///< CV_8UC1, the camera's size; non-zero = robot
  std::vector<PlacedVolume> volumes;  ///< world coordinates
  std::vector<PlacedMesh>
      meshes;  ///< what the robot looks like (visual meshes); drawn instead of the volumes when given
  /// CV_8UC1: non-zero where the mask says anything (empty: everywhere). Elsewhere (e.g. where a
  /// background estimate never saw the scene) outline points do not count and IoUs are not taken.
  cv::Mat known;
};

/// How the refinement runs.
struct RefineOptions {
  double spacing_px = 2.0;              ///< outline samples' spacing
  int max_iterations = 40;              ///< per stage of the robust scale
  double min_iou = 0.6;                 ///< a refined pose whose mean IoU stays below this is not a camera
  double max_rotation_sigma_deg = 3.0;  ///< nor one this uncertain (the points' solve has the same gate)
  double max_frame_drop = 0.02;         ///< nor one that lowers a frame's IoU by more than this
  /// The start's sigmas (when it has them) are a prior: a pose more than 3 sigma from it for a mean
  /// IoU gain below 0.02 keeps the start (the masks and the volumes differ, not the start).
  bool start_is_prior = false;
};

/// The agreement of one frame before and after (a refinement to masks fills the IoUs, one to
/// edges the matched fractions).
struct FrameAgreement {
  double iou_before = 0.0;      ///< mask IoU at the start pose
  double iou_after = 0.0;       ///< at the returned pose
  double matched_before = 0.0;  ///< share of the drawn outline on an image edge of its direction, at the start
  double matched_after = 0.0;   ///< at the returned pose
  double rms_px =
      0.0;  ///< outline points' distance to the mask's outline (or the edges) at the returned pose (robust rms)
  int outline_points = 0;  ///< points of the drawn outline inside the image at the returned pose
};

/// What a refinement was made to.
enum class RefineSource { Masks, Edges };

/// The result; `camera` is the refined pose only when `improved`, else the start.
struct RefineResult {
  RefineSource source = RefineSource::Masks;
  bool improved = false;
  std::string message;  ///< one line: what happened, and why the start was kept when it was
  Camera camera;        ///< with the refinement's pose sigmas when improved
  std::vector<FrameAgreement> frames;
  int iterations = 0;
  cv::Matx66d covariance = cv::Matx66d::zeros();  ///< of (rvec, tvec) when improved
};

/// Refines `start`'s pose (world -> camera) so that the drawn silhouettes match the masks: the
/// masks are cleaned first (specks away from the robot dropped, small holes filled), then each
/// drawn outline point is pulled onto the mask's outline (a signed distance field) by
/// Levenberg-Marquardt over (rvec, tvec), with a robust (Cauchy) loss whose scale shrinks from a
/// tenth of the image to a few pixels; outline points at the image border, and those whose
/// field points the other way (a hole's edge, another object's), count little. The result is
/// kept only if the mean IoU grows and no frame's falls by more than max_frame_drop (never a worse camera),
/// and if it is a camera at all: a mean IoU of at least min_iou, a rotation sigma within bounds.
/// Throws InputError for masks of another size than the camera's or no frame.
RefineResult refineToMasks(const Camera& start, std::span<const MaskFrame> frames, const RefineOptions& options = {});

}  // namespace kccd::calib
