// Ssch operations: each must contain exactly the volume it claims.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "kccd/distance.hpp"
#include "kccd/ssch.hpp"
#include "support/random_shapes.hpp"
#include "support/reference_distance.hpp"

namespace kccd {
namespace {

using testing::Points;

// Independent containment test: q is inside S(P, r) iff dist(q, conv P) <= r.
bool contains(const Ssch& s, const Vec3& q, double slack = 1e-12) {
  const Points pts(s.points().begin(), s.points().end());
  return static_cast<double>(testing::referencePointHullDistance(q, pts)) <= s.radius() + slack;
}

TEST(Ssch, RejectsInvalidConstruction) {
  EXPECT_THROW(Ssch({}, 0.1), std::invalid_argument);
  EXPECT_THROW(Ssch({Vec3(0, 0, 0)}, -0.1), std::invalid_argument);
  EXPECT_THROW(Ssch({Vec3(std::nan(""), 0, 0)}, 0.1), std::invalid_argument);
  EXPECT_THROW(Ssch({Vec3(0, 0, 0)}, std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_NO_THROW(Ssch({Vec3(0, 0, 0)}, 0.0));
}

TEST(Ssch, RigidTransformPreservesDistances) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 200; ++i) {
    const Ssch a(testing::randomCloud(rng, 8, Vec3::Zero(), 1.0), 0.05);
    const Ssch b(testing::randomCloud(rng, 5, Vec3(2, 0, 0), 1.0), 0.1);
    Pose pose = Pose::Identity();
    pose.linear() = testing::randomRotation(rng);
    pose.translation() = 3.0 * testing::randomUnit(rng);
    const double before = distance(a.view(), b.view()).distance;
    const double after = distance(a.transformed(pose).view(), b.transformed(pose).view()).distance;
    EXPECT_NEAR(before, after, 1e-12);
  }
}

TEST(Ssch, InflationAddsToTheRadius) {
  const Ssch a({Vec3(0, 0, 0), Vec3(1, 0, 0)}, 0.1);
  EXPECT_DOUBLE_EQ(a.inflated(0.25).radius(), 0.35);
  EXPECT_THROW(a.inflated(-0.1), std::invalid_argument);
}

TEST(Ssch, SweptAlongContainsEveryTranslate) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 50; ++i) {
    const Ssch a(testing::randomCloud(rng, 6, Vec3::Zero(), 1.0), 0.05);
    const Vec3 from = testing::randomUnit(rng), to = 2.0 * testing::randomUnit(rng);
    const Ssch swept = a.sweptAlong(from, to);
    EXPECT_EQ(swept.points().size(), 12u);
    for (int k = 0; k < 20; ++k) {
      const double t = u(rng);
      for (const Vec3& p : a.points()) EXPECT_TRUE(contains(swept, p + from + t * (to - from)));
    }
  }
  EXPECT_EQ(Ssch({Vec3::Zero()}, 0.0).sweptAlong(Vec3::UnitX(), Vec3::UnitX()).points().size(), 1u);
}

TEST(Ssch, PruningDropsInteriorPointsAndKeepsTheVolume) {
  Points cube;
  for (int i = 0; i < 8; ++i) cube.emplace_back((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
  Points with_inner = cube;
  with_inner.emplace_back(0, 0, 0);
  with_inner.emplace_back(0.5, -0.2, 0.9);
  with_inner.emplace_back(1, 0, 0);  // on a face
  with_inner.push_back(cube[3]);     // duplicate vertex
  const Ssch pruned = Ssch(with_inner, 0.1).pruned();
  EXPECT_EQ(pruned.points().size(), 8u);
  EXPECT_NEAR(pruned.radius(), 0.1, 1e-12);
  EXPECT_GE(pruned.radius(), 0.1);
  for (const Vec3& p : cube) EXPECT_TRUE(contains(pruned, p, 0.0));

  std::mt19937_64 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Points pts = testing::randomCloud(rng, 30, Vec3::Zero(), 1.0);
    const double tol = i % 2 == 0 ? 0.0 : 0.05;
    const Ssch s = Ssch(pts, 0.02).pruned(tol);
    EXPECT_LE(s.points().size(), pts.size());
    for (const Vec3& p : pts) ASSERT_TRUE(contains(s, p, 0.0)) << "case " << i;
  }
}

TEST(Ssch, BoundingSphereContainsTheVolume) {
  std::mt19937_64 rng(4);
  for (int i = 0; i < 200; ++i) {
    const Ssch s(testing::randomCloud(rng, 1 + i % 20, Vec3(1, 2, 3), 2.0), 0.3);
    const Sphere b = s.boundingSphere();
    for (const Vec3& p : s.points()) ASSERT_LE((p - b.center).norm() + s.radius(), b.radius);
  }
}

}  // namespace
}  // namespace kccd
