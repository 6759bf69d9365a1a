// GJK distance against the independent Wolfe oracle and against libccd, on random pairs.
#include <gtest/gtest.h>

#include <random>

#include "kccd/distance.hpp"
#include "support/random_shapes.hpp"
#include "support/reference_distance.hpp"

namespace kccd {
namespace {

using testing::Points;

struct Pair {
  Points a, b;
  double ra = 0.0, rb = 0.0;
  double scale = 1.0;
};

// Separated, near-touching and overlapping pairs with 1..64 points each.
Pair randomPair(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> count(1, 64);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Pair p;
  p.scale = std::pow(10.0, -2.0 + 3.0 * u(rng));  // 1 cm .. 10 m objects
  const Vec3 dir = testing::randomUnit(rng);
  const double gap = (u(rng) < 0.2 ? 1e-3 * u(rng) : 2.5 * u(rng)) * p.scale;
  p.a = testing::randomCloud(rng, count(rng), Vec3::Zero(), p.scale);
  p.b = testing::randomCloud(rng, count(rng), dir * (gap + 0.5 * p.scale), p.scale);
  p.ra = u(rng) < 0.3 ? 0.0 : 0.2 * p.scale * u(rng);
  p.rb = u(rng) < 0.3 ? 0.0 : 0.2 * p.scale * u(rng);
  return p;
}

double tolerance(double reference, double scale) { return 1e-9 * reference + 1e-12 * scale; }

TEST(Gjk, AgreesWithIndependentOracleOnRandomPairs) {
  std::mt19937_64 rng(20261121);
  int separated = 0, overlapping = 0;
  for (int i = 0; i < 3000; ++i) {
    const Pair p = randomPair(rng);
    const auto ref_hull = static_cast<double>(testing::referenceHullDistance(p.a, p.b));
    const double ref = std::max(0.0, ref_hull - p.ra - p.rb);
    const DistanceResult r = distance({p.a, p.ra}, {p.b, p.rb});
    ASSERT_NE(r.status, GjkStatus::InvalidInput);
    ASSERT_NEAR(r.distance, ref, tolerance(ref, p.scale)) << "pair " << i << " status " << int(r.status);
    // Conservative: never above the true distance (beyond the oracle's own rounding).
    ASSERT_LE(r.distance, ref + 1e-13 * p.scale) << "pair " << i;
    ASSERT_LE(r.hull_lower, ref_hull + 1e-13 * p.scale);
    ASSERT_GE(r.hull_upper, ref_hull - 1e-13 * p.scale);
    ASSERT_LE(r.iterations, GjkOptions{}.max_iterations);
    if (ref > 0.0) {
      ++separated;
      // Witness points lie on the two surfaces, at the reported distance.
      EXPECT_NEAR((r.witness_a - r.witness_b).norm(), ref, 1e-8 * p.scale);
      EXPECT_NEAR(static_cast<double>(testing::referencePointHullDistance(r.witness_a, p.a)), p.ra, 1e-8 * p.scale);
      EXPECT_NEAR(static_cast<double>(testing::referencePointHullDistance(r.witness_b, p.b)), p.rb, 1e-8 * p.scale);
    } else {
      ++overlapping;
    }
  }
  EXPECT_GT(separated, 1000);
  EXPECT_GT(overlapping, 300);
}

TEST(Gjk, LibccdAgreesOnIntersection) {
  std::mt19937_64 rng(7);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Pair p = randomPair(rng);
    const auto ref = static_cast<double>(testing::referenceHullDistance(p.a, p.b)) - p.ra - p.rb;
    if (std::abs(ref) < 1e-6 * p.scale) continue;  // too close to touching for libccd's tolerance
    const DistanceResult r = distance({p.a, p.ra}, {p.b, p.rb});
    ASSERT_EQ(r.distance == 0.0, intersectsLibccd({p.a, p.ra}, {p.b, p.rb})) << "pair " << i << " ref " << ref;
    ++checked;
  }
  EXPECT_GT(checked, 1800);
}

TEST(Gjk, TruncatedIterationsStillGiveLowerBounds) {
  std::mt19937_64 rng(99);
  for (int i = 0; i < 500; ++i) {
    const Pair p = randomPair(rng);
    const double ref = static_cast<double>(testing::referenceSschDistance(p.a, p.ra, p.b, p.rb));
    for (int k = 1; k <= 6; ++k) {
      GjkOptions opt;
      opt.max_iterations = k;
      const DistanceResult r = distance({p.a, p.ra}, {p.b, p.rb}, opt);
      ASSERT_LE(r.iterations, k);
      ASSERT_LE(r.distance, ref + 1e-13 * p.scale) << "pair " << i << " k " << k;
    }
  }
}

// A random pair, its reference distance, and GJK's answer with a stop at `stop` times its scale
// (stop_above or stop_below, as `set` assigns it).
struct StopRun {
  Pair p;
  double ref = 0.0;
  GjkOptions opt;
  DistanceResult r;
};
StopRun runWithStop(std::mt19937_64& rng, double stop, double GjkOptions::*set) {
  StopRun run;
  run.p = randomPair(rng);
  run.ref = static_cast<double>(testing::referenceSschDistance(run.p.a, run.p.ra, run.p.b, run.p.rb));
  run.opt.*set = stop * run.p.scale;
  run.r = distance({run.p.a, run.p.ra}, {run.p.b, run.p.rb}, run.opt);
  return run;
}

TEST(Gjk, StopAboveEndsEarlyWithAValidBound) {
  std::mt19937_64 rng(5);
  int early = 0;
  for (int i = 0; i < 500; ++i) {
    const auto [p, ref, opt, r] = runWithStop(rng, 0.1, &GjkOptions::stop_above);
    ASSERT_LE(r.distance, ref + 1e-13 * p.scale);
    if (r.status == GjkStatus::StoppedEarly) {
      ++early;
      EXPECT_GE(r.distance, opt.stop_above);
    } else {
      EXPECT_LT(r.distance, opt.stop_above + tolerance(ref, p.scale));
    }
  }
  EXPECT_GT(early, 50);
}

// stop_below: GJK ends once two points of the volumes are proven within it (the true distance is
// then at most stop_below), from the start when the centroids already are; the bound stays a
// lower bound; without the stop the answer is the converged distance.
TEST(Gjk, StopBelowEndsOnceTheVolumesAreProvenWithinIt) {
  std::mt19937_64 rng(8);
  int early = 0, at_start = 0, converged = 0;
  for (int i = 0; i < 1000; ++i) {
    const auto [p, ref, opt, r] = runWithStop(rng, 0.1, &GjkOptions::stop_below);
    ASSERT_LE(r.distance, ref + 1e-13 * p.scale) << "pair " << i;
    if (r.status == GjkStatus::StoppedEarly) {
      ++early;
      at_start += r.iterations == 0;
      ASSERT_LE(ref, opt.stop_below + tolerance(ref, p.scale)) << "pair " << i;
      ASSERT_LE(r.distance, opt.stop_below);
    } else if (r.status != GjkStatus::Overlap) {
      ++converged;
      ASSERT_NEAR(r.distance, ref, tolerance(ref, p.scale)) << "pair " << i;
      ASSERT_GT(ref, opt.stop_below - tolerance(ref, p.scale)) << "pair " << i;
    }
  }
  EXPECT_GT(early, 100);
  EXPECT_GT(at_start, 0);
  EXPECT_GT(converged, 100);
  // A warm start replaces the start points: v is then a direction, not a point of the difference.
  const Points a{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Points b{{0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}};
  const Vec3 dir(0, 0, -1e-3);
  GjkOptions warm;
  warm.stop_below = 0.6;
  warm.warm_start = &dir;
  EXPECT_GT(distance({a, 0.0}, {b, 0.0}, warm).iterations, 0);
  warm.warm_start = nullptr;
  EXPECT_EQ(distance({a, 0.0}, {b, 0.0}, warm).iterations, 0);
}

TEST(Gjk, WarmStartFromLastDirectionSavesIterations) {
  std::mt19937_64 rng(11);
  long cold_total = 0, warm_total = 0;
  for (int i = 0; i < 300; ++i) {
    Pair p = randomPair(rng);
    const DistanceResult first = distance({p.a, p.ra}, {p.b, p.rb});
    // The next cycle: b moved a little.
    const Vec3 shift = 1e-3 * p.scale * testing::randomUnit(rng);
    for (Vec3& q : p.b) q += shift;
    const double ref = static_cast<double>(testing::referenceSschDistance(p.a, p.ra, p.b, p.rb));
    GjkOptions warm;
    warm.warm_start = &first.direction;
    const DistanceResult cold = distance({p.a, p.ra}, {p.b, p.rb});
    const DistanceResult hot = distance({p.a, p.ra}, {p.b, p.rb}, warm);
    ASSERT_NEAR(hot.distance, ref, tolerance(ref, p.scale));
    ASSERT_LE(hot.distance, ref + 1e-13 * p.scale);
    cold_total += cold.iterations;
    warm_total += hot.iterations;
  }
  EXPECT_LT(warm_total, cold_total);
}

TEST(Gjk, WarmStartCertificateAnswersSeparatedPairsInOneIteration) {
  const Points a{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Points b{{0, 0, 3}, {1, 0, 3}, {0, 1, 4}};
  const Vec3 dir(0, 0, -1);  // from b to a
  GjkOptions opt;
  opt.warm_start = &dir;
  opt.stop_above = 1.0;
  const DistanceResult r = distance({a, 0.1}, {b, 0.1}, opt);
  EXPECT_EQ(r.status, GjkStatus::StoppedEarly);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_NEAR(r.distance, 2.8, 1e-12);
}

TEST(Gjk, PenetrationDepthOfOverlappingSpheres) {
  const Points a{{0, 0, 0}};
  const Points b{{1.5, 0, 0}};
  const Penetration pen = penetration({a, 1.0}, {b, 1.0});
  ASSERT_TRUE(pen.overlapping);
  EXPECT_NEAR(pen.depth, 0.5, 1e-6);
  EXPECT_NEAR(std::abs(pen.direction.x()), 1.0, 1e-6);
  EXPECT_FALSE(penetration({a, 0.7}, {b, 0.7}).overlapping);
}

}  // namespace
}  // namespace kccd
