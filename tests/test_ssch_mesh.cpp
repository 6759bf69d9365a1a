// SSCH meshes contain the true volume (exactly and on sampled surface points), tessellation
// error, and the mesh cache.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/distance.hpp"
#include "kccd/render/mesh_cache.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "support/cameras.hpp"
#include "support/random_shapes.hpp"

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
      const double allowed =
          r * (spherePolytope(level).scale - 1.0) + 1e-5 * (1.0 + 2000.0) * spherePolytope(level).scale;
      for (const Vec3& v : m.vertices) {
        double nearest = 1e300;  // distance to the nearest core point bounds the distance to the hull
        for (const Vec3& p : sh.points) nearest = std::min(nearest, (v - p).norm());
        EXPECT_LE(nearest - r, allowed + 1e-9);
      }
    }
}

// ---------------------------------------------------------------------------------------------
// The direct construction: degenerate cores and random sets

// Checks one mesh of the SSCH (points, r) built at `level`: closed and consistently wound,
// convex, containing the true volume (every face plane clears the support of the SSCH in its
// normal; sampled points of the true boundary inside every face plane), and no vertex farther
// from conv(points) than the circumscribed radius allows.
void checkMesh(const Mesh& m, const std::vector<Vec3>& points, double radius, int level, std::mt19937_64& rng) {
  const double r = std::max(radius, kMinDrawRadius);
  double extent = 0.0;
  for (const Vec3& p : points) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  const double tiny = 1e-9 * (1.0 + extent);
  ASSERT_GE(m.triangles.size(), 4u);
  ASSERT_EQ(m.normals.size(), m.triangles.size());
  for (const auto& e : m.edges) ASSERT_NE(e[2], e[3]);
  ASSERT_EQ(
      static_cast<long>(m.vertices.size()) - static_cast<long>(m.edges.size()) + static_cast<long>(m.triangles.size()),
      2);
  ASSERT_EQ(m.edges.size() * 2, m.triangles.size() * 3);  // every edge has exactly two triangles
  std::vector<double> offsets(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3& n = m.normals[t];
    ASSERT_NEAR(n.norm(), 1.0, 1e-12);
    offsets[t] = n.dot(m.vertices[m.triangles[t][0]]);
    double support = -1e300;
    for (const Vec3& p : points) support = std::max(support, n.dot(p));
    ASSERT_LE(support + r, offsets[t] + tiny) << "face " << t;
    const auto& tri = m.triangles[t];
    const Vec3 area = (m.vertices[tri[1]] - m.vertices[tri[0]]).cross(m.vertices[tri[2]] - m.vertices[tri[0]]);
    ASSERT_GE(area.dot(n), -1e-12 * (1.0 + extent) * (1.0 + extent)) << "face " << t;
    // Planar: the other two vertices lie on the face plane too.
    for (int k = 1; k < 3; ++k) ASSERT_NEAR(n.dot(m.vertices[tri[k]]), offsets[t], tiny);
  }
  // Convex: every vertex under every face plane (a sample of the vertices for large meshes).
  for (std::size_t i = 0; i < m.vertices.size(); i += 1 + m.vertices.size() / 200)
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      ASSERT_LE(m.normals[t].dot(m.vertices[i]), offsets[t] + tiny) << "vertex " << i << " face " << t;
  // Points of the true boundary: the support point of the core in a random direction d plus r d,
  // and random points of the core hull (convex combinations) pushed out by r.
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    Vec3 x;
    if (k % 2 == 0) {
      std::size_t best = 0;
      for (std::size_t i = 1; i < points.size(); ++i)
        if (d.dot(points[i]) > d.dot(points[best])) best = i;
      x = points[best] + r * d;
    } else {
      Vec3 c = Vec3::Zero();
      double total = 0.0;
      for (const Vec3& p : points) {
        const double w = -std::log(1.0 - u(rng));
        c += w * p;
        total += w;
      }
      x = c / total + r * d;
    }
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      ASSERT_LE(m.normals[t].dot(x), offsets[t] + tiny) << "sample " << k;
  }
  // Not much larger: every vertex within the circumscribed radius of conv(points).
  const double allowed = r * spherePolytope(level).scale + 2e-6 * (1.0 + extent) * spherePolytope(level).scale;
  for (const Vec3& v : m.vertices) {
    const DistanceResult d = distance(SschView{points, 0.0}, SschView{std::span<const Vec3>(&v, 1), 0.0});
    ASSERT_LE(d.distance, allowed * (1.0 + 1e-9) + tiny);
  }
}

