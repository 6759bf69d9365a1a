// The renderer: projection against cv::projectPoints, meshes that contain the true volume, masks
// against an independent CPU silhouette, golden images (camera files: test_calib.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>

#include <sys/stat.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/checker.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "support/cameras.hpp"
#include "support/silhouette.hpp"
#include "support/golden.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using namespace kccd::calib;
using kccd::testing::cpuSilhouette;
using kccd::testing::cvProject;
using kccd::testing::lookAt;
using kccd::testing::randomCamera;

const std::string kData = KCCD_DATA_DIR;

TEST(RenderCamera, TinyImagesRender) {
  for (const auto& [w, h] : {std::pair{8, 3}, std::pair{3, 8}, std::pair{1, 1}}) {
    Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), w, h, 3.0 * w, {-0.1, 0.01, 0, 0, 0});
    c.camera_matrix(0, 2) = (w - 1) / 2.0;
    c.camera_matrix(1, 2) = (h - 1) / 2.0;
    Renderer r(c);
    const std::vector<Vec3> ball = {Vec3(0, 0, 0)};
    const Volume v[] = {{ball, 1.5, VolumeStatus::Clear, "ball"}};  // wider than the view
    const Frame f = r.render(v, Style{.labels = true, .legend = true});
    EXPECT_EQ(f.bgra.cols, w);
    EXPECT_EQ(f.bgra.rows, h);
    EXPECT_EQ(f.pixels[0], w * h) << w << "x" << h;
  }
}

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
      const int u0 = std::min(static_cast<int>(ref.x), c.width - 2), v0 = std::min(static_cast<int>(ref.y), c.height - 2);
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
    const Volume v{flat, 0.0, VolumeStatus::Clear, ""};
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

// ---------------------------------------------------------------------------------------------
// Meshes

struct Shape {
  std::vector<Vec3> points;
  double radius;
  std::string what;
};

std::vector<Shape> testShapes(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  auto rnd = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  std::vector<Shape> s = {
      {{Vec3(0.1, 0.2, 0.3)}, 0.2, "one point"},
      {{Vec3(0.1, 0.2, 0.3)}, 0.0, "one point, radius 0"},
      {{Vec3(0, 0, 0), Vec3(0.5, 0.1, 0)}, 0.05, "segment"},
      {{Vec3(0, 0, 0), Vec3(0.5, 0.1, 0)}, 0.0, "segment, radius 0"},
      {{Vec3(0, 0, 0), Vec3(0.25, 0.05, 0), Vec3(0.5, 0.1, 0)}, 0.03, "collinear"},
      {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0), Vec3(0.5, 0.5, 0)}, 0.02, "flat square"},
      {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}, 0.0, "flat square, radius 0"},
      {{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0.3, 0, 0)}, 0.1, "duplicates"},
      {{Vec3(1000, 2000, -500), Vec3(1000.5, 2000, -500)}, 0.05, "far from the origin"},
  };
  for (int i = 0; i < 12; ++i) {
    Shape sh;
    const int n = 1 + i % 9;
    for (int k = 0; k < n; ++k) sh.points.push_back(rnd());
    sh.radius = i % 4 == 0 ? 0.0 : 0.3 * std::abs(u(rng));
    sh.what = "random " + std::to_string(n) + " points";
    s.push_back(sh);
  }
  return s;
}

