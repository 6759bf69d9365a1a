// An independent CPU silhouette of an SSCH as a camera sees it, for checking rendered masks
// (render) and overlays (overlay): shares no code with the renderer.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"

namespace kccd::testing {

// The silhouette of an SSCH from dense sphere samples projected with cv::projectPoints: balls of
// the radius centred on a dense set of points of the core hull (vertices, edges, triangles),
// each ball's rim sampled densely, projected, and its convex outline filled at 7x resolution
// (pixel (x, y) is the 7x pixel (7x + 3, 7y + 3)), so the fill follows pixel centres to ~0.1 px.
// This is the 7x image itself (kSilhouetteScale); cpuSilhouette below samples it at pixel centres.
// A smaller `k` (odd) is faster and follows pixel centres to about 0.5 / k px.
constexpr int kSilhouetteScale = 7;
inline cv::Mat cpuSilhouetteFine(const calib::Camera& c, const std::vector<Vec3>& pts, double radius,
                                 int k = kSilhouetteScale) {
  cv::Mat big = cv::Mat::zeros(c.height * k, c.width * k, CV_8UC1);
  std::vector<Vec3> centres = pts;
  const double step = radius / 6.0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size(); ++j)
      for (std::size_t l = j; l < pts.size(); ++l) {
        // Points of the triangle (i, j, l) (an edge when l == j) at spacing <= step.
        const double len = std::max((pts[j] - pts[i]).norm(), (pts[l] - pts[i]).norm());
        const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
        for (int a = 0; a <= n; ++a)
          for (int b = 0; a + b <= n; ++b) {
            const double s = static_cast<double>(a) / n, t = static_cast<double>(b) / n;
            centres.push_back(pts[i] + s * (pts[j] - pts[i]) + t * (pts[l] - pts[i]));
          }
      }
  // A ball's image is the image of its rim, the circle where the rays from the camera's centre
  // touch it (every other point of the ball lies on a ray inside that cone, and the lens maps the
  // cone's inside to the inside of the rim's image), so each ball's outline is its rim sampled
  // densely; a ball around the camera's centre (no rim) is sampled over its whole surface.
  cv::Mat rotation;
  cv::Rodrigues(c.rvec, rotation);
  const cv::Mat centre_cv = -rotation.t() * cv::Mat(c.tvec).reshape(1, 3);
  const Vec3 eye(centre_cv.at<double>(0), centre_cv.at<double>(1), centre_cv.at<double>(2));
  constexpr int kRim = 256;
  std::vector<cv::Point3d> sphere;
  const int m = 1500;
  for (int i = 0; i < m; ++i) {  // Fibonacci sphere
    const double z = 1.0 - (2.0 * i + 1.0) / m, rr = std::sqrt(1.0 - z * z), phi = i * 2.399963229728653;
    sphere.emplace_back(rr * std::cos(phi), rr * std::sin(phi), z);
  }
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> img;
  for (const Vec3& ce : centres) {
    const Vec3 to_eye = eye - ce;
    const double d = to_eye.norm();
    world.clear();
    if (d > radius * (1.0 + 1e-9)) {
      const Vec3 axis = to_eye / d;
      const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
      const Vec3 mid = ce + axis * (radius * radius / d);
      const double rho = radius * std::sqrt(1.0 - (radius / d) * (radius / d));
      for (int i = 0; i < kRim; ++i) {
        const double phi = 2.0 * M_PI * i / kRim;
        const Vec3 p = mid + rho * (std::cos(phi) * u + std::sin(phi) * v);
        world.emplace_back(p.x(), p.y(), p.z());
      }
    } else {
      for (const cv::Point3d& q : sphere) world.push_back(cv::Point3d(ce.x(), ce.y(), ce.z()) + radius * q);
    }
    cv::projectPoints(world, c.rvec, c.tvec, c.camera_matrix, c.distortion, img);
    std::vector<cv::Point> fixed;
    for (const cv::Point2d& p : img)
      fixed.emplace_back(static_cast<int>(std::lround((p.x * k + (k - 1) / 2.0) * 256)),
                         static_cast<int>(std::lround((p.y * k + (k - 1) / 2.0) * 256)));
    std::vector<cv::Point> hull;
    cv::convexHull(fixed, hull);
    cv::fillConvexPoly(big, hull, cv::Scalar(1), cv::LINE_8, 8);
  }
  return big;
}

// The silhouette at pixel centres (1 inside, 0 outside).
inline cv::Mat cpuSilhouette(const calib::Camera& c, const std::vector<Vec3>& pts, double radius,
                             int k = kSilhouetteScale) {
  const cv::Mat big = cpuSilhouetteFine(c, pts, radius, k);
  cv::Mat out(c.height, c.width, CV_8UC1);
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) out.at<uchar>(y, x) = big.at<uchar>(y * k + k / 2, x * k + k / 2);
  return out;
}

}  // namespace kccd::testing
