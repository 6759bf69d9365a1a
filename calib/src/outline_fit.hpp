// Internal: a camera pose fitted so the robot's drawn outline (silhouette.hpp) lands where an image
// field says it should, over several frames at once; the field is the caller's (a mask's signed
// distance for mask_refine, an oriented edge distance for edge_refine). Robust Levenberg-Marquardt
// over (rvec, tvec) with a Cauchy loss whose scale shrinks stage by stage.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/calib/silhouette.hpp"

namespace kccd::calib::detail {

/// One drawn outline point of one frame: where on the robot it is and its outward normal.
struct OutlineSample {
  std::size_t frame = 0;
  cv::Point3d world;
  cv::Point2d normal;
};

/// What is drawn of one frame: its meshes when it has them, else its volumes.
struct FrameShape {
  std::span<const PlacedVolume> volumes;
  std::span<const PlacedMesh> meshes;
};

/// The outline points of every frame's shape at `camera` that lie inside the image (2 px from its
/// border); the frames' filled silhouettes into `drawn` when given.
std::vector<OutlineSample> outlineSamples(const Camera& camera, std::span<const FrameShape> frames, double spacing,
                                          std::vector<cv::Mat>* drawn = nullptr);

/// `cam` turned so its image moves by (du, dv) px (about its own x and y axes), then moved along
/// its axis so the image of things at `depth` grows by `growth` (> 0).
Camera turnedAndMoved(const Camera& cam, double du, double dv, double growth, double depth);

/// The mean depth in front of `cam` of the frames' volumes' core points (0 when none is in front).
double meanDepth(const Camera& cam, std::span<const FrameShape> frames);

/// Bilinear sample of a CV_32F field at (x, y), clamped to the field.
double sampleField(const cv::Mat& field, double x, double y);

/// What the field says of one sample at `pixel`: its residual (px), the residual's gradient in the
/// image, and a factor on its robust weight (1: trusted).
struct FieldValue {
  double r = 0.0, gx = 0.0, gy = 0.0, trust = 1.0;
};
using Field = std::function<FieldValue(const OutlineSample&, const cv::Point2d& pixel)>;

/// Points seen in the image (clicks, tag corners) that hold the fit near them: each a robust 2-D
/// residual with its own Cauchy scale.
struct Anchors {
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> pixel;
  double scale_px = 8.0;
};

/// The robust cost of `samples` (and `anchors`, when given) at (rvec, tvec) with Cauchy scale `c`,
/// and its normal equations.
struct Evaluation {
  double cost = 0.0;
  cv::Matx66d jtj = cv::Matx66d::zeros();
  cv::Vec6d jtr = cv::Vec6d::all(0);
  double weight_sum = 0.0, weighted_sq = 0.0;  ///< sum of w, sum of w r^2 (a robust rms)
};
Evaluation evaluate(const Camera& cam, const cv::Vec3d& rvec, const cv::Vec3d& tvec,
                    std::span<const OutlineSample> samples, const Field& field, double c, bool normal_equations,
                    const Anchors* anchors = nullptr);

/// Levenberg-Marquardt from `cam` for each Cauchy scale in turn (px), outline samples redrawn
/// every iteration; `samples_at` gives them at a pose. A stage ends when a step changes (rvec,
/// tvec) by less than `tiny` (norm) or lowers the cost by less than `min_gain` of it (a drawing
/// quantised to pixels never settles to `tiny`). Returns the pose, counts iterations.
Camera fitPose(Camera cam, const std::function<std::vector<OutlineSample>(const Camera&)>& samples_at,
               const Field& field, std::span<const double> scales_px, int max_iterations, int& iterations,
               const Anchors* anchors = nullptr, double tiny = 1e-7, double min_gain = 0.0);

/// How far `cam` lies from `start` in the start's own sigmas (the larger of rotation and position),
/// and the difference; none when the start has no sigmas.
struct FromStart {
  PoseDifference difference;
  double sigmas = 0.0;
};
std::optional<FromStart> fromStart(const Camera& cam, const Camera& start);

/// The pose's covariance from the normal equations at the optimum: sigma^2 (J^T W J)^-1, with the
/// outline samples' correlation (neighbours a spacing apart see the same edge) counted by a factor
/// of 5 on the variance.
cv::Matx66d poseCovariance(const Evaluation& e);

}  // namespace kccd::calib::detail
