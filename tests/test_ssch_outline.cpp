// Outlines computed from the core (sschOutline) against independent oracles: the exact rim
// circles of the spheres for containment and tightness, and the CPU silhouette for the colour
// layer drawn from them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <tuple>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "kccd/render/renderer.hpp"
#include "kccd/render/ssch_outline.hpp"
#include "support/cameras.hpp"
#include "support/random_shapes.hpp"
#include "support/sanitized.hpp"
#include "support/silhouette.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using Vec2 = Eigen::Vector2d;

// The rim of a sphere seen from the origin, sampled: the circle where the viewing cone touches it
// (centre c (1 - r^2 / |c|^2), radius r sqrt(|c|^2 - r^2) / |c|, in the plane normal to c),
// divided by depth. Exact boundary points of the sphere's image.
void rimPoints(const Vec3& c, double r, int n, std::vector<Vec2>& out) {
  const double l2 = c.squaredNorm(), l = std::sqrt(l2);
  const Vec3 a = c / l;
  const Vec3 centre = c * (1.0 - r * r / l2);
  const double rho = r * std::sqrt(l2 - r * r) / l;
  const Vec3 e1 = (std::abs(a.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(a).normalized();
  const Vec3 e2 = a.cross(e1);
  for (int k = 0; k < n; ++k) {
    const double t = 2.0 * M_PI * k / n;
    const Vec3 p = centre + rho * (std::cos(t) * e1 + std::sin(t) * e2);
    out.emplace_back(p.x() / p.z(), p.y() / p.z());
  }
}

double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Andrew's monotone chain, counter-clockwise (x right, y up).
std::vector<Vec2> hull2d(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Vec2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k > 1 ? k - 1 : k);
  return h;
}

// Distance from x to a convex polygon given counter-clockwise (0 inside).
double polygonDistance(const Vec2& x, const std::vector<Vec2>& poly) {
  if (poly.size() == 1) return (x - poly[0]).norm();
  bool inside = poly.size() >= 3;
  double best = 1e300;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    if (cross(a, b, x) < 0) inside = false;
    const Vec2 ab = b - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (x - (a + t * ab)).norm());
  }
  return inside ? 0.0 : best;
}

struct Case {
  std::vector<Vec3> points;
  double radius;
  std::string what;
};

// Shapes in front of a camera at the origin looking along +z: ordinary, degenerate (points,
// segments, flat and collinear sets, duplicates), far off the optical axis, tiny and huge, near
// the camera and very far from it.
std::vector<Case> cases(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Case> s;
  const Vec3 a(0.3, -0.2, 2.9), b(0.7, 0.4, 2.5), c(-0.1, 0.6, 3.2);
  s.push_back({{a}, 0.1, "one point"});
  s.push_back({{a}, 1e-9, "one point, radius 1e-9"});
  s.push_back({{a, b}, 0.05, "segment"});
  s.push_back({{a, b}, 0.0, "segment, radius 0"});
  s.push_back({{a, a, b, b, 0.5 * (a + b)}, 0.03, "collinear with duplicates"});
  s.push_back({{a, b, c}, 0.02, "triangle"});
  s.push_back({{Vec3(0, 0, 3), Vec3(0, 0, 5)}, 0.2, "along the optical axis"});
  s.push_back({{Vec3(0, 0, 3), Vec3(0, 0, 3) + Vec3(1e-12, 0, 0)}, 0.3, "two points 1e-12 apart"});
  s.push_back({{Vec3(4, 3, 1.2), Vec3(5, 2.5, 1.0)}, 0.3, "far off the axis, grazing"});
  s.push_back({{Vec3(-30, 20, 2), Vec3(-29, 21, 2.5)}, 0.5, "very far off the axis"});
  s.push_back({{Vec3(0.01, 0.02, 0.3), Vec3(-0.05, 0.0, 0.4)}, 0.2, "near the camera"});
  s.push_back({{Vec3(100, -50, 1e5), Vec3(130, -40, 1.0001e5)}, 10.0, "far away"});
  s.push_back({{Vec3(0, 0, 1e4), Vec3(1e3, 0, 1e4)}, 3e3, "huge"});
  s.push_back({{Vec3(0.2, 0.1, 1.0)}, 0.949, "radius nearly its depth"});
  s.push_back({{Vec3(0.2, 0.1, 1.0)}, 0.99, "reaching nearer than min_depth"});
  s.push_back({{Vec3(0.2, 0.1, 1.0), Vec3(3, 2, 40)}, 0.9, "near and far"});
  for (int i = 0; i < 40; ++i) {
    const Vec3 centre(3.0 * u(rng), 2.0 * u(rng), 1.5 + 4.0 * std::abs(u(rng)));
    Case k;
    k.points = kccd::testing::randomCloud(rng, 1 + static_cast<int>(rng() % 40), centre, 0.05 + 0.8 * std::abs(u(rng)));
    k.radius = i % 5 == 0 ? 0.0 : 0.4 * std::abs(u(rng));
    k.what = "random " + std::to_string(k.points.size()) + " points";
    s.push_back(k);
  }
  return s;
}

