// The numerical extremes of docs/algorithms.md section 11 for the distance routine.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "kccd/distance.hpp"
#include "support/random_shapes.hpp"
#include "support/reference_distance.hpp"

namespace kccd {
namespace {

using testing::Points;
constexpr double kEps = std::numeric_limits<double>::epsilon();

enum class Family { Coincident, Collinear, Coplanar, SinglePoint, Duplicated, General };

// A degenerate point set of the given family, size ~scale, around centre.
Points degenerateSet(std::mt19937_64& rng, Family f, const Vec3& centre, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> count(2, 24);
  const int n = count(rng);
  const Vec3 e1 = testing::randomUnit(rng);
  const Vec3 e2 = e1.unitOrthogonal();
  Points pts;
  switch (f) {
    case Family::Coincident:
      pts.assign(n, centre);
      break;
    case Family::SinglePoint:
      pts.push_back(centre);
      break;
    case Family::Collinear:
      for (int i = 0; i < n; ++i) pts.push_back(centre + scale * u(rng) * e1);
      break;
    case Family::Coplanar:
      for (int i = 0; i < n; ++i) pts.push_back(centre + scale * (u(rng) * e1 + u(rng) * e2));
      break;
    case Family::Duplicated: {
      const Points base = testing::randomCloud(rng, 4, centre, scale);
      for (int i = 0; i < n; ++i) pts.push_back(base[i % 4]);
      break;
    }
    case Family::General:
      pts = testing::randomCloud(rng, n, centre, scale);
      break;
  }
  return pts;
}

double maxCoord(const Points& a, const Points& b) {
  double m = 0.0;
  for (const auto& p : a) m = std::max(m, p.cwiseAbs().maxCoeff());
  for (const auto& p : b) m = std::max(m, p.cwiseAbs().maxCoeff());
  return m;
}

TEST(GjkExtremes, DegenerateSetsAtEveryScale) {
  std::mt19937_64 rng(314159);
  const Family families[] = {Family::Coincident,  Family::Collinear,  Family::Coplanar,
                             Family::SinglePoint, Family::Duplicated, Family::General};
  const double scales[] = {1e-6, 1e-3, 1.0, 1e2, 1e4};
  const double offsets[] = {0.0, 1.0, 1e4};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cases = 0;
  for (Family fa : families) {
    for (Family fb : families) {
      for (double scale : scales) {
        for (double offset : offsets) {
          for (int rep = 0; rep < 4; ++rep) {
            const Vec3 base = offset * testing::randomUnit(rng);
            const Vec3 dir = testing::randomUnit(rng);
            const double gap = (rep == 0 ? 0.0 : rep == 1 ? 1e-3 : 1.0) * scale;
            const Points a = degenerateSet(rng, fa, base, scale);
            const Points b = degenerateSet(rng, fb, base + dir * (2.0 * scale + gap), scale);
            const double ra = rep == 3 ? 0.0 : 0.1 * scale * u(rng);
            const double rb = rep == 2 ? 0.0 : 0.1 * scale * u(rng);
            const double ref = static_cast<double>(testing::referenceSschDistance(a, ra, b, rb));
            const DistanceResult r = distance({a, ra}, {b, rb});
            const double slack = 1e-9 * ref + 256.0 * kEps * maxCoord(a, b);
            ASSERT_TRUE(std::isfinite(r.distance));
            ASSERT_TRUE(r.witness_a.allFinite() && r.witness_b.allFinite() && r.direction.allFinite());
            ASSERT_LE(r.iterations, GjkOptions{}.max_iterations);
            ASSERT_LE(r.distance, ref + slack)
                << int(fa) << " " << int(fb) << " scale " << scale << " offset " << offset;
            ASSERT_NEAR(r.distance, ref, slack)
                << int(fa) << " " << int(fb) << " scale " << scale << " offset " << offset;
            ++cases;
          }
        }
      }
    }
  }
  EXPECT_EQ(cases, 6 * 6 * 5 * 3 * 4);
}

TEST(GjkExtremes, TouchingVolumesReportZero) {
  // Two unit spheres exactly touching, two boxes sharing a face, a point on a face.
  EXPECT_EQ(distance({Points{{0, 0, 0}}, 1.0}, {Points{{2, 0, 0}}, 1.0}).distance, 0.0);
  Points box_a, box_b;
  for (int i = 0; i < 8; ++i) {
    const Vec3 c((i & 1) ? 1 : 0, (i & 2) ? 1 : 0, (i & 4) ? 1 : 0);
    box_a.push_back(c);
    box_b.push_back(c + Vec3(1, 0.3, 0.2));
  }
  const DistanceResult faces = distance({box_a, 0.0}, {box_b, 0.0});
  EXPECT_EQ(faces.distance, 0.0);
  EXPECT_LE(faces.hull_upper, 1e-12);
  EXPECT_EQ(distance({Points{{0.5, 0.5, 1.0}}, 0.0}, {box_a, 0.0}).distance, 0.0);
}

TEST(GjkExtremes, DeepOverlapIsZeroWithOverlapStatus) {
  std::mt19937_64 rng(3);
  const Points outer = testing::randomCloud(rng, 40, Vec3::Zero(), 1.0);
  const Points inner{Vec3(0.001, 0.002, -0.001), Vec3(-0.002, 0.0, 0.001)};
  const DistanceResult r = distance({outer, 0.0}, {inner, 0.0});
  EXPECT_EQ(r.distance, 0.0);
  EXPECT_EQ(r.status, GjkStatus::Overlap);
  EXPECT_EQ(distance({outer, 0.5}, {outer, 0.5}).distance, 0.0);
}

TEST(GjkExtremes, ZeroAndHugeRadii) {
  const Points a{{0, 0, 0}, {1, 0, 0}};
  const Points b{{0, 5, 0}, {1, 5, 0}};
  EXPECT_NEAR(distance({a, 0.0}, {b, 0.0}).distance, 5.0, 1e-12);
  EXPECT_EQ(distance({a, 1e6}, {b, 0.0}).distance, 0.0);
  EXPECT_NEAR(distance({a, 1.0}, {b, 1.5}).distance, 2.5, 1e-12);
  const Points far{{0, 3e6, 0}};
  EXPECT_NEAR(distance({a, 1e6}, {far, 1e6}).distance, 1e6, 1e-6);
}

TEST(GjkExtremes, InvalidInputIsReportedAsUnsafe) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Points good{{0, 0, 0}};
  const Points far{{10, 0, 0}};
  const Points with_nan{{10, 0, 0}, {nan, 0, 0}};
  const Points with_inf{{10, 0, 0}, {0, inf, 0}};
  const Points empty;
  for (const auto& [pts, r] : {std::pair{with_nan, 0.0}, std::pair{with_inf, 0.0}, std::pair{empty, 0.0},
                               std::pair{far, -1.0}, std::pair{far, nan}, std::pair{far, inf}}) {
    const DistanceResult d = distance({good, 0.1}, {pts, r});
    EXPECT_EQ(d.status, GjkStatus::InvalidInput);
    EXPECT_EQ(d.distance, 0.0);
    EXPECT_TRUE(d.witness_a.allFinite() && d.direction.allFinite());
  }
  const Vec3 nan_dir(nan, 0, 0);
  GjkOptions opt;
  opt.warm_start = &nan_dir;
  EXPECT_NEAR(distance({good, 0.0}, {far, 0.0}, opt).distance, 10.0, 1e-12);
  opt.max_iterations = 0;
  EXPECT_EQ(distance({good, 0.0}, {far, 0.0}, opt).distance, 0.0);  // no iteration, no proof
}

TEST(GjkExtremes, KnownAnalyticDistances) {
  // Segment to segment (skew lines), point to triangle interior, triangle to triangle edges.
  EXPECT_NEAR(distance({Points{{-1, 0, 0}, {1, 0, 0}}, 0.0}, {Points{{0, -1, 2}, {0, 1, 2}}, 0.0}).distance, 2.0,
              1e-13);
  EXPECT_NEAR(distance({Points{{0.2, 0.2, 0.7}}, 0.0}, {Points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 0.0}).distance, 0.7,
              1e-13);
  const DistanceResult r =
      distance({Points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, 0.25}, {Points{{2, 2, 0}, {3, 2, 0}, {2, 3, 0}}, 0.25});
  EXPECT_NEAR(r.distance, std::sqrt(2.0) * 1.5 - 0.5, 1e-13);
  EXPECT_NEAR(r.witness_a.x(), r.witness_a.y(), 1e-12);
}

}  // namespace
}  // namespace kccd
