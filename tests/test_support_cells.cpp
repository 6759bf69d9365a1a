// Support candidates by direction against a scan of every point: the same largest computed dot
// product, bit for bit, for point sets of every shape and magnitude and directions on and around
// the cells' borders; and few candidates per cell for a round body.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "point_scan.hpp"
#include "support_cells.hpp"

namespace kccd::detail {
namespace {

double cellDot(const Vec3& p, const Vec3& d) { return p.x() * d.x() + p.y() * d.y() + p.z() * d.z(); }

// Sets a body can have: on an ellipsoid, a box's grid (many ties), flat, on a line, with repeated
// points, around a far-off centre; sizes from 1e-120 to 1e150.
std::vector<Vec3> randomBody(std::mt19937_64& rng, int n) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int mode = std::uniform_int_distribution<int>(0, 5)(rng);
  const double scale = std::pow(10.0, std::uniform_int_distribution<int>(-120, 150)(rng));
  const Vec3 axes(std::abs(g(rng)) + 0.01, std::abs(g(rng)) + 0.01, std::abs(g(rng)) + 0.01);
  const Vec3 centre = mode == 5 ? Vec3(Vec3(g(rng), g(rng), g(rng)) * 1e3) : Vec3::Zero();
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    Vec3 p(g(rng), g(rng), g(rng));
    p = axes.cwiseProduct(p.normalized());
    if (mode == 1) p = Vec3(std::round(2.0 * u(rng)), std::round(2.0 * u(rng)), std::round(2.0 * u(rng)));
    if (mode == 2) p.z() = 0.0;
    if (mode == 3) p = Vec3(1.0, 2.0, -0.5) * u(rng);
    if (mode == 4 && i > 0 && u(rng) > 0.0) {
      pts.push_back(pts[static_cast<std::size_t>(std::uniform_int_distribution<int>(0, i - 1)(rng))]);
      continue;
    }
    pts.push_back((centre + p) * scale);
  }
  return pts;
}

// Directions anywhere, on and beside the cells' borders (the face coordinates -1 + 2k / 4 and
// their neighbours in floating point), on the cube's edges and corners, tiny and huge.
Vec3 borderDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  std::uniform_int_distribution<int> kind(0, 5), axis(0, 2), border(0, kCellsPerEdge), step(-2, 2);
  const int a = axis(rng);
  auto near_border = [&] {
    double t = -1.0 + 2.0 * border(rng) / kCellsPerEdge;
    for (int s = step(rng); s != 0; s += s > 0 ? -1 : 1) t = std::nextafter(t, s > 0 ? 2.0 : -2.0);
    return t;
  };
  Vec3 d(g(rng), g(rng), g(rng));
  switch (kind(rng)) {
    case 0:
      d[a] = g(rng) > 0.0 ? 1.0 : -1.0;
      d[(a + 1) % 3] = near_border();
      break;
    case 1:
      d[a] = g(rng) > 0.0 ? 1.0 : -1.0;
      d[(a + 1) % 3] = near_border();
      d[(a + 2) % 3] = near_border();
      break;
    case 2:
      d *= std::pow(10.0, std::uniform_int_distribution<int>(-300, 300)(rng));
      break;
    default:
      break;
  }
  return d;
}

TEST(SupportCells, ACellsLargestDotProductIsTheWholeSetsBitForBit) {
  std::mt19937_64 rng(7);
  long compared = 0, cells_built = 0, shortened = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int n = std::uniform_int_distribution<int>(12, 120)(rng);
    const std::vector<Vec3> pts = randomBody(rng, n);
    const SupportCells cells = supportCells(pts);
    if (cells.empty()) continue;
    ++cells_built;
    for (int q = 0; q < 200; ++q) {
      const Vec3 d = borderDirection(rng);
      const CellScan scan = cellScan(cells, pts, d);
      ASSERT_FALSE(scan.points.empty());
      ASSERT_EQ(scan.index == nullptr, cellOf(d) < 0);  // no cell: every point, as they are
      const int j = supportIndex(scan.points, d);
      const int i = scan.index == nullptr ? j : scan.index[j];
      ASSERT_EQ(pts[static_cast<std::size_t>(i)], scan.points[static_cast<std::size_t>(j)]);
      const double got = cellDot(scan.points[static_cast<std::size_t>(j)], d);
      const double want = cellDot(pts[static_cast<std::size_t>(supportIndex(pts, d))], d);
      ASSERT_TRUE(got == want || (std::isnan(got) && std::isnan(want)))
          << "trial " << trial << " direction " << d.transpose() << ": " << got << " against " << want;
      // The checker's call (a short cell scanned in order) finds the same value.
      const double by_cell = cellDot(pts[static_cast<std::size_t>(cellSupport(cells, pts, d))], d);
      ASSERT_TRUE(by_cell == want || (std::isnan(by_cell) && std::isnan(want))) << "trial " << trial;
      if (scan.points.size() < pts.size()) ++shortened;
      ++compared;
    }
  }
  EXPECT_GT(cells_built, 2000);
  EXPECT_GT(compared, 400000);
  EXPECT_GT(shortened, compared / 2);
}

