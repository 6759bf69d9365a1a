#include "kccd/render/projection.hpp"

#include "kccd/render/lens_inverse.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <opencv2/calib3d.hpp>

namespace kccd::render {

Projection::Projection(const Camera& camera, double supersample) : camera_(camera), supersample_(supersample) {
  camera_.validate("camera");
  world_to_camera_ = camera.worldToCamera();
  if (!(supersample >= 1.0 && supersample <= 4.0))
    throw CameraError(InputLocation{"camera", 0, 0, "supersample"}, "must be in 1..4");
  const double s = supersample;
  const double fx = camera.camera_matrix(0, 0), fy = camera.camera_matrix(1, 1);
  const double cx = camera.camera_matrix(0, 2), cy = camera.camera_matrix(1, 2);
  pinhole_.fx = s * fx;
  pinhole_.fy = s * fy;
  if (!camera.distorted()) {
    // Same frame, scaled: output pixel u covers pinhole pixels around s (u + 0.5) - 0.5.
    pinhole_.cx = s * (cx + 0.5) - 0.5;
    pinhole_.cy = s * (cy + 0.5) - 0.5;
    pinhole_.width = static_cast<int>(std::lround(s * camera.width));
    pinhole_.height = static_cast<int>(std::lround(s * camera.height));
    warps_ = s != 1.0;
    stretch_ = 1.0 / s;
    for (const double x : {(-0.5 - cx) / fx, (camera.width - 0.5 - cx) / fx})
      for (const double y : {(-0.5 - cy) / fy, (camera.height - 0.5 - cy) / fy})
        obliquity_ = std::max(obliquity_, std::sqrt(1.0 + x * x + y * y));
    if (warps_) {
      map_x_.create(camera.height, camera.width, CV_32F);
      map_y_.create(camera.height, camera.width, CV_32F);
      for (int v = 0; v < camera.height; ++v)
        for (int u = 0; u < camera.width; ++u) {
          map_x_.at<float>(v, u) = static_cast<float>(s * (u + 0.5) - 0.5);
          map_y_.at<float>(v, u) = static_cast<float>(s * (v + 0.5) - 0.5);
        }
    }
    return;
  }
  // Normalised coordinates of every output pixel centre (the inverse of the distortion model),
  // computed once per lens and kept in the lens cache.
  const LensInverse inverse = lensInverse(camera);
  const cv::Mat& normal = inverse.normal;
  const std::vector<unsigned char>& valid = inverse.valid;
  // One pass over the pixels, in parallel blocks of rows (minima and maxima do not depend on the
  // order): the extent of the valid pixels' normalised coordinates, the obliquity, and the
  // Jacobian of the camera -> pinhole map from each pixel to its right and lower neighbours (left
  // and upper on the last column and row), whose smallest singular value is the least a camera
  // pixel spans in pinhole pixels, the inverse of the most a pinhole pixel spans in the camera.
  const int w = camera.width, h = camera.height;
  struct Extremes {
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, obliquity = 1.0, least = 1e300;
  };
  Extremes all;
  std::mutex merge;
  const double pfx = pinhole_.fx, pfy = pinhole_.fy;
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    Extremes e;
    for (int v = rows.start; v < rows.end; ++v)
      for (int u = 0; u < w; ++u) {
        const int i = v * w + u;
        if (!valid[i]) continue;
        const cv::Vec2d p = normal.at<cv::Vec2d>(i);
        e.xmin = std::min(e.xmin, p[0]), e.xmax = std::max(e.xmax, p[0]);
        e.ymin = std::min(e.ymin, p[1]), e.ymax = std::max(e.ymax, p[1]);
        e.obliquity = std::max(e.obliquity, std::sqrt(1.0 + p[0] * p[0] + p[1] * p[1]));
        const int iu = u + 1 < w ? i + 1 : i - 1, iv = v + 1 < h ? i + w : i - w;
        if (w < 2 || h < 2 || !valid[iu] || !valid[iv]) continue;
        const double su = u + 1 < w ? 1.0 : -1.0, sv = v + 1 < h ? 1.0 : -1.0;
        const cv::Vec2d du = (normal.at<cv::Vec2d>(iu) - p) * su, dv = (normal.at<cv::Vec2d>(iv) - p) * sv;
        const double a = du[0] * pfx, b = dv[0] * pfx, c = du[1] * pfy, d = dv[1] * pfy;
        const double t = a * a + b * b + c * c + d * d, det = a * d - b * c;
        const double largest = std::sqrt(0.5 * (t + std::sqrt(std::max(0.0, t * t - 4.0 * det * det))));
        e.least = std::min(e.least, largest > 0.0 ? std::abs(det) / largest : 0.0);
      }
    const std::lock_guard lock(merge);
    all.xmin = std::min(all.xmin, e.xmin), all.xmax = std::max(all.xmax, e.xmax);
    all.ymin = std::min(all.ymin, e.ymin), all.ymax = std::max(all.ymax, e.ymax);
    all.obliquity = std::max(all.obliquity, e.obliquity);
    all.least = std::min(all.least, e.least);
  });
  if (all.xmin > all.xmax)
    throw CameraError(InputLocation{"camera", 0, 0, "distortion_coefficients"},
                      "the lens model cannot be inverted anywhere in the image");
  const double pad = 2.0;
  pinhole_.cx = -all.xmin * pinhole_.fx + pad;
  pinhole_.cy = -all.ymin * pinhole_.fy + pad;
  pinhole_.width = static_cast<int>(std::ceil((all.xmax - all.xmin) * pinhole_.fx + 2 * pad)) + 1;
  pinhole_.height = static_cast<int>(std::ceil((all.ymax - all.ymin) * pinhole_.fy + 2 * pad)) + 1;
  warps_ = true;
  obliquity_ = all.obliquity;
  const double least = all.least;
  stretch_ = least >= 1e300 ? 1.0 / s : least > 0.0 ? 1.0 / least : std::numeric_limits<double>::infinity();
  map_x_.create(camera.height, camera.width, CV_32F);
  map_y_.create(camera.height, camera.width, CV_32F);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      auto* mx = map_x_.ptr<float>(v);
      auto* my = map_y_.ptr<float>(v);
      for (int u = 0, i = v * w; u < w; ++u, ++i) {
        const cv::Vec2d p = normal.at<cv::Vec2d>(i);
        mx[u] = valid[i] ? static_cast<float>(p[0] * pinhole_.fx + pinhole_.cx) : -1e6f;
        my[u] = valid[i] ? static_cast<float>(p[1] * pinhole_.fy + pinhole_.cy) : -1e6f;
      }
    }
  });
}