std::vector<Shape> degenerateShapes() {
  const Vec3 a(0.3, -0.2, 0.9), b(0.7, 0.4, 0.5), c(-0.1, 0.6, 1.2), d(0.2, 0.1, 0.4);
  const Vec3 n = (b - a).cross(c - a).normalized();
  std::vector<Shape> s = {
      {{a}, 0.1, "single point"},
      {{a, a, a}, 0.05, "one point three times"},
      {{a}, 0.0, "single point, radius 0"},
      {{Vec3(0, 0, 0), Vec3(0, 0, 0.4)}, 0.05, "axis-aligned capsule"},
      {{Vec3(0, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0.3, 0), Vec3(0, 0.3, 0)}, 0.04, "collinear with duplicates"},
      {{a, b, a + 0.25 * (b - a), a + 0.7 * (b - a)}, 0.02, "collinear, oblique"},
      {{a, b}, 0.0, "segment, radius 0"},
      {{Vec3(0, 0, 0), Vec3(0.4, 0, 0), Vec3(0.4, 0.2, 0), Vec3(0, 0.2, 0), Vec3(0.2, 0.1, 0)},
       0.03,
       "axis-aligned slab"},
      {{a, b, c, a + 0.3 * (b - a) + 0.3 * (c - a), b, c}, 0.02, "oblique triangle with duplicates"},
      {{a, b, c}, 0.0, "triangle, radius 0"},
      {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1), Vec3(1, 0, 1), Vec3(0, 1, 1),
        Vec3(1, 1, 0)},
       0.05,
       "axis-aligned cube"},
      {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1), Vec3(1, 0, 1), Vec3(0, 1, 1),
        Vec3(1, 1, 0)},
       0.0,
       "cube, radius 0"},
      {{a, b, c, d}, 0.0, "tetrahedron, radius 0"},
      {{a, b, c, d, 0.5 * (a + b), 0.5 * (c + d), 0.25 * (a + b + c + d)},
       0.08,
       "tetrahedron with edge and inner points"},
      {{Vec3(1000, 2000, -500), Vec3(1000.3, 2000, -500), Vec3(1000, 2000.2, -500.1), Vec3(1000.1, 2000.1, -499.8)},
       0.05,
       "far from the origin"},
  };
  for (const double thick : {1e-12, 1e-10, 1e-8, 1e-6, 1e-3}) {
    s.push_back(
        {{a, b, c, 0.3 * a + 0.3 * b + 0.4 * c + thick * n}, 0.02, "thin tetrahedron " + std::to_string(thick)});
    const Vec3 side = (b - a).cross(n).normalized();
    s.push_back({{a, b, a + 0.5 * (b - a) + thick * side}, 0.02, "thin triangle " + std::to_string(thick)});
    s.push_back({{a, a + Vec3(thick, 0, 0), a + Vec3(0, thick, 0), a + Vec3(0, 0, thick)},
                 0.02,
                 "tiny tetrahedron " + std::to_string(thick)});
  }
  return s;
}

