// The GL projection chain (render/projection.hpp) against cv::projectPoints, with and
// without distortion, and rasterised edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "support/cameras.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using namespace kccd::calib;
using kccd::testing::cvProject;
using kccd::testing::randomCamera;

// ---------------------------------------------------------------------------------------------
// Projection: the GL chain against cv::projectPoints

Vec3 randomVisiblePoint(std::mt19937_64& rng, const Camera& c) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Pose cam_to_world = c.worldToCamera().inverse();
  const double z = 0.3 + 5.0 * u(rng);
  const double px = -0.1 * c.width + 1.2 * c.width * u(rng), py = -0.1 * c.height + 1.2 * c.height * u(rng);
  const Vec3 cam((px - c.camera_matrix(0, 2)) / c.camera_matrix(0, 0) * z,
                 (py - c.camera_matrix(1, 2)) / c.camera_matrix(1, 1) * z, z);
  return cam_to_world * cam;
}

TEST(RenderProjection, PinholeMatchesProjectPoints) {
  std::mt19937_64 rng(11);
  double worst = 0.0;
  for (int cam = 0; cam < 20; ++cam) {
    const Camera c = randomCamera(rng, false, 1280, 720);
    for (double s : {1.0, 2.0}) {
      const Projection p(c, s);
      EXPECT_EQ(p.warps(), s != 1.0);
      for (int i = 0; i < 500; ++i) {
        const Vec3 x = randomVisiblePoint(rng, c);
        const cv::Point2d ref = cvProject(c, x);
        const Eigen::Vector2d got = p.project(x);
        worst = std::max(worst, std::hypot(got.x() - ref.x, got.y() - ref.y));
      }
    }
  }
  RecordProperty("worst_px", std::to_string(worst));
  std::cout << "pinhole: worst |GL chain - projectPoints| = " << worst << " px\n";
  EXPECT_LE(worst, 0.05);
}

// With distortion the output pixel at projectPoints(X) samples the pinhole image through the
// warp map (bilinear, as cv::remap does); that sample position must be where GL draws X.
TEST(RenderProjection, DistortionWarpMatchesProjectPoints) {
  std::mt19937_64 rng(12);
  double worst_map = 0.0, worst_project = 0.0;
  int checked = 0;
  for (int cam = 0; cam < 6; ++cam) {
    const Camera c = randomCamera(rng, true, 320, 240);
    const Projection p(c, cam % 2 == 0 ? 1.0 : 2.0);
    ASSERT_TRUE(p.warps());
    for (int i = 0; i < 2000; ++i) {
      const Vec3 x = randomVisiblePoint(rng, c);
      const cv::Point2d ref = cvProject(c, x);
      if (ref.x < 0 || ref.y < 0 || ref.x > c.width - 1 || ref.y > c.height - 1) continue;
      const int u0 = std::min(static_cast<int>(ref.x), c.width - 2),
                v0 = std::min(static_cast<int>(ref.y), c.height - 2);
      const double fu = ref.x - u0, fv = ref.y - v0;
      auto bilinear = [&](const cv::Mat& m) {
        return (1 - fu) * (1 - fv) * m.at<float>(v0, u0) + fu * (1 - fv) * m.at<float>(v0, u0 + 1) +
               (1 - fu) * fv * m.at<float>(v0 + 1, u0) + fu * fv * m.at<float>(v0 + 1, u0 + 1);
      };
      const double mx = bilinear(p.mapX()), my = bilinear(p.mapY());
      if (mx < 0 || my < 0) continue;  // outside the invertible region
      const Eigen::Vector2d gl = p.pinholePixel(x);
      // In output pixels: the pinhole image is `supersample` times finer.
      worst_map = std::max(worst_map, std::hypot(gl.x() - mx, gl.y() - my) / p.supersample());
      const Eigen::Vector2d proj = p.project(x);
      worst_project = std::max(worst_project, std::hypot(proj.x() - ref.x, proj.y() - ref.y));
      ++checked;
    }
  }
  std::cout << "distortion: " << checked << " points, worst warp-map error " << worst_map
            << " px, worst project() error " << worst_project << " px\n";
  EXPECT_GT(checked, 5000);
  EXPECT_LE(worst_map, 0.05);
  EXPECT_LE(worst_project, 0.05);
}

// Render-based: a large flat quadrilateral (drawn with a 10 micrometre radius, so its mesh is
// the quad itself to ~0.003 px) must cover exactly the pixel centres inside its projected
// outline, except within 0.05 px of the outline.
TEST(RenderProjection, RasterisedEdgesMatchProjectPoints) {
  std::mt19937_64 rng(13);
  RenderOptions opt;
  opt.min_radius = 1e-5;
  opt.msaa_samples = 0;
  int checked = 0, wrong = 0;
  for (int cam = 0; cam < 4; ++cam) {
    const Camera c = randomCamera(rng, false, 320, 240);
    Renderer r(c, opt);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    const std::vector<Vec3> quad = {Vec3(-0.4 + 0.1 * u(rng), -0.3 + 0.1 * u(rng), 0.1 * u(rng)),
                                    Vec3(0.4 + 0.1 * u(rng), -0.35 + 0.1 * u(rng), 0.1 * u(rng)),
                                    Vec3(0.35 + 0.1 * u(rng), 0.4 + 0.1 * u(rng), 0.1 * u(rng)),
                                    Vec3(-0.3 + 0.1 * u(rng), 0.3 + 0.1 * u(rng), 0.1 * u(rng))};
    // Make it planar: project onto the plane of the first three points.
    std::vector<Vec3> flat = quad;
    const Vec3 n = (quad[1] - quad[0]).cross(quad[2] - quad[0]).normalized();
    flat[3] -= n * n.dot(quad[3] - quad[0]);
    const Volume v{flat, 0.0, SafetyStatus::Clear, ""};
    const Frame f = r.render(std::span<const Volume>(&v, 1), Style{}, false, true);
    std::vector<cv::Point2d> corners;
    for (const Vec3& p : flat) corners.push_back(cvProject(c, p));
    std::vector<cv::Point2f> hull;
    std::vector<cv::Point2f> cf(corners.begin(), corners.end());
    cv::convexHull(cf, hull);
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) {
        const double d = cv::pointPolygonTest(hull, cv::Point2f(x, y), true);
        if (std::abs(d) <= 0.05) continue;
        ++checked;
        if ((d > 0) != (f.mask.at<uchar>(y, x) == 1)) ++wrong;
      }
  }
  EXPECT_GT(checked, 200000);
  EXPECT_EQ(wrong, 0) << "pixel centres more than 0.05 px from a projected edge drawn on the wrong side";
}

}  // namespace
