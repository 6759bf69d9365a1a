// The principal frame (PCA) of a point set.
#pragma once

#include <span>

#include <Eigen/Core>

#include "kccd/types.hpp"

namespace kccd::hull {

/// Mean and principal axes of a point set.
struct PrincipalFrame {
  Vec3 mean = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  ///< unit eigenvectors of the covariance, increasing spread
};

/// The mean and the covariance's eigenvectors (columns, by increasing eigenvalue) of a non-empty point set.
PrincipalFrame principalFrame(std::span<const Vec3> points);

}  // namespace kccd::hull
