// SSCH meshes contain the true volume (exactly and on sampled surface points), tessellation
// error, and the mesh cache.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/ssch_mesh.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using namespace kccd::calib;

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

}  // namespace