TEST(RenderMesh, DegenerateCores) {
  std::mt19937_64 rng(5);
  for (const Shape& sh : degenerateShapes())
    for (int level = 0; level <= 4; ++level) {
      SCOPED_TRACE(sh.what + ", level " + std::to_string(level));
      const Mesh m = buildSschMesh(sh.points, sh.radius, level);
      EXPECT_TRUE(m.direct);
      checkMesh(m, sh.points, sh.radius, level, rng);
    }
  // A single point gives the sphere polytope itself, every vertex at the mesh radius.
  const Vec3 p(0.3, -0.2, 0.9);
  const Mesh ball = buildSschMesh(std::span<const Vec3>(&p, 1), 0.1, 2);
  EXPECT_EQ(ball.vertices.size(), spherePolytope(2).vertices.size());
  EXPECT_EQ(ball.triangles.size(), spherePolytope(2).triangles.size());
  EXPECT_EQ(ball.hull_input, 0);
  for (const Vec3& v : ball.vertices) EXPECT_NEAR((v - p).norm(), ball.mesh_radius, 1e-12);
  // A capsule: two sphere halves (vertices at the mesh radius from an end point) and a tube
  // (parallelograms joining the two halves, vertices within the mesh radius of the axis).
  const std::vector<Vec3> seg = {Vec3(0, 0, 0), Vec3(0, 0, 0.4)};
  const Mesh capsule = buildSschMesh(seg, 0.05, 3);
  EXPECT_EQ(capsule.hull_input, 0);
  for (const Vec3& v : capsule.vertices) {
    const double to_end = std::min(v.norm(), (v - seg[1]).norm());
    const double to_axis = Vec3(v.x(), v.y(), 0.0).norm();
    EXPECT_TRUE(std::abs(to_end - capsule.mesh_radius) < 1e-12 ||
                (to_axis <= capsule.mesh_radius + 1e-12 && to_axis >= 0.05 * 0.99));
  }
  // A flat square: both faces offset by at most the mesh radius, and no qhull at all.
  const std::vector<Vec3> square = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  const Mesh slab = buildSschMesh(square, 0.02, 2);
  EXPECT_EQ(slab.hull_input, 0);
  double top = -1.0, bottom = 1.0;
  for (const Vec3& v : slab.vertices) top = std::max(top, v.z()), bottom = std::min(bottom, v.z());
  EXPECT_LE(top, slab.mesh_radius + 1e-12);
  EXPECT_GE(top, 0.02);
  EXPECT_NEAR(top, -bottom, 1e-12);
}

// Random core sets, many of them degenerate on purpose: points on a random line or plane, on
// an integer grid (many coplanar and collinear subsets), clustered duplicates, thin noise
// around a plane, far from the origin; random radii including 0.
TEST(RenderMesh, RandomCoresFuzz) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  int fallbacks = 0, cases = 0;
  for (int c = 0; c < 400; ++c) {
    const int kind = c % 8;
    const int n = 1 + static_cast<int>(rng() % 40);
    const Vec3 o(u(rng), u(rng), u(rng));
    const Vec3 e1 = Vec3(g(rng), g(rng), g(rng)).normalized();
    const Vec3 e2 = e1.cross(Vec3(g(rng), g(rng), g(rng))).normalized();
    const Vec3 e3 = e1.cross(e2);
    std::vector<Vec3> pts;
    for (int k = 0; k < n; ++k) {
      switch (kind) {
        case 0:
          pts.push_back(o + 0.5 * Vec3(u(rng), u(rng), u(rng)));
          break;
        case 1:
          pts.push_back(o + 0.5 * u(rng) * e1);
          break;
        case 2:
          pts.push_back(o + 0.5 * u(rng) * e1 + 0.5 * u(rng) * e2);
          break;
        case 3:
          pts.push_back(0.1 * Vec3(static_cast<double>(rng() % 3), static_cast<double>(rng() % 3),
                                   static_cast<double>(rng() % 2)));
          break;
        case 4:
          pts.push_back(k % 3 == 0 || pts.empty() ? o + 0.3 * Vec3(u(rng), u(rng), u(rng)) : pts[rng() % pts.size()]);
          break;
        case 5:
          pts.push_back(o + 0.5 * u(rng) * e1 + 0.5 * u(rng) * e2 +
                        std::pow(10.0, -3.0 - 9.0 * std::abs(u(rng))) * u(rng) * e3);
          break;
        case 6:
          pts.push_back(Vec3(300, -200, 150) + 0.4 * Vec3(u(rng), u(rng), u(rng)));
          break;
        default:
          pts.push_back(o + 0.3 * u(rng) * Vec3(0, 0, 1) + (k % 2) * 0.2 * Vec3(1, 0, 0));
          break;  // axis-aligned
      }
    }
    const double radius = c % 5 == 0 ? 0.0 : 0.2 * std::abs(u(rng));
    const int level = static_cast<int>(rng() % 4);
    SCOPED_TRACE("case " + std::to_string(c) + " kind " + std::to_string(kind) + ", " + std::to_string(n) +
                 " points, level " + std::to_string(level));
    const Mesh m = buildSschMesh(pts, radius, level);
    ++cases;
    if (!m.direct) ++fallbacks;
    checkMesh(m, pts, radius, level, rng);
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(fallbacks, 0) << "of " << cases;
}

