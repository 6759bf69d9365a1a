// The camera model: OpenCV intrinsics, lens distortion, pose and calibration quality, and the
// camera file that holds them (docs/formats.md section 3). No GL: calibration, rendering and the
// overlay all use this one model.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/types.hpp"

namespace kccd::calib {

/// A camera file that cannot be used: the message names the file and the field.
class CameraError : public InputError {
 public:
  using InputError::InputError;
};

/// Bounds of the cameras the suite accepts (checked by Camera::validate): what the renderer can draw.
inline constexpr int kMaxImageSide = 8192;         ///< image_width, image_height
inline constexpr long kMaxImagePixels = 1L << 24;  ///< width * height (4096 x 4096)
inline constexpr int kMaxPinholeSide = 8192;       ///< the widened pinhole image at supersample 1
inline constexpr double kMaxFocal = 1e6;           ///< fx, fy in 1 .. kMaxFocal pixels
inline constexpr double kMaxDistortion = 1e4;      ///< |k_i|, |p_i|, |s_i|; tilt |tx|, |ty| <= 1 rad
inline constexpr double kMaxTranslation = 1e6;     ///< |tvec| in metres
inline constexpr std::size_t kMaxCameraFileBytes = 1 << 20;

/// A calibrated camera in OpenCV's conventions (pixel centres at integer coordinates).
struct Camera {
  int width = 0;  ///< image size in pixels
  int height = 0;
  cv::Matx33d camera_matrix = cv::Matx33d::eye();  ///< fx 0 cx; 0 fy cy; 0 0 1 (no skew)
  std::vector<double> distortion;                  ///< OpenCV order: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]]
  cv::Vec3d rvec{0, 0, 0};                         ///< world -> camera rotation (Rodrigues vector)
  cv::Vec3d tvec{0, 0, 0};                         ///< world -> camera translation (metres)
  /// The model frame the camera is fixed to (a wrist or head camera): a joint's, body's or link's
  /// name; rvec/tvec are then that frame -> camera, and the camera moves with the robot's state.
  /// Empty: fixed in the world.
  std::string frame;
  /// Quality of a calibrated pose, as calibration writes it (absent in a file: unknown).
  std::optional<double> reprojection_rms_px;
  std::optional<double> rotation_sigma_deg;
  std::optional<double> position_sigma_m;

  /// True when some distortion coefficient is non-zero.
  bool distorted() const;
  /// The world -> camera transform (x right, y down, z forward).
  Pose worldToCamera() const;
  /// Checks sizes, finiteness and ranges, and that the distortion model can be inverted on the
  /// whole image border with a widened pinhole image of at most kMaxPinholeSide pixels a side;
  /// throws CameraError("<source>: <field>: <problem>").
  void validate(const std::string& source) const;
};

/// Whether a camera file must hold a pose: rendering needs one; calibrating from intrinsics also
/// reads OpenCV's own calibration output, which has none (rvec = tvec = 0 then). A file with one
/// of rvec, tvec and not the other is an error either way.
enum class CameraPose : std::uint8_t { Required, Optional };

/// Reads an OpenCV FileStorage camera file (image_width, image_height, camera_matrix,
/// distortion_coefficients, rvec, tvec) and validates it. The file must be a regular text file
/// of at most kMaxCameraFileBytes starting with `%YAML:1.x`, holding one YAML document whose
/// top level is a mapping without repeated keys. Throws CameraError (an InputError), never
/// anything else for any file content.
Camera loadCamera(const std::string& path, CameraPose pose = CameraPose::Required);
/// The text of a camera file in the same layout, quality figures included when known.
std::string cameraText(const Camera& camera);
/// Writes cameraText(camera) to `path` (not atomically: tools write through a temporary file).
void saveCamera(const Camera& camera, const std::string& path);

/// Normalised image coordinates of the pixel centres `pixels` (n x 1, CV_64FC2) through the
/// inverse of the camera's distortion model, and per pixel whether the inversion really solved it
/// (distorting the result again lands within 1e-3 px) within one image size of extra field.
void undistortPixels(const Camera& camera, const cv::Mat& pixels, cv::Mat& normal, std::vector<unsigned char>& valid);

}  // namespace kccd::calib
