// Camera fixtures for the calib, render and overlay tests: cameras placed by eye and target, and
// random cameras around the origin, in OpenCV's conventions.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/camera.hpp"

namespace kccd::testing {

using calib::Camera;

// A camera at `eye` looking at `target` (z up in the world), OpenCV axes.
inline Camera lookAt(const Vec3& eye, const Vec3& target, int w, int h, double f, std::vector<double> dist) {
  const Vec3 z = (target - eye).normalized();
  const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
  const Vec3 y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  cv::Matx33d rc;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rc(i, j) = r(i, j);
  Camera c;
  c.width = w;
  c.height = h;
  c.camera_matrix = cv::Matx33d(f, 0, (w - 1) / 2.0 + 1.3, 0, f * 1.01, (h - 1) / 2.0 - 0.7, 0, 0, 1);
  c.distortion = std::move(dist);
  cv::Rodrigues(rc, c.rvec);
  const Vec3 t = -(r * eye);
  c.tvec = cv::Vec3d(t.x(), t.y(), t.z());
  return c;
}

inline cv::Point2d cvProject(const Camera& c, const Vec3& p) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, c.rvec, c.tvec, c.camera_matrix, c.distortion, out);
  return out[0];
}

inline Camera randomCamera(std::mt19937_64& rng, bool distorted, int w = 320, int h = 240) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dist = 1.5 + 0.4 * u(rng);
  const Vec3 dir = Vec3(u(rng), u(rng), 0.3 + 0.5 * std::abs(u(rng))).normalized();
  std::vector<double> d(5, 0.0);
  if (distorted) d = {0.15 * u(rng) - 0.05, 0.05 * u(rng), 0.002 * u(rng), 0.002 * u(rng), 0.01 * u(rng)};
  return lookAt(dist * dir, Vec3(0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng)), w, h, 0.9 * w * (1.0 + 0.2 * u(rng)), d);
}

}  // namespace kccd::testing