// The direct construction is the same volume as the previous hull construction (both are the
// Minkowski sum of the core hull and a sphere polytope of the same level, turned differently):
// their vertices lie at the same distance from the core hull, and their volumes agree closely.
TEST(RenderMesh, DirectAgreesWithHullConstruction) {
  auto volume = [](const Mesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
    return v;
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int c = 0; c < 20; ++c) {
    std::vector<Vec3> pts;
    for (int k = 0; k < 3 + c; ++k) pts.emplace_back(u(rng), u(rng), u(rng));
    const Mesh direct = buildSschMesh(pts, 0.1, 3);
    const Mesh hull = buildSschMesh(pts, 0.1, 3, kMinDrawRadius, SschMeshing::Hull);
    EXPECT_TRUE(direct.direct);
    EXPECT_FALSE(hull.direct);
    EXPECT_NEAR(volume(direct), volume(hull), 2e-3 * volume(hull));
    EXPECT_LE(direct.hull_input, static_cast<int>(pts.size()));
    EXPECT_GT(hull.hull_input, 10 * static_cast<int>(pts.size()));
  }
}

TEST(RenderMesh, TessellationErrorShrinksWithLevel) {
  EXPECT_GT(spherePolytope(1).scale, spherePolytope(2).scale);
  EXPECT_GT(spherePolytope(2).scale, spherePolytope(3).scale);
  EXPECT_LT(spherePolytope(3).scale - 1.0, 0.005);
  EXPECT_EQ(spherePolytope(2).vertices.size(), 162u);
}

// Every level's neighbour table, checked by brute force: the triangle across edge k of t holds that
// edge reversed, is another triangle, and the relation is mutual; out-of-range levels clamp.
TEST(RenderMesh, SpherePolytopeNeighboursHoldTheSharedEdgeAtEveryLevel) {
  for (int level = 0; level <= 5; ++level) {
    const SpherePolytope& s = spherePolytope(level);
    ASSERT_EQ(s.vertices.size(), static_cast<std::size_t>(10 * (1 << (2 * level)) + 2)) << level;
    ASSERT_EQ(s.triangles.size(), static_cast<std::size_t>(20 * (1 << (2 * level)))) << level;
    ASSERT_EQ(s.neighbours.size(), s.triangles.size()) << level;
    int wrong = 0;
    for (std::size_t t = 0; t < s.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t u = s.triangles[t][k], w = s.triangles[t][(k + 1) % 3], n = s.neighbours[t][k];
        const auto& other = s.triangles.at(n);
        bool reversed = false, back = false;
        for (int j = 0; j < 3; ++j) {
          reversed |= other[j] == w && other[(j + 1) % 3] == u;
          back |= other[j] == w && other[(j + 1) % 3] == u && s.neighbours[n][j] == t;
        }
        wrong += n == t || !reversed || !back;
      }
    EXPECT_EQ(wrong, 0) << "level " << level;
  }
  EXPECT_EQ(&spherePolytope(-3), &spherePolytope(0));
  EXPECT_EQ(&spherePolytope(9), &spherePolytope(5));
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

// The construction is a setting of each cache: two caches side by side build the same shapes
// their own way (the qhull construction never gives a direct mesh).
TEST(RenderMesh, CacheBuildsWithItsOwnConstruction) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(0.3, 0, 0), Vec3(0, 0.2, 0), Vec3(0.1, 0.1, 0.25)};
  MeshCache direct;
  MeshCache hull(MeshCache::kDefaultCapacity, SschMeshing::Hull);
  EXPECT_EQ(direct.meshing(), SschMeshing::Direct);
  EXPECT_EQ(hull.meshing(), SschMeshing::Hull);
  const auto a = direct.get(pts, 0.05, 3);
  const auto b = hull.get(pts, 0.05, 3);
  const MeshRequest request{pts, 0.05, 3};
  const auto c = hull.getAll(std::span<const MeshRequest>(&request, 1));
  EXPECT_TRUE(a->direct);
  EXPECT_FALSE(b->direct);
  EXPECT_EQ(c[0].mesh.get(), b.get());  // cached by shape
  const Mesh expected = buildSschMesh(pts, 0.05, 3, kMinDrawRadius, SschMeshing::Hull);
  EXPECT_EQ(b->vertices, expected.vertices);
  EXPECT_EQ(b->triangles, expected.triangles);
  EXPECT_EQ(buildSschMesh(pts, 0.05, 3).vertices, a->vertices);
}