TEST(RenderMesh, ContainsTheTrueVolume) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  for (const Shape& sh : testShapes(rng))
    for (int level = 0; level <= 3; ++level) {
      SCOPED_TRACE(sh.what + ", level " + std::to_string(level));
      const Mesh m = buildSschMesh(sh.points, sh.radius, level);
      const double r = std::max(sh.radius, kMinDrawRadius);
      ASSERT_GE(m.triangles.size(), 4u);
      // Closed: every edge has two triangles; Euler characteristic 2.
      for (const auto& e : m.edges) ASSERT_NE(e[2], e[3]);
      EXPECT_EQ(static_cast<long>(m.vertices.size()) - static_cast<long>(m.edges.size()) +
                    static_cast<long>(m.triangles.size()),
                2);
      // Exact containment: for every face plane, the support of the SSCH in its normal lies inside.
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const Vec3& n = m.normals[t];
        const double offset = n.dot(m.vertices[m.triangles[t][0]]);
        double support = -1e300;
        for (const Vec3& p : sh.points) support = std::max(support, n.dot(p));
        ASSERT_LE(support + r, offset + 1e-9) << "face " << t;
        // Winding agrees with the outward normal.
        const auto& tri = m.triangles[t];
        EXPECT_GE((m.vertices[tri[1]] - m.vertices[tri[0]]).cross(m.vertices[tri[2]] - m.vertices[tri[0]]).dot(n), 0.0);
      }
      // Sampled surface points (a core point's support point plus r in a random direction, and
      // points on segments between core points pushed out by r) lie inside every half-space.
      for (int k = 0; k < 300; ++k) {
        const Vec3 dir = Vec3(g(rng), g(rng), g(rng)).normalized();
        const Vec3& a = sh.points[rng() % sh.points.size()];
        const Vec3& b = sh.points[rng() % sh.points.size()];
        const Vec3 x = a + u(rng) * (b - a) + r * dir;
        for (std::size_t t = 0; t < m.triangles.size(); ++t)
          ASSERT_LE(m.normals[t].dot(x), m.normals[t].dot(m.vertices[m.triangles[t][0]]) + 1e-9);
      }
      // Not much larger than needed: every vertex is within the tessellation's outward error.
      const double allowed = r * (spherePolytope(level).scale - 1.0) + 1e-5 * (1.0 + 2000.0) * spherePolytope(level).scale;
      for (const Vec3& v : m.vertices) {
        double nearest = 1e300;  // distance to the nearest core point bounds the distance to the hull
        for (const Vec3& p : sh.points) nearest = std::min(nearest, (v - p).norm());
        EXPECT_LE(nearest - r, allowed + 1e-9);
      }
    }
}

TEST(RenderMesh, TessellationErrorShrinksWithLevel) {
  EXPECT_GT(spherePolytope(1).scale, spherePolytope(2).scale);
  EXPECT_GT(spherePolytope(2).scale, spherePolytope(3).scale);
  EXPECT_LT(spherePolytope(3).scale - 1.0, 0.005);
  EXPECT_EQ(spherePolytope(2).vertices.size(), 162u);
}

TEST(RenderMesh, CacheReusesUnchangedShapes) {
  MeshCache cache;
  const std::vector<Vec3> a = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  std::vector<Vec3> b = a;
  cache.nextFrame();
  const auto m1 = cache.get(a, 0.1, 2);
  const auto m2 = cache.get(b, 0.1, 2);
  EXPECT_EQ(m1.get(), m2.get());
  EXPECT_EQ(cache.built(), 1u);
  b[1].x() = std::nextafter(1.0, 2.0);
  EXPECT_NE(cache.get(b, 0.1, 2).get(), m1.get());
  EXPECT_NE(cache.get(a, 0.1000001, 2).get(), m1.get());
  EXPECT_EQ(cache.built(), 3u);
}

// ---------------------------------------------------------------------------------------------
// Masks against an independent CPU silhouette


TEST(RenderMask, MatchesIndependentCpuSilhouette) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_iou = 1.0, worst_boundary = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    const Camera c = randomCamera(rng, trial % 4 != 3);  // mostly with distortion
    std::vector<Vec3> pts;
    const int n = 1 + trial % 4;
    for (int i = 0; i < n; ++i) pts.push_back(Vec3(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)));
    const double radius = 0.15 + 0.1 * std::abs(u(rng));
    const cv::Mat cpu = cpuSilhouette(c, pts, radius);
    Renderer r(c);
    const Volume v{pts, radius, VolumeStatus::Clear, ""};
    const Frame f = r.render(std::span<const Volume>(&v, 1), Style{}, false, true);
    const cv::Mat gl = f.mask > 0, ref = cpu > 0;
    const double inter = cv::countNonZero(gl & ref), uni = cv::countNonZero(gl | ref);
    const double iou = inter / uni;
    worst_iou = std::min(worst_iou, iou);
    // Containment up to a one-pixel boundary: every CPU pixel is in the mask or next to it.
    cv::Mat grown;
    cv::dilate(gl, grown, cv::Mat::ones(3, 3, CV_8U));
    const int outside = cv::countNonZero(ref & ~grown);
    const int boundary = cv::countNonZero(ref & ~gl);
    SCOPED_TRACE("trial " + std::to_string(trial) + ": mask " + std::to_string(cv::countNonZero(gl)) + " px, CPU " +
                 std::to_string(cv::countNonZero(ref)) + " px, common " + std::to_string(static_cast<int>(inter)));
    EXPECT_GT(uni, 2000);
    EXPECT_GE(iou, 0.98);
    EXPECT_EQ(outside, 0);
    EXPECT_LE(boundary, 0.02 * cv::countNonZero(ref));
    worst_boundary = std::max(worst_boundary, static_cast<double>(boundary) / cv::countNonZero(ref));
  }
  std::cout << "mask vs CPU silhouette: worst IoU " << worst_iou << ", CPU pixels outside the mask (all within 1 px): at most "
            << 100.0 * worst_boundary << "% of the silhouette\n";
}