TEST(RenderOutline, ContainsTheImageAndIsWithinTolerance) {
  std::mt19937_64 rng(5);
  int drawn = 0, refused = 0;
  double worst = 0.0;
  std::size_t most = 0;
  // Under the sanitizers without the longest focal length (the finest outlines and oracle rims:
  // the same code with more corners).
  const std::vector<double> focals =
      kccd::testing::kSanitized ? std::vector<double>{300.0, 1000.0} : std::vector<double>{300.0, 1000.0, 4000.0};
  for (const double focal : focals)
    for (const Case& k : cases(rng)) {
      SCOPED_TRACE(k.what + ", focal " + std::to_string(focal));
      const OutlineOptions options{.focal_px = focal, .tolerance_px = 0.5, .min_depth = 0.05};
      std::vector<Vec2> poly;
      const bool ok = sschOutline(k.points, k.radius, options, poly);
      double zmin = 1e300;
      for (const Vec3& p : k.points) zmin = std::min(zmin, p.z() - k.radius);
      if (zmin < options.min_depth) {  // reaches nearer than min_depth: refused
        EXPECT_FALSE(ok);
        ++refused;
        continue;
      }
      ASSERT_TRUE(ok);
      ASSERT_GE(poly.size(), k.radius > 0.0 ? 3u : 1u);
      ++drawn;
      most = std::max(most, poly.size());
      // Convex and counter-clockwise (as the support directions turn).
      for (std::size_t i = 0; i < poly.size(); ++i)
        ASSERT_GE(cross(poly[i], poly[(i + 1) % poly.size()], poly[(i + 2) % poly.size()]), -1e-12) << "corner " << i;
      // Containment: every rim point of every sphere (exact image boundary points), and so the
      // hull of them, lies inside.
      std::vector<Vec2> rim;
      for (const Vec3& p : k.points) {
        // Fine enough that the chords between neighbouring rim points stay within 1e-3 px of the
        // rim: from the image's size (its farthest rim point from the centre's image).
        std::vector<Vec2> coarse;
        rimPoints(p, k.radius, 64, coarse);
        const Vec2 mid(p.x() / p.z(), p.y() / p.z());
        double size = 0.0;
        for (const Vec2& x : coarse) size = std::max(size, (x - mid).norm() * focal);
        rimPoints(p, k.radius, std::max(64, static_cast<int>(std::ceil(4.0 * M_PI * std::sqrt(size / 2e-3)))), rim);
      }
      double scale = 0.0;
      for (const Vec2& v : poly) scale = std::max(scale, v.norm());
      for (const Vec2& x : rim) {
        // Signed distance inside every edge line; a polygon of one or two corners (radius 0):
        // distance to it.
        double inside = poly.size() < 3 ? -polygonDistance(x, poly) : 1e300;
        for (std::size_t i = 0; i < poly.size() && poly.size() >= 3; ++i) {
          const Vec2& a = poly[i];
          const Vec2& b = poly[(i + 1) % poly.size()];
          inside = std::min(inside, cross(a, b, x) / (b - a).norm());
        }
        ASSERT_GE(inside * focal, -1e-9 * (1.0 + scale * focal)) << "rim point outside the outline";
      }
      // Tightness: every corner within the tolerance of the hull of the rim points (which lies
      // inside the true image by less than a thousandth of a pixel here).
      const std::vector<Vec2> truth = hull2d(rim);
      for (const Vec2& v : poly) {
        const double d = polygonDistance(v, truth) * focal;
        worst = std::max(worst, d);
        ASSERT_LE(d, 0.5 + 2e-3 + 1e-9 * scale * focal) << "corner too far outside";
      }
    }
  EXPECT_GT(drawn, 40 * static_cast<int>(focals.size()));
  EXPECT_GT(refused, 0);
  std::cout << drawn << " outlines, " << refused << " refused (nearer than min_depth); farthest corner " << worst
            << " px outside the image (tolerance 0.5); at most " << most << " corners\n";
}

