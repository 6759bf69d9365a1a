// How a calibrated camera is drawn with GL: the undistorted pinhole image GL renders, the warp into
// the camera image, and the GL matrix that reproduces cv::projectPoints.
#pragma once

#include <array>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/types.hpp"

namespace kccd::render {

using calib::Camera;
using calib::CameraError;

/// The undistorted pinhole camera GL actually renders with. Pixel centres are at integers.
struct Pinhole {
  int width = 0;
  int height = 0;
  double fx = 1, fy = 1, cx = 0, cy = 0;
};

/// How a Camera is drawn with GL: a pinhole image (the camera's intrinsics scaled by
/// `supersample`, widened so that the distorted frame is covered), then — when the camera
/// distorts or supersamples — a warp to the camera image through a per-pixel map
/// (output pixel centre -> pinhole pixel), computed once with cv::undistortPoints (iterated to
/// convergence) per lens: kept between runs in the lens cache (lens_inverse.hpp).
class Projection {
 public:
  explicit Projection(const Camera& camera, double supersample = 1.0);

  const Camera& camera() const { return camera_; }
  const Pinhole& pinhole() const { return pinhole_; }
  double supersample() const { return supersample_; }
  /// True when the GL image is warped into the camera image (distortion or supersampling).
  bool warps() const { return warps_; }
  /// Output pixel -> pinhole pixel, CV_32FC1 each (for cv::remap); empty when !warps().
  const cv::Mat& mapX() const { return map_x_; }
  const cv::Mat& mapY() const { return map_y_; }

  /// The GL projection matrix (column-major, as uploaded) for camera coordinates x right,
  /// y down, z forward. It maps image rows top-down onto GL rows, so glReadPixels returns
  /// the image in OpenCV row order without a flip (triangles wound counter-clockwise seen from
  /// outside appear clockwise: the renderer sets glFrontFace(GL_CW)).
  std::array<float, 16> glMatrix(double near, double far) const;

  /// CPU mirror of the GL chain: world -> camera (double) -> float vertex -> matrix as
  /// uploaded -> perspective divide -> viewport -> pinhole pixel (pixel centres at integers).
  Eigen::Vector2d pinholePixel(const Vec3& world, double near = 0.05, double far = 100.0) const;
  /// Where the drawn image shows a world point in the camera image: pinholePixel, then the
  /// camera's distortion model (what the warp inverts). Equals cv::projectPoints to ~1e-3 px.
  Eigen::Vector2d project(const Vec3& world) const;
  /// The most one pinhole pixel spans in the camera image, in camera pixels: the largest singular
  /// value of the pinhole -> camera map's Jacobian over the image (1 / supersample without
  /// distortion). A label taken at the nearest pinhole pixel lies within sqrt(2)/2 of this.
  double stretch() const { return stretch_; }
  /// The largest sqrt(1 + x^2 + y^2) over the image's normalised coordinates (x, y): a point at
  /// depth z moved by d metres moves at most f d sqrt(1 + x^2 + y^2) / z pinhole pixels at scale 1.
  double obliquity() const { return obliquity_; }

 private:
  Camera camera_;
  double supersample_ = 1.0;
  Pinhole pinhole_;
  bool warps_ = false;
  double stretch_ = 1.0, obliquity_ = 1.0;
  cv::Mat map_x_, map_y_;
  Pose world_to_camera_;
};

}  // namespace kccd::render