TEST(RenderMask, NearestBodyWinsAndLabelsAreIndexPlusOne) {
  const Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), 160, 120, 150, {0, 0, 0, 0, 0});
  Renderer r(c);
  const std::vector<Vec3> far = {Vec3(-0.3, 0, 0)}, near = {Vec3(0.3, 0.1, 0)};
  // The far one first in the list, so drawing order alone would let it win.
  const Volume v[] = {{far, 0.25, VolumeStatus::Clear, "far"}, {near, 0.15, VolumeStatus::Colliding, "near"}};
  const Frame f = r.render(v, Style{.legend = false}, true, true);
  const cv::Point centre_near(static_cast<int>(std::lround(r.projection().project(near[0]).x())),
                              static_cast<int>(std::lround(r.projection().project(near[0]).y())));
  EXPECT_EQ(f.mask.at<uchar>(centre_near), 2);
  EXPECT_EQ(f.mask.at<uchar>(0, 0), 0);
  EXPECT_GT(f.pixels[0], 0);
  EXPECT_GT(f.pixels[1], 0);
  EXPECT_EQ(f.pixels[0] + f.pixels[1], cv::countNonZero(f.mask));
  // Straight alpha: the fill of the near body alone shows its colour at the fill opacity.
  const cv::Point far_only(static_cast<int>(std::lround(r.projection().project(far[0]).x())) - 10,
                           static_cast<int>(std::lround(r.projection().project(far[0]).y())));
  ASSERT_EQ(f.mask.at<uchar>(far_only), 1);
  const cv::Vec4b px = f.bgra.at<cv::Vec4b>(far_only);
  EXPECT_NEAR(px[3], 0.35 * 255, 2);
  const cv::Scalar green = statusColour(VolumeStatus::Clear);
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(px[ch], green[ch], 3) << ch;
  EXPECT_EQ(f.bgra.at<cv::Vec4b>(c.height - 1, c.width - 1)[3], 0);
}

TEST(RenderMask, DegenerateVolumesAreVisible) {
  const Camera c = lookAt(Vec3(1.5, -1.0, 1.0), Vec3(0, 0, 0), 160, 120, 150, {-0.1, 0.01, 0, 0, 0});
  Renderer r(c);
  const std::vector<Vec3> square = {Vec3(-0.3, -0.3, 0), Vec3(0.3, -0.3, 0), Vec3(0.3, 0.3, 0), Vec3(-0.3, 0.3, 0)};
  const std::vector<Vec3> segment = {Vec3(-0.4, 0.4, 0.2), Vec3(0.4, 0.4, 0.2)};
  const std::vector<Vec3> point = {Vec3(0, 0, 0.5)};
  const Volume v[] = {{square, 0.0, VolumeStatus::Clear, ""},
                      {segment, 0.0, VolumeStatus::Clear, ""},
                      {point, 0.05, VolumeStatus::Clear, ""}};
  const Frame f = r.render(v, Style{}, true, true);
  EXPECT_GT(f.pixels[0], 500);  // a flat square seen at an angle
  EXPECT_GT(f.pixels[2], 20);    // a ball
  EXPECT_GT(f.pixels[1], 0);    // a radius-0 segment, drawn 1 mm thick
  EXPECT_GT(cv::countNonZero(f.mask), 500);
}