TEST(RenderOutline, RefusesWhatItCannotDraw) {
  std::vector<Vec2> poly;
  const OutlineOptions o{.focal_px = 1000, .tolerance_px = 0.5, .min_depth = 0.05};
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{}, 0.1, o, poly));
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, 0, -1)}, 0.1, o, poly));    // behind
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, 0, 0.1)}, 0.08, o, poly));  // nearer than min_depth
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, 0, 1)}, 2.0, o, poly));     // contains the camera
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, NAN, 1)}, 0.1, o, poly));   // not finite
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, 0, 1)}, INFINITY, o, poly));
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(1e300, 0, 1)}, 0.1, o, poly));  // overflows
  EXPECT_TRUE(poly.empty());
  // Too fine for the vertex limit.
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(0, 0, 1)}, 0.5,
                           OutlineOptions{.focal_px = 1e9, .tolerance_px = 0.5, .max_vertices = 64}, poly));
  EXPECT_TRUE(sschOutline(std::vector<Vec3>{Vec3(0, 0, 1)}, 0.5, o, poly));
  // Angles that stop splitting before a corner comes within tolerance (a sphere 1e-9 in front
  // of the camera's plane): refused, not an endless refinement.
  EXPECT_FALSE(sschOutline(std::vector<Vec3>{Vec3(1, 0, 0.5)}, 0.5 - 1e-9,
                           OutlineOptions{.focal_px = 1000, .tolerance_px = 0.5, .min_depth = 0.0}, poly));
}

// Huge and tiny magnitudes in one core: every sphere counts (nothing lost to overflow or
// underflow), the outline holds each centre's image and stays near it.
TEST(RenderOutline, MixedMagnitudesKeepEverySphere) {
  const OutlineOptions o{.focal_px = 1000, .tolerance_px = 0.5, .min_depth = 0.0};
  std::vector<Vec2> poly;
  for (const auto& [points, radius, far_image] :
       {std::tuple{std::vector<Vec3>{Vec3(0, 0, 2), Vec3(1e200, 0, 1e200)}, 1.0, Vec2(1, 0)},
        std::tuple{std::vector<Vec3>{Vec3(0, 0, 1), Vec3(1e-170, 0, 1e-170)}, 0.0, Vec2(1, 0)},
        std::tuple{std::vector<Vec3>{Vec3(0, 0, 1e-160), Vec3(0, 5e-161, 1e-160)}, 0.0, Vec2(0, 0.5)},
        std::tuple{std::vector<Vec3>{Vec3(0, 0, 3e150), Vec3(-3e150, 3e150, 3e150)}, 1e149, Vec2(-1, 1)}}) {
    ASSERT_TRUE(sschOutline(points, radius, o, poly));
    for (const Vec2& image : {Vec2(points[0].x() / points[0].z(), points[0].y() / points[0].z()), far_image}) {
      bool inside = true;
      for (std::size_t i = 0; i < poly.size() && poly.size() >= 3; ++i)
        inside = inside && cross(poly[i], poly[(i + 1) % poly.size()], image) >= -1e-12;
      EXPECT_TRUE(inside || polygonDistance(image, poly) < 1e-12) << image.transpose();
    }
    double reach = 0.0;
    for (const Vec2& v : poly) reach = std::max(reach, v.norm());
    EXPECT_LT(reach, 1.5 * std::max(1.0, far_image.norm()) + 0.5);
  }
}

