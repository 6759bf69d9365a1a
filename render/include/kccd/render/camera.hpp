// The camera model: OpenCV intrinsics, lens distortion and pose, read from a camera file, and
// how the renderer reproduces cv::projectPoints with GL (pinhole render + distortion warp).
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/ssch.hpp"

namespace kccd::render {

/// A camera file that cannot be used: the message names the file and the field.
class CameraError : public InputError {
 public:
  using InputError::InputError;
};

/// Bounds of the cameras the renderer accepts (checked by Camera::validate).
inline constexpr int kMaxImageSide = 8192;                ///< image_width, image_height
inline constexpr long kMaxImagePixels = 1L << 24;         ///< width * height (4096 x 4096)
inline constexpr int kMaxPinholeSide = 8192;              ///< the widened pinhole image at supersample 1
inline constexpr double kMaxFocal = 1e6;                  ///< fx, fy in 1 .. kMaxFocal pixels
inline constexpr double kMaxDistortion = 1e4;             ///< |k_i|, |p_i|, |s_i|; tilt |tx|, |ty| <= 1 rad
inline constexpr double kMaxTranslation = 1e6;            ///< |tvec| in metres
inline constexpr std::size_t kMaxCameraFileBytes = 1 << 20;

/// A calibrated camera in OpenCV's conventions (pixel centres at integer coordinates).
struct Camera {
  int width = 0;                   ///< image size in pixels
  int height = 0;
  cv::Matx33d camera_matrix = cv::Matx33d::eye();  ///< fx 0 cx; 0 fy cy; 0 0 1 (no skew)
  std::vector<double> distortion;  ///< OpenCV order: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]]
  cv::Vec3d rvec{0, 0, 0};         ///< world -> camera rotation (Rodrigues vector)
  cv::Vec3d tvec{0, 0, 0};         ///< world -> camera translation (metres)

  /// True when some distortion coefficient is non-zero.
  bool distorted() const;
  /// The world -> camera transform (x right, y down, z forward).
  Pose worldToCamera() const;
  /// Checks sizes, finiteness and ranges, and that the distortion model can be inverted on the
  /// whole image border with a widened pinhole image of at most kMaxPinholeSide pixels a side;
  /// throws CameraError("<source>: <field>: <problem>").
  void validate(const std::string& source) const;
};

/// Reads an OpenCV FileStorage camera file (image_width, image_height, camera_matrix,
/// distortion_coefficients, rvec, tvec) and validates it. The file must be a regular text file
/// of at most kMaxCameraFileBytes starting with `%YAML:1.x`, holding one YAML document whose
/// top level is a mapping without repeated keys. Throws CameraError (an InputError), never
/// anything else for any file content.
Camera loadCamera(const std::string& path);
/// Writes a camera file in the same layout (used by tests and tools).
void saveCamera(const Camera& camera, const std::string& path);

/// The undistorted pinhole camera GL actually renders with. Pixel centres are at integers.
struct Pinhole {
  int width = 0;
  int height = 0;
  double fx = 1, fy = 1, cx = 0, cy = 0;
};

/// How a Camera is drawn with GL: a pinhole image (the camera's intrinsics scaled by
/// `supersample`, widened so that the distorted frame is covered), then — when the camera
/// distorts or supersamples — a warp to the camera image through a per-pixel map
/// (output pixel centre -> pinhole pixel), computed once with cv::undistortPoints (iterated to convergence).
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

 private:
  Camera camera_;
  double supersample_ = 1.0;
  Pinhole pinhole_;
  bool warps_ = false;
  cv::Mat map_x_, map_y_;
  Pose world_to_camera_;
};

}  // namespace kccd::render