TEST(RenderMask, VolumesThatCannotBeDrawnAreReported) {
  // Camera at x = 2 looking along -x: camera z = -world x, camera x = world -y (right).
  const Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), 160, 120, 150, {0, 0, 0, 0, 0});
  Renderer r(c);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Vec3> behind = {Vec3(5, 0, 0)}, far = {Vec3(-2e7, 0, 0)}, bad = {Vec3(nan, 0, 0)},
                          distant = {Vec3(-500, 0, 0)}, off_axis = {Vec3(1.9999, -1e5, 0)};
  const Volume v[] = {{behind, 0.5, VolumeStatus::Clear, "behind"},  {far, 1e3, VolumeStatus::Clear, "far"},
                      {bad, 0.1, VolumeStatus::Clear, "bad"},        {distant, 30, VolumeStatus::Clear, "distant"},
                      {off_axis, 0.01, VolumeStatus::Clear, "off axis"}};
  const Frame f = r.render(v, Style{.labels = true}, true, true);
  EXPECT_EQ(f.visibility[0], Visibility::BehindCamera);
  EXPECT_EQ(f.visibility[1], Visibility::BeyondFar);
  EXPECT_EQ(f.visibility[2], Visibility::NotFinite);
  EXPECT_EQ(f.visibility[3], Visibility::Drawn);
  EXPECT_EQ(f.visibility[4], Visibility::Drawn);  // its label (centre at ~1e11 px) is skipped
  EXPECT_EQ(f.pixels[0] + f.pixels[1] + f.pixels[2], 0);
  EXPECT_GT(f.pixels[3], 50);  // 500 m away, beyond the default far plane (100 m): still drawn
  EXPECT_GT(f.far, 500.0);
  // 1 cm from the camera (closer than the default near plane, 5 cm): a ball of 2 cm radius
  // seen from 1 cm covers the whole view, not clipped away by the near plane.
  const std::vector<Vec3> close = {Vec3(1.97, 0, 0)};
  const Volume u[] = {{close, 0.02, VolumeStatus::Clear, "close"}};
  const Frame e = r.render(u, Style{}, true, true);
  EXPECT_EQ(e.visibility[0], Visibility::Drawn);
  EXPECT_LT(e.near, 0.01);
  EXPECT_EQ(e.pixels[0], c.width * c.height);
  EXPECT_STREQ(toString(Visibility::BeyondFar), "beyond far plane");

  // A volume containing the camera fills the view in the mask and tints the colour layer.
  const std::vector<Vec3> room = {Vec3(0, 0, 0)}, ball = {Vec3(0, 0, 0)};
  const Volume w[] = {{ball, 0.3, VolumeStatus::Clear, "ball"}, {room, 5.0, VolumeStatus::Colliding, "room"}};
  const Frame g = r.render(w, Style{.legend = false}, true, true);
  EXPECT_EQ(g.visibility[1], Visibility::FillsView);
  EXPECT_EQ(g.pixels[1], c.width * c.height);
  EXPECT_EQ(cv::countNonZero(g.mask == 2), c.width * c.height);
  EXPECT_NEAR(g.bgra.at<cv::Vec4b>(0, 0)[3], 0.35 * 255, 2);
  EXPECT_GT(g.bgra.at<cv::Vec4b>(c.height / 2, c.width / 2)[3], g.bgra.at<cv::Vec4b>(0, 0)[3]);  // the ball shows through
}

// ---------------------------------------------------------------------------------------------
// Golden images: the demo arm through a 320x180 version of the sample camera.

Camera goldenCamera() {
  Camera c = loadCamera(kData + "/demo_camera.yaml");
  const double s = 1.0 / 4.0;
  c.width = 320;
  c.height = 180;
  c.camera_matrix(0, 0) *= s;
  c.camera_matrix(1, 1) *= s;
  c.camera_matrix(0, 2) = (c.camera_matrix(0, 2) + 0.5) * s - 0.5;
  c.camera_matrix(1, 2) = (c.camera_matrix(1, 2) + 0.5) * s - 0.5;
  return c;
}