// The colour layer drawn from outlines covers the independent CPU silhouette (to one pixel of
// boundary) and not more than the outline's width beyond it, through distorting and plain
// cameras, without building a mesh; a volume reaching nearer than the near plane is drawn from
// its mesh instead.
TEST(RenderOutline, ColourLayerMatchesTheCpuSilhouette) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_iou = 1.0;
  int outlines = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const Camera c = kccd::testing::randomCamera(rng, trial % 4 != 3);
    const std::vector<Vec3> pts =
        kccd::testing::randomCloud(rng, 1 + static_cast<int>(rng() % 5), Vec3(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)),
                                   0.1 + 0.3 * std::abs(u(rng)));
    const double radius = 0.05 + 0.15 * std::abs(u(rng));
    const cv::Mat cpu = kccd::testing::cpuSilhouette(c, pts, radius) > 0;
    Renderer r(c);
    const Volume v{pts, radius, SafetyStatus::Clear, ""};
    const Frame f = r.render(std::span<const Volume>(&v, 1), Style{.legend = false}, true, false);
    EXPECT_EQ(f.meshes_built, 0);
    outlines += f.outlines;
    cv::Mat alpha;
    cv::extractChannel(f.bgra, alpha, 3);
    const cv::Mat gl = alpha > 0;
    cv::Mat gl_grown, cpu_grown, cpu_far;
    cv::dilate(gl, gl_grown, cv::Mat::ones(3, 3, CV_8U));
    cv::dilate(cpu, cpu_grown, cv::Mat::ones(3, 3, CV_8U));
    // The smoothed outline (2 px wide, centred on the edge) and the warp's bilinear fringe.
    cv::dilate(cpu, cpu_far, cv::Mat::ones(7, 7, CV_8U));
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_GT(cv::countNonZero(cpu), 200);
    EXPECT_EQ(cv::countNonZero(cpu & ~gl_grown), 0) << "silhouette pixels not covered";
    EXPECT_EQ(cv::countNonZero(gl & ~cpu_far), 0) << "layer pixels beyond the silhouette";
    const double iou = static_cast<double>(cv::countNonZero(gl & cpu_grown)) / cv::countNonZero(gl | cpu);
    worst_iou = std::min(worst_iou, iou);
  }
  EXPECT_EQ(outlines, 10);
  // Through the near plane: the mesh (its triangles, clipped), as before.
  const Camera c = kccd::testing::lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), 160, 120, 150, {-0.1, 0.01, 0, 0, 0});
  const std::vector<Vec3> close = {Vec3(1.97, 0.05, 0), Vec3(1.5, 0.1, 0)};  // 3 cm in front of the camera
  Renderer r(c);
  const Volume v{close, 0.02, SafetyStatus::Clear, ""};
  const Frame f = r.render(std::span<const Volume>(&v, 1), Style{.legend = false}, true, false);
  EXPECT_EQ(f.outlines, 0);
  EXPECT_EQ(f.meshes_built, 1);
  EXPECT_EQ(f.visibility[0], Visibility::Drawn);
  cv::Mat alpha;
  cv::extractChannel(f.bgra, alpha, 3);
  EXPECT_GT(cv::countNonZero(alpha), 1000);
  std::cout << outlines << " volumes drawn from outlines; worst IoU against the CPU silhouette " << worst_iou << "\n";
}

}  // namespace
