// Camera intrinsics (focal lengths, principal point, lens distortion) from several images of a
// planar AprilTag board: the board, the per-image correspondences and the solve, with a status
// saying how it ended and, when it failed, what to add.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/correspondence.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/calib/tag_layout.hpp"

namespace kccd::calib {

/// A regular grid of tags: `cols` x `rows` tags with black squares of edge `tag_size` (metres),
/// `spacing` metres of white between neighbouring squares, ids first_id, first_id + 1, ... row
/// by row (left to right, top to bottom as the printed board is seen from its front).
struct TagGrid {
  int cols = 0;
  int rows = 0;
  double tag_size = 0.0;
  double spacing = 0.0;
  int first_id = 0;
};

/// A calibration board: tags that all lie in one plane and face the same way.
///
/// Board frame of a grid: origin at the centre of the first tag (top left), x to the right along
/// a row, y up (rows go towards -y), z out of the board towards the viewer; every tag has the
/// board's orientation (rpy 0). A board from a layout file keeps the file's frame.
struct Board {
  TagLayout layout;

  /// The grid board. Throws InputError ("grid: field: problem") for fewer than one tag, a size
  /// or spacing that is not finite and positive (spacing may be 0), or ids beyond kMaxTagId.
  static Board grid(const TagGrid& grid);
  /// A board from a tag layout: every tag corner within 1e-3 of the layout's extent of one plane
  /// and every tag facing the same side of it. Throws TagLayoutError ("source: tags: tag N ...").
  static Board fromLayout(const TagLayout& layout, const std::string& source);

  /// The correspondences of one image's detections (tagCorrespondences; unknown ids are left
  /// out). Throws TagDetectionError for a tag seen twice, `image` naming the image.
  std::vector<Correspondence> correspondences(const std::vector<TagDetection>& detections,
                                              const std::string& image) const;
};

/// The correspondences of one image of the board.
struct IntrinsicsView {
  std::string name;                    ///< unique, non-empty (an image file name); used in reports
  std::vector<Correspondence> points;  ///< names unique within the view; world points on the board
};

/// Tuning of calibrateIntrinsics. The defaults suit detected tag corners (sub-pixel noise).
struct IntrinsicsOptions {
  bool fix_k3 = false;          ///< keep k3 at 0 (k1 k2 p1 p2 only; for lenses with little distortion)
  bool rational = false;        ///< the rational model k1..k6 (8 coefficients; wide-angle lenses, many views)
  int min_views = 3;            ///< fewer usable views -> TooFewViews; at least 3
  int min_points_per_view = 8;  ///< a view with fewer corners (2 tags) is not used; at least 6
  /// The focal length is observable only when some views see the board tilted: the largest view
  /// tilt (angle between the board normal and the optical axis) must reach this, else FrontoParallel.
  double min_tilt_deg = 10.0;
  /// A view whose RMS exceeds max(outlier_ratio * median view RMS, outlier_floor_px) is left
  /// out and the solve repeated (worst first) while enough views remain.
  double outlier_ratio = 3.0;
  double outlier_floor_px = 1.0;
  /// Conditioning: sigmas of the solve scaled to max(RMS, noise_floor_px) of noise, so exact data
  /// on a bad geometry is still refused.
  double noise_floor_px = 0.5;
  double max_focal_sigma_ratio = 0.01;      ///< sigma(fx) / fx, sigma(fy) / fy; larger -> IllConditioned
  double max_principal_sigma_ratio = 0.02;  ///< sigma(cx) / width, sigma(cy) / height; larger -> IllConditioned
};

/// How an intrinsics solve ended. Only Solved comes with a camera.
enum class IntrinsicsStatus : std::uint8_t {
  Solved,          ///< camera holds the intrinsics (pose zero) and the quality figures
  TooFewViews,     ///< fewer than min_views views with enough board corners (or left after outliers)
  NotPlanar,       ///< the board points do not lie in one plane
  FrontoParallel,  ///< every view sees the board (nearly) face-on: the focal length is not observable
  IllConditioned,  ///< a solution fits but its parameters are ill-determined (or the lens model is unusable)
};

/// What happened to one view, in input order.
struct IntrinsicsViewReport {
  std::string name;
  int points = 0;
  bool used = false;                                         ///< in the final solve
  double rms_px = std::numeric_limits<double>::quiet_NaN();  ///< under the final (or best) solution; NaN if not solved
  double tilt_deg = std::numeric_limits<double>::quiet_NaN();  ///< board normal vs optical axis; NaN if unknown
  std::string note;                                            ///< why it is not used ("" when used)
};

/// Standard deviations of the solved parameters (pixels, and unitless for distortion), from the
/// solve's covariance at the measured noise (not the floored one used for the conditioning test).
struct IntrinsicsSigmas {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::vector<double> distortion;  ///< one per Camera::distortion coefficient (0 for a fixed one)
};

/// The outcome of calibrateIntrinsics.
struct IntrinsicsResult {
  IntrinsicsStatus status = IntrinsicsStatus::TooFewViews;
  std::string message;  ///< one line: what was found, and for a failure what to add
  Camera camera;        ///< Solved: the intrinsics, rvec = tvec = 0, reprojection_rms_px = rms_px
  double rms_px = std::numeric_limits<double>::quiet_NaN();  ///< over the points of the used views
  IntrinsicsSigmas sigmas;
  std::vector<IntrinsicsViewReport> views;  ///< per input view, in input order
  std::vector<std::string> used;            ///< names of the views in the final solve
  std::vector<std::string> rejected;        ///< names of the views left out, with a note (too few points, outlier)
};

/// Intrinsics of the camera that took `views` (images of `image_size` pixels) with cv::calibrateCamera:
/// k1 k2 p1 p2 k3 by default, no skew. Views with fewer than min_points_per_view points are left
/// out, the board plane is fitted to all world points (NotPlanar if they are not in one plane), the
/// board tilt of each view is estimated from its homography (FrontoParallel if every tilt is below
/// min_tilt_deg), outlier views are removed one by one, and the result is checked for conditioning.
/// Throws InputError for unusable input: an image size outside the camera bounds, an empty or
/// repeated view name, a repeated point name within a view, a non-finite coordinate, bad options.
IntrinsicsResult calibrateIntrinsics(const std::vector<IntrinsicsView>& views, cv::Size image_size,
                                     const IntrinsicsOptions& options = {});

/// Name of a status ("solved", "too few views", ...).
const char* toString(IntrinsicsStatus status);

/// The camera file of a solved result: cameraText's layout (what loadCamera reads) followed by the
/// fields OpenCV's calibration sample writes (avg_reprojection_error, nr_of_frames).
std::string intrinsicsCameraText(const IntrinsicsResult& result);

}  // namespace kccd::calib
