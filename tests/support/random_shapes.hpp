// Random point sets and SSCHs for property tests (deterministic for a given seed).
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kccd::testing {

using Points = std::vector<Eigen::Vector3d>;

/// A uniformly random rotation (normalised Gaussian quaternion).
inline Eigen::Matrix3d randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  if (q.norm() < 1e-9) return Eigen::Matrix3d::Identity();
  return q.normalized().toRotationMatrix();
}

/// n points in a randomly oriented, randomly stretched box of size ~scale around centre.
inline Points randomCloud(std::mt19937_64& rng, int n, const Eigen::Vector3d& centre, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d stretch(0.05 + std::abs(u(rng)), 0.05 + std::abs(u(rng)), 0.05 + std::abs(u(rng)));
  const Eigen::Matrix3d rot = randomRotation(rng);
  Points pts;
  pts.reserve(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d local(u(rng) * stretch.x(), u(rng) * stretch.y(), u(rng) * stretch.z());
    pts.push_back(centre + scale * (rot * local));
  }
  return pts;
}

inline Eigen::Vector3d randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector3d v(g(rng), g(rng), g(rng));
  return v.norm() > 1e-9 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
}

}  // namespace kccd::testing
