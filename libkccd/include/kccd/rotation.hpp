// Rotation conversions shared by the model reader, kinematics and the sweep bounds.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kccd {

/// The rotation by `angle` about the axis v / angle, where `angle` is |v| as the caller measured
/// it (v.norm() or v.stableNorm()); `angle` must be non-zero.
inline Eigen::Matrix3d rotationAboutVector(const Eigen::Vector3d& v, double angle) {
  return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
}

/// exp of the rotation vector v: the rotation by |v| about v / |v| (v.norm()), the identity for v = 0.
inline Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0.0 ? rotationAboutVector(v, angle) : Eigen::Matrix3d::Identity();
}

/// URDF roll-pitch-yaw (x, y, z): fixed-axis roll about x, then pitch about y, then yaw about z.
inline Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace kccd