TEST(RenderMesh, CacheBuildsBatchesInParallelLikeOneByOne) {
  std::mt19937_64 rng(5);
  const std::vector<Shape> shapes = testShapes(rng);
  std::vector<MeshRequest> requests;
  for (const Shape& s : shapes) requests.push_back(MeshRequest{s.points, s.radius, 2});
  requests.push_back(requests[3]);  // a repeated request is built once and shared
  MeshCache batch;
  batch.nextFrame();
  const std::vector<MeshCache::Found> found = batch.getAll(requests);
  ASSERT_EQ(found.size(), requests.size());
  EXPECT_EQ(batch.built(), shapes.size());
  EXPECT_EQ(found.back().mesh.get(), found[3].mesh.get());
  EXPECT_FALSE(found.back().built);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    SCOPED_TRACE(shapes[i].what);
    ASSERT_TRUE(found[i].mesh);
    EXPECT_TRUE(found[i].built);
    const Mesh one = buildSschMesh(shapes[i].points, shapes[i].radius, 2);
    EXPECT_EQ(found[i].mesh->vertices, one.vertices);
    EXPECT_EQ(found[i].mesh->triangles, one.triangles);
  }
  // The next frame takes every one from the cache, and get() sees them too.
  batch.nextFrame();
  const std::vector<MeshCache::Found> again = batch.getAll(requests);
  for (std::size_t i = 0; i < requests.size(); ++i) {
    EXPECT_EQ(again[i].mesh.get(), found[i].mesh.get());
    EXPECT_FALSE(again[i].built);
  }
  EXPECT_EQ(batch.get(shapes[0].points, shapes[0].radius, 2).get(), found[0].mesh.get());
  EXPECT_EQ(batch.built(), shapes.size());
}

// The tint drawn as each volume's silhouette polygon covers exactly the pixels its front
// triangles cover: random scenes of overlapping volumes, near and far, partly outside the view
// and reaching behind the near plane, through distorting and plain cameras, bit for bit.
TEST(RenderMesh, PolygonFillCoversTheSamePixelsAsTheTriangles) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int polygons = 0, volumes = 0;
  for (int trial = 0; trial < 16; ++trial) {
    Camera c = kccd::testing::randomCamera(rng, trial % 2 == 0, 480, 320);
    const Vec3 eye(kccd::testing::cameraCentre(c)[0], kccd::testing::cameraCentre(c)[1],
                   kccd::testing::cameraCentre(c)[2]);
    std::vector<std::vector<Vec3>> cores;
    std::vector<Volume> scene;
    const int n = 2 + trial % 6;
    for (int i = 0; i < n; ++i) {
      // Around the origin (what the random cameras look at); every fourth trial one volume
      // right in front of the camera, partly behind its near plane.
      const Vec3 centre =
          (trial % 4 == 3 && i == 0) ? Vec3(eye * 0.97) : Vec3(0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng));
      cores.push_back(
          kccd::testing::randomCloud(rng, 1 + static_cast<int>(rng() % 12), centre, 0.1 + 0.4 * std::abs(u(rng))));
    }
    for (int i = 0; i < n; ++i) {
      const SafetyStatus status = static_cast<SafetyStatus>(i % 3);
      scene.push_back(Volume{cores[static_cast<std::size_t>(i)], 0.02 + 0.2 * std::abs(u(rng)), status, ""});
    }
    RenderOptions triangles, silhouettes;
    triangles.polygon_fill = false;
    silhouettes.outline_from_core = false;  // the mesh's silhouette (outlines from the core: test_ssch_outline)
    Renderer with_polygons(c, silhouettes), with_triangles(c, triangles);
    const Frame a = with_polygons.render(scene, Style{}, true, false);
    const Frame b = with_triangles.render(scene, Style{}, true, false);
    cv::Mat diff;
    cv::absdiff(a.bgra, b.bgra, diff);
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0);
    EXPECT_GT(cv::countNonZero(a.bgra.reshape(1)), 0);
    polygons += a.polygon_fills;
    volumes += n;
  }
  // Most volumes were drawn as polygons (the rest, behind the near plane or degenerate views,
  // as triangles).
  EXPECT_GT(polygons, volumes * 3 / 4);
  std::cout << polygons << " of " << volumes << " volumes filled as silhouette polygons\n";
}

}  // namespace
