#include "kccd/hull/principal.hpp"

#include <Eigen/Eigenvalues>

namespace kccd::hull {

PrincipalFrame principalFrame(std::span<const Vec3> points) {
  PrincipalFrame p;
  for (const Vec3& v : points) p.mean += v;
  p.mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& v : points) cov += (v - p.mean) * (v - p.mean).transpose();
  p.axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors();
  return p;
}

}  // namespace kccd::hull