class RenderGolden : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new Model(loadModel(kData + "/demo_arm.yaml"));
    renderer_ = new Renderer(goldenCamera());
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete model_;
  }
  Frame draw(const std::vector<double>& lower, const std::vector<double>& upper, const Style& style) {
    Checker checker(*model_);
    const QueryResult& q = checker.query(lower, upper, QueryOptions{.type = QueryType::Distances});
    EXPECT_EQ(q.status, Status::Ok);
    const std::vector<Volume> volumes = sceneVolumes(*model_, checker, bodyStatus(*model_, q));
    return renderer_->render(volumes, style);
  }
  static Model* model_;
  static Renderer* renderer_;
};
Model* RenderGolden::model_ = nullptr;
Renderer* RenderGolden::renderer_ = nullptr;

const kccd::test::GoldenTolerance kMaskTolerance{0, 0.0025, 4};

TEST_F(RenderGolden, DemoArmStatic) {
  const Frame f = draw({0.3, 0.4, 0.6}, {0.3, 0.4, 0.6}, Style{.labels = false, .legend = false});
  EXPECT_TRUE(kccd::test::compareGolden(f.bgra, "demo_static_rgba", renderer_->rendererString()));
  EXPECT_TRUE(kccd::test::compareGolden(f.mask, "demo_static_mask", renderer_->rendererString(), kMaskTolerance));
}

TEST_F(RenderGolden, DemoArmSwept) {
  const Frame f = draw({-0.5, 0.0, 0.0}, {0.5, 0.1, 0.2}, Style{.labels = true, .legend = true});
  EXPECT_TRUE(kccd::test::compareGolden(f.bgra, "demo_swept_rgba", renderer_->rendererString()));
  EXPECT_TRUE(kccd::test::compareGolden(f.mask, "demo_swept_mask", renderer_->rendererString(), kMaskTolerance));
}

// Static frames place each body's own (cached) mesh with its pose: the same pixels as meshes
// built from the checker's world volumes, and no mesh rebuilt when only the state changes.
TEST_F(RenderGolden, StaticFramesReuseBodyMeshes) {
  for (const std::vector<double>& q : {std::vector<double>{0.3, 0.4, 0.6}, std::vector<double>{-0.7, 0.2, 1.1}}) {
    Checker checker(*model_);
    const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    const std::vector<Volume> world = sceneVolumes(*model_, checker, bodyStatus(*model_, r));
    const std::vector<Volume> posed = staticSceneVolumes(*model_, checker, q, bodyStatus(*model_, r));
    const Frame a = renderer_->render(world, Style{}, false, true);
    const Frame b = renderer_->render(posed, Style{}, false, true);
    // The sphere polytopes are turned with the body, so only edge pixels may differ (both
    // meshes contain the true volume and lie at most tolerance_px outside it).
    EXPECT_LE(cv::countNonZero(a.mask != b.mask), 0.01 * cv::countNonZero(a.mask));
    EXPECT_GT(cv::countNonZero(a.mask), 1000);
  }
  // A small motion (same tessellation levels): posed meshes all come from the cache, world
  // meshes of the moving bodies are rebuilt.
  auto frame = [&](const std::vector<double>& q, bool posed) {
    Checker checker(*model_);
    const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    const std::vector<Volume> v = posed ? staticSceneVolumes(*model_, checker, q, bodyStatus(*model_, r))
                                        : sceneVolumes(*model_, checker, bodyStatus(*model_, r));
    return renderer_->render(v, Style{}, false, true);
  };
  frame({0.1, -0.3, 0.9}, true);
  const int b2 = frame({0.1001, -0.3001, 0.9001}, true).meshes_built;
  frame({0.1, -0.3, 0.9}, false);
  const int b4 = frame({0.1001, -0.3001, 0.9001}, false).meshes_built;
  EXPECT_EQ(b2, 0);
  EXPECT_GT(b4, 0);
}

TEST(RenderContext, ReportsItsRenderer) {
  const auto ctx = GlContext::make();
  EXPECT_FALSE(ctx->renderer().empty());
  std::cout << "renderer: " << ctx->renderer() << "\n";
}

}  // namespace
