// The point scans' AVX2 paths against their scalar paths: the same support index and the same
// summary for every input, ties, zero and non-finite directions and coordinates at the extremes
// of a double included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "point_scan.hpp"

namespace kccd::detail {
namespace {

double dot(const Vec3& p, const Vec3& d) { return p.x() * d.x() + p.y() * d.y() + p.z() * d.z(); }

// Coordinates of every magnitude a file can hold, signs mixed, sometimes repeated points.
std::vector<Vec3> randomPoints(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  const int mode = std::uniform_int_distribution<int>(0, 3)(rng);
  const double scale = std::pow(10.0, exponent(rng));
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    if (mode == 1 && i > 0 && u(rng) > 0.0) {  // duplicates: ties across lanes
      pts.push_back(pts[static_cast<std::size_t>(std::uniform_int_distribution<int>(0, i - 1)(rng))]);
    } else if (mode == 2) {  // each coordinate of its own magnitude
      pts.emplace_back(u(rng) * std::pow(10.0, exponent(rng)), u(rng) * std::pow(10.0, exponent(rng)),
                       u(rng) * std::pow(10.0, exponent(rng)));
    } else if (mode == 3) {  // a grid: many exact ties
      pts.emplace_back(std::round(2.0 * u(rng)), std::round(2.0 * u(rng)), std::round(2.0 * u(rng)));
    } else {
      pts.emplace_back(u(rng) * scale, u(rng) * scale, u(rng) * scale);
    }
  }
  return pts;
}

Vec3 randomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  std::uniform_int_distribution<int> kind(0, 9);
  const double inf = std::numeric_limits<double>::infinity();
  switch (kind(rng)) {
    case 0:
      return Vec3::Zero();
    case 1:
      return Vec3(1.0, 0.0, 0.0);
    case 2:
      return Vec3(g(rng), inf, 0.0);
    case 3:
      return Vec3(std::numeric_limits<double>::quiet_NaN(), g(rng), g(rng));
    case 4:
      return Vec3(g(rng), g(rng), g(rng)) * 1e300;
    case 5:
      return Vec3(g(rng), g(rng), g(rng)) * 1e-300;
    default:
      return Vec3(g(rng), g(rng), g(rng));
  }
}

TEST(SupportScan, Avx2AndScalarPathsPickTheSamePoint) {
  if (!avx2Available()) GTEST_SKIP() << "this CPU has no AVX2: only the scalar path runs";
  std::mt19937_64 rng(20261130);
  std::uniform_int_distribution<int> count(1, 300);
  int checked = 0, maxima = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::vector<Vec3> pts = randomPoints(rng, count(rng));
    const Vec3 d = randomDirection(rng);
    const int scalar = supportIndexScalar(pts, d);
    const int avx2 = supportIndexAvx2(pts, d);
    ASSERT_EQ(scalar, avx2) << "trial " << trial << ", " << pts.size() << " points, direction " << d.transpose();
    ASSERT_EQ(supportIndex(pts, d), scalar);
    ++checked;
    // Where every dot product is a number, the point picked attains the largest of them.
    bool numbers = true;
    double best = -std::numeric_limits<double>::infinity();
    for (const Vec3& p : pts) {
      numbers &= !std::isnan(dot(p, d));
      best = std::max(best, dot(p, d));
    }
    if (numbers) {
      ASSERT_EQ(dot(pts[static_cast<std::size_t>(scalar)], d), best) << "trial " << trial;
      ++maxima;
    }
  }
  EXPECT_EQ(checked, 20000);
  EXPECT_GT(maxima, 15000);  // most draws have finite dot products, so the maximum was checked
}

