// How far apart two camera poses are: the angle between their orientations and the distance
// between their centres (a solved camera against a known one).
#pragma once

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"

namespace kccd::calib {

/// The camera's centre in the world (metres): -R^T t of its world -> camera pose.
cv::Vec3d cameraCentre(const Camera& camera);

/// The difference between two camera poses.
struct PoseDifference {
  double rotation_deg = 0.0;  ///< angle of the rotation between the orientations (accurate for tiny angles too)
  double position_m = 0.0;    ///< distance between the camera centres
};

/// The difference between the poses of `a` and `b` (their intrinsics are not compared).
PoseDifference poseDifference(const Camera& a, const Camera& b);

}  // namespace kccd::calib