std::array<float, 16> Projection::glMatrix(double near, double far) const {
  const Pinhole& p = pinhole_;
  std::array<float, 16> m{};
  m[0] = static_cast<float>(2.0 * p.fx / p.width);
  m[5] = static_cast<float>(2.0 * p.fy / p.height);
  m[8] = static_cast<float>(2.0 * (p.cx + 0.5) / p.width - 1.0);
  m[9] = static_cast<float>(2.0 * (p.cy + 0.5) / p.height - 1.0);
  m[10] = static_cast<float>((far + near) / (far - near));
  m[11] = 1.0f;
  m[14] = static_cast<float>(-2.0 * far * near / (far - near));
  return m;
}

Eigen::Vector2d Projection::pinholePixel(const Vec3& world, double near, double far) const {
  const Vec3 c = world_to_camera_ * world;
  const double x = static_cast<float>(c.x()), y = static_cast<float>(c.y()), z = static_cast<float>(c.z());
  const std::array<float, 16> m = glMatrix(near, far);
  const double xc = m[0] * x + m[8] * z, yc = m[5] * y + m[9] * z, wc = m[11] * z;
  const double xw = (xc / wc + 1.0) * 0.5 * pinhole_.width, yw = (yc / wc + 1.0) * 0.5 * pinhole_.height;
  return {xw - 0.5, yw - 0.5};
}

Eigen::Vector2d Projection::project(const Vec3& world) const {
  const Eigen::Vector2d p = pinholePixel(world);
  if (!camera_.distorted()) return (p.array() + 0.5) / supersample_ - 0.5;
  const cv::Vec3d normal((p.x() - pinhole_.cx) / pinhole_.fx, (p.y() - pinhole_.cy) / pinhole_.fy, 1.0);
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Vec3d>{normal}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera_.camera_matrix,
                    camera_.distortion, out);
  return {out[0].x, out[0].y};
}

}  // namespace kccd::render