TEST(SupportScan, TheInOrderScanFindsTheLanesLargestValueAndItsFirstPoint) {
  std::mt19937_64 rng(20261201);
  std::uniform_int_distribution<int> count(1, 12);
  int numbers = 0, ties = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    const std::vector<Vec3> pts = randomPoints(rng, count(rng));
    const Vec3 d = randomDirection(rng);
    bool finite = true;
    for (const Vec3& p : pts) finite &= std::isfinite(dot(p, d));
    if (!finite) continue;  // a cell's dot products are finite (support_cells.hpp)
    ++numbers;
    const int in_order = supportIndexInOrder(pts, d);
    const int lanes = supportIndexScalar(pts, d);
    const double value = dot(pts[static_cast<std::size_t>(in_order)], d);
    ASSERT_EQ(value, dot(pts[static_cast<std::size_t>(lanes)], d)) << "trial " << trial;
    for (int k = 0; k < in_order; ++k) ASSERT_LT(dot(pts[static_cast<std::size_t>(k)], d), value) << trial;
    ties += in_order != lanes;
  }
  EXPECT_GT(numbers, 30000);
  EXPECT_GT(ties, 0);  // the grids' ties: the two scans may name different points of one value
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(PointSummary, Avx2AndScalarPathsAgreeBitForBit) {
  if (!avx2Available()) GTEST_SKIP() << "this CPU has no AVX2: only the scalar path runs";
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> count(1, 300);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const double big = std::numeric_limits<double>::max();
  int rejected = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<Vec3> pts = randomPoints(rng, count(rng));
    const int poison = std::uniform_int_distribution<int>(0, 19)(rng);
    const std::size_t at = std::uniform_int_distribution<std::size_t>(0, pts.size() - 1)(rng);
    if (poison == 0) pts[at].y() = nan;
    if (poison == 1) pts[at].z() = -inf;
    if (poison == 2) pts[at].x() = big;  // sums that may overflow
    const PointSummary s = summarizeScalar(pts), v = summarizeAvx2(pts), d = summarize(pts);
    ASSERT_EQ(s.finite, v.finite) << "trial " << trial;
    ASSERT_EQ(s.finite, d.finite) << "trial " << trial;
    if (!s.finite) {
      ++rejected;
      continue;
    }
    for (int c = 0; c < 3; ++c) ASSERT_TRUE(sameBits(s.centroid[c], v.centroid[c])) << "trial " << trial;
    ASSERT_TRUE(sameBits(s.scale, v.scale)) << "trial " << trial;
    // The scale is the largest absolute coordinate, and the centroid lies within the points' box.
    double m = 0.0;
    Vec3 lo = pts[0], hi = pts[0];
    for (const Vec3& p : pts) {
      m = std::max(m, p.cwiseAbs().maxCoeff());
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    ASSERT_EQ(s.scale, m);
    for (int c = 0; c < 3; ++c) {
      const double slack = 1e-12 * std::max(std::abs(lo[c]), std::abs(hi[c]));
      ASSERT_GE(s.centroid[c], lo[c] - slack) << "trial " << trial;
      ASSERT_LE(s.centroid[c], hi[c] + slack) << "trial " << trial;
    }
  }
  EXPECT_GT(rejected, 1000);  // the poisoned draws (a tenth of them) are all rejected
}

TEST(SupportScan, EveryLaneAndTailPositionCanWin) {
  // One point far out along x, at each position of sets of 1..40 points: each lane, each tail slot.
  for (int n = 1; n <= 40; ++n) {
    for (int at = 0; at < n; ++at) {
      std::vector<Vec3> pts(static_cast<std::size_t>(n), Vec3(0.0, 1.0, -1.0));
      pts[static_cast<std::size_t>(at)] = Vec3(2.0, 0.0, 0.0);
      ASSERT_EQ(supportIndexScalar(pts, Vec3::UnitX()), at) << n << " points";
      ASSERT_EQ(supportIndex(pts, Vec3::UnitX()), at) << n << " points";
      if (avx2Available()) {
        ASSERT_EQ(supportIndexAvx2(pts, Vec3::UnitX()), at) << n << " points";
      }
    }
  }
}

}  // namespace
}  // namespace kccd::detail