// Points that differ by 1e-16 to 1e-3 of the set's size around a few centres, the cells'
// threshold (kCellThreshold) among them: whether one beats another at a cell's vertices is decided
// by the threshold and the rounding, the case the argument at the top of support_cells.hpp is for.
TEST(SupportCells, PointsAsCloseAsTheThresholdKeepTheLargestDotProduct) {
  std::mt19937_64 rng(19);
  std::normal_distribution<double> g;
  long compared = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const double scale = std::pow(10.0, std::uniform_int_distribution<int>(-90, 140)(rng));
    const double spread = std::pow(10.0, std::uniform_real_distribution<double>(-16.0, -3.0)(rng));
    std::vector<Vec3> centres;
    for (int c = 0; c < 3; ++c) centres.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
    std::vector<Vec3> pts;
    const int n = std::uniform_int_distribution<int>(12, 60)(rng);
    for (int i = 0; i < n; ++i) {
      const Vec3& c = centres[static_cast<std::size_t>(i % 3)];
      pts.push_back((c + spread * Vec3(g(rng), g(rng), g(rng))) * scale);
    }
    const SupportCells cells = supportCells(pts);
    ASSERT_FALSE(cells.empty());
    for (int q = 0; q < 100; ++q) {
      // Directions along the centres (where their points compete) and on the cells' borders.
      const Vec3 d = q % 2 == 0 ? Vec3(centres[static_cast<std::size_t>(q % 3)] + 1e-3 * Vec3(g(rng), g(rng), g(rng)))
                                : borderDirection(rng);
      const double want = cellDot(pts[static_cast<std::size_t>(supportIndex(pts, d))], d);
      const double got = cellDot(pts[static_cast<std::size_t>(cellSupport(cells, pts, d))], d);
      ASSERT_TRUE(got == want || (std::isnan(got) && std::isnan(want)))  // huge directions overflow
          << "trial " << trial << " direction " << d.transpose() << ": " << got << " against " << want;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 150000);
}

TEST(SupportCells, DirectionsWithoutACellAndSmallSetsScanEveryPoint) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(cellOf(Vec3::Zero()), -1);
  EXPECT_EQ(cellOf(Vec3(inf, 0.0, 0.0)), -1);
  EXPECT_EQ(cellOf(Vec3(1.0, nan, 0.0)), -1);
  EXPECT_EQ(cellOf(Vec3(nan, nan, nan)), -1);
  std::vector<Vec3> pts(40, Vec3(1.0, 2.0, 3.0));
  pts.push_back(Vec3(inf, 0.0, 0.0));
  EXPECT_TRUE(supportCells(pts).empty());  // not finite
  pts.back() = Vec3(0.0, nan, 0.0);
  EXPECT_TRUE(supportCells(pts).empty());                                  // NaN
  EXPECT_TRUE(supportCells(std::vector<Vec3>(40, Vec3::Zero())).empty());  // no extent
  EXPECT_TRUE(supportCells(std::vector<Vec3>(8, Vec3(1.0, 0.0, 0.0))).empty());
  EXPECT_TRUE(supportCells(std::vector<Vec3>(40, Vec3(1e200, 0.0, 0.0))).empty());
  EXPECT_TRUE(supportCells(std::vector<Vec3>(40, Vec3(1e-200, 0.0, 0.0))).empty());
  EXPECT_EQ(cellOf(Vec3(1e-200, 0.0, 0.0)), -1);
  EXPECT_EQ(cellOf(Vec3(-1e200, 0.0, 0.0)), -1);
  // Every direction lands in one of the 6 * 16 cells.
  std::mt19937_64 rng(3);
  std::vector<int> hits(6 * kCellsPerEdge * kCellsPerEdge, 0);
  std::normal_distribution<double> g;
  for (int k = 0; k < 100000; ++k) {
    const int c = cellOf(Vec3(g(rng), g(rng), g(rng)));
    ASSERT_GE(c, 0);
    ASSERT_LT(c, static_cast<int>(hits.size()));
    ++hits[static_cast<std::size_t>(c)];
  }
  for (int h : hits) EXPECT_GT(h, 0);
}

// A round body of 64 points (every one a hull vertex): a cell keeps a small part of them, which
// is what makes the scan shorter.
TEST(SupportCells, ACellOfARoundBodyKeepsFewPoints) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  double total = 0.0, cells_seen = 0.0;
  for (int body = 0; body < 50; ++body) {
    std::vector<Vec3> pts;
    for (int i = 0; i < 64; ++i) pts.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
    const SupportCells cells = supportCells(pts);
    ASSERT_FALSE(cells.empty());
    for (std::size_t c = 0; c + 1 < cells.begin.size(); ++c) {
      total += cells.begin[c + 1] - cells.begin[c];
      cells_seen += 1.0;
    }
  }
  const double mean = total / cells_seen;
  std::printf("mean candidates per cell of 64 points: %.2f\n", mean);
  EXPECT_LT(mean, 16.0);
}

}  // namespace
}  // namespace kccd::detail
