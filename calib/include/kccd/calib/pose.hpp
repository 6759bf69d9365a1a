// Camera pose from 2-D <-> 3-D correspondences (labelled points, tag corners): a robust solve with
// an honest quality report, or a status saying why no pose can be trusted and what to add.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/correspondence.hpp"

namespace kccd::calib {

/// Tuning of solvePose. The defaults suit hand-labelled points with a few pixels of error.
struct PoseOptions {
  double ransac_threshold_px = 8.0;  ///< a point farther than this from its projection is rejected
  int min_inliers = 6;               ///< fewer points (given, or agreeing) -> no pose; at least 4
  /// Spread test: the second singular value of the centred points (world, and image after
  /// undistortion) must be at least this fraction of the first, else the points are on a line.
  double min_spread_ratio = 0.02;
  /// The conditioning tests below use max(measured noise, noise_floor_px) as the pixel noise,
  /// so exact (noise-free) data on a bad geometry is still refused.
  double noise_floor_px = 0.5;
  double max_rotation_sigma_deg = 3.0;     ///< larger -> PoorGeometry
  double max_position_sigma_ratio = 0.05;  ///< position sigma / distance to the points; larger -> PoorGeometry
  /// A (nearly) planar set is refused when its mirrored (Necker) pose fits almost as well:
  /// (SSE_mirror - SSE_best) / noise^2 below this.
  double min_mirror_separation = 16.0;
};

/// How a pose solve ended. Only Solved comes with a pose.
enum class PoseStatus : std::uint8_t {
  Solved,         ///< camera holds the pose and its quality figures
  TooFewPoints,   ///< fewer than max(4, min_inliers) correspondences
  Collinear,      ///< the world points (or the agreeing ones) lie nearly on one line
  PoorGeometry,   ///< a pose fits but is ill-determined (small view extent, mirror ambiguity, edge-on)
  TooFewInliers,  ///< fewer than min_inliers points agree on one pose within the threshold
};

/// Reprojection residual of one correspondence under the returned pose (or the best pose found).
struct Residual {
  std::string name;
  double px = 0.0;      ///< distance between the pixel and the projected world point; inf behind the camera
  bool inlier = false;  ///< used in the final fit
};

/// The outcome of solvePose.
struct PoseResult {
  PoseStatus status = PoseStatus::TooFewPoints;
  std::string message;                ///< one line: what was found, and for a failure what to add
  Camera camera;                      ///< the intrinsics with rvec/tvec and the quality figures (Solved only)
  std::vector<Residual> residuals;    ///< per correspondence, in input order, under the best pose found (empty if none)
  std::vector<std::string> rejected;  ///< names of the correspondences left out of the fit
  cv::Matx66d covariance = cv::Matx66d::zeros();  ///< of (rvec, tvec), Solved only
  int inliers = 0;
};

/// Camera pose (world -> camera) from correspondences, using the intrinsics and lens distortion of
/// `intrinsics` (its rvec/tvec and quality fields are ignored). Exhaustive or sampled P3P RANSAC on
/// undistorted points, SQPnP and Levenberg-Marquardt on the inliers, then the covariance
/// sigma^2 (J^T J)^-1 with sigma^2 = SSE / (2N - 6). Never returns Solved for a degenerate or
/// ill-conditioned set. Throws InputError for unusable input: a non-finite coordinate, an empty
/// or repeated name (the message names it), bad options, or invalid intrinsics (CameraError).
PoseResult solvePose(const Camera& intrinsics, const std::vector<Correspondence>& points,
                     const PoseOptions& options = {});

/// The reprojection uncertainty of world points under a solved pose: for each point, the square
/// root of the largest eigenvalue of J C J^T (J: the 2x6 derivative of its projection with respect
/// to rvec, tvec; C: the pose covariance), in pixels; the largest over the points (points behind
/// the camera are skipped; 0 when none is in front).
double projectedSigmaPx(const Camera& camera, const cv::Matx66d& covariance, const std::vector<cv::Point3d>& world);

/// The 1-sigma rotation (degrees, largest over axes) and camera-centre position (metres, largest
/// over directions) of a pose (rvec, tvec) whose covariance is `covariance`.
std::pair<double, double> poseSigmas(const cv::Vec3d& rvec, const cv::Vec3d& tvec, const cv::Matx66d& covariance);

/// Name of a status ("solved", "too few points", ...).
const char* toString(PoseStatus status);

}  // namespace kccd::calib
