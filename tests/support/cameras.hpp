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

// The sample camera `c` at a quarter of its size (1280 x 720 -> 320 x 180, the same view): short runs.
inline Camera quarterSized(Camera c) {
  c.width /= 4;
  c.height /= 4;
  c.camera_matrix(0, 0) /= 4;
  c.camera_matrix(1, 1) /= 4;
  c.camera_matrix(0, 2) = (c.camera_matrix(0, 2) + 0.5) / 4 - 0.5;
  c.camera_matrix(1, 2) = (c.camera_matrix(1, 2) + 0.5) / 4 - 0.5;
  return c;
}

// `c` with its pose set to look from `eye` at `target` (z up in the world), OpenCV axes, turned
// by `roll` radians about the viewing direction.
inline Camera placedAt(Camera c, const Vec3& eye, const Vec3& target, double roll = 0.0) {
  const Vec3 z = (target - eye).normalized();
  const Vec3 x0 = z.cross(Vec3::UnitZ()).normalized();
  const Vec3 x = std::cos(roll) * x0 + std::sin(roll) * z.cross(x0);
  const Vec3 y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  cv::Matx33d rc;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rc(i, j) = r(i, j);
  cv::Rodrigues(rc, c.rvec);
  const Vec3 t = -(r * eye);
  c.tvec = cv::Vec3d(t.x(), t.y(), t.z());
  return c;
}

// A camera at `eye` looking at `target` (z up in the world), OpenCV axes.
inline Camera lookAt(const Vec3& eye, const Vec3& target, int w, int h, double f, std::vector<double> dist) {
  Camera c;
  c.width = w;
  c.height = h;
  c.camera_matrix = cv::Matx33d(f, 0, (w - 1) / 2.0 + 1.3, 0, f * 1.01, (h - 1) / 2.0 - 0.7, 0, 0, 1);
  c.distortion = std::move(dist);
  return placedAt(std::move(c), eye, target);
}

// The benchmarks' camera: 1280 x 720, f 1000 px, mild barrel distortion, at `eye` looking at `target`.
inline Camera hdCamera(const Vec3& eye, const Vec3& target) {
  Camera c;
  c.width = 1280;
  c.height = 720;
  c.camera_matrix = cv::Matx33d(1000, 0, 641.3, 0, 1000, 358.2, 0, 0, 1);
  c.distortion = {-0.11, 0.06, 0.0006, -0.0004, -0.01};
  return placedAt(std::move(c), eye, target);
}

// The angle between two rotations (Rodrigues vectors), degrees; accurate for tiny angles too.
inline double rotationErrorDeg(const cv::Vec3d& a, const cv::Vec3d& b) {
  cv::Matx33d ra, rb;
  cv::Rodrigues(a, ra);
  cv::Rodrigues(b, rb);
  const cv::Matx33d d = ra * rb.t();
  const double s = 0.5 * std::hypot(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  return std::atan2(s, 0.5 * (d(0, 0) + d(1, 1) + d(2, 2) - 1.0)) * 180.0 / CV_PI;
}

// Where the camera is in the world.
inline cv::Vec3d cameraCentre(const Camera& c) {
  cv::Matx33d r;
  cv::Rodrigues(c.rvec, r);
  return -(r.t() * c.tvec);
}

inline cv::Point2d cvProject(const Camera& c, const Vec3& p) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, c.rvec, c.tvec, c.camera_matrix, c.distortion,
                    out);
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

// `c` turned by `deg` about a random axis through its centre and moved `m` in a random direction.
inline Camera perturbed(const Camera& c, double deg, double m, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  cv::Vec3d axis(n(rng), n(rng), n(rng));
  axis *= (deg * M_PI / 180.0) / cv::norm(axis);
  cv::Vec3d dir(n(rng), n(rng), n(rng));
  dir *= m / cv::norm(dir);
  cv::Matx33d r, d;
  cv::Rodrigues(c.rvec, r);
  cv::Rodrigues(axis, d);
  const cv::Vec3d centre = -(r.t() * c.tvec) + dir;
  const cv::Matx33d r2 = d * r;
  Camera out = c;
  cv::Rodrigues(r2, out.rvec);
  out.tvec = -(r2 * centre);
  return out;
}

}  // namespace kccd::testing
