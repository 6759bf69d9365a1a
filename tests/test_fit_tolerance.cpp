// Fits to a tolerance (kccd/modelling/fit.hpp: fitToTolerance, outsideDistance) and concave
// parts in convex pieces (kccd/modelling/convex_pieces.hpp), checked against the independent
// long-double point-to-hull distance (tests/support/reference_distance.hpp): every point of the
// part inside the volumes, and no point of a volume farther outside the part's hull than the
// tolerance it reports.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "kccd/modelling/convex_hull.hpp"
#include "kccd/modelling/convex_pieces.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/part.hpp"
#include "support/reference_distance.hpp"
#include "support/sanitized.hpp"

namespace km = kccd::modelling;
using kccd::Vec3;
using kccd::testing::referencePointHullDistance;

namespace {

constexpr double kPi = std::numbers::pi;

// A closed box mesh (12 triangles) from lo to hi.
void addBox(km::Part& part, const Vec3& lo, const Vec3& hi) {
  auto corner = [&](int i) { return Vec3(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()); };
  static constexpr int kFaces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : kFaces) {
    part.addTriangle(corner(f[0]), corner(f[1]), corner(f[2]));
    part.addTriangle(corner(f[0]), corner(f[2]), corner(f[3]));
  }
}

// A closed cylinder mesh along z: `segments` around, radius r, from z0 to z1, centred at (cx, cy).
km::Part cylinder(int segments, double r, double z0, double z1, double cx = 0.0, double cy = 0.0) {
  km::Part part;
  auto rim = [&](int i, double z) {
    const double a = 2 * kPi * i / segments;
    return Vec3(cx + r * std::cos(a), cy + r * std::sin(a), z);
  };
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    part.addTriangle(rim(i, z0), rim(j, z0), rim(j, z1));
    part.addTriangle(rim(i, z0), rim(j, z1), rim(i, z1));
    part.addTriangle(Vec3(cx, cy, z0), rim(j, z0), rim(i, z0));
    part.addTriangle(Vec3(cx, cy, z1), rim(i, z1), rim(j, z1));
  }
  return part;
}

// A fork like an industrial robot's forearm: a 0.2 m body and two 0.12 m prongs 6 cm apart.
km::Part fork() {
  km::Part part;
  addBox(part, Vec3(0.0, -0.06, -0.04), Vec3(0.2, 0.06, 0.04));
  addBox(part, Vec3(0.19, -0.06, -0.04), Vec3(0.32, -0.03, 0.04));
  addBox(part, Vec3(0.19, 0.03, -0.04), Vec3(0.32, 0.06, 0.04));
  return part;
}

// The largest distance to conv(hull) of a point of conv(core) ⊕ ball(radius), sampled: every core
// point moved by the radius in 240 directions (the volume's farthest points are of that form).
double sampledOutside(const std::vector<Vec3>& core, double radius, const std::vector<Vec3>& hull) {
  std::vector<Vec3> dirs;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < 240; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / 240, s = std::sqrt(1.0 - z * z);
    dirs.emplace_back(s * std::cos(golden * i), s * std::sin(golden * i), z);
  }
  double worst = 0.0;
  for (const Vec3& c : core)
    for (const Vec3& d : dirs)
      worst = std::max(worst, static_cast<double>(referencePointHullDistance(c + radius * d, hull)));
  return worst;
}

// Every point in `points` lies inside conv(core) ⊕ ball(radius) of at least one volume.
double worstUncovered(const std::vector<Vec3>& points, const std::vector<km::FitResult>& volumes) {
  double worst = -INFINITY;
  for (const Vec3& p : points) {
    double best = INFINITY;
    for (const km::FitResult& v : volumes)
      best = std::min(best, static_cast<double>(referencePointHullDistance(p, v.points)) - v.radius);
    worst = std::max(worst, best);
  }
  return worst;
}

// Points spread over the part's triangles (corners included).
std::vector<Vec3> surfaceSamples(const km::Part& part, int per_triangle, std::mt19937_64& rng) {
  std::vector<Vec3> out = part.points;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const auto& f : part.faces)
    for (int k = 0; k < per_triangle; ++k) {
      double a = u(rng), b = u(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const Vec3 &p = part.points[f[0]], &q = part.points[f[1]], &r = part.points[f[2]];
      out.push_back(p + a * (q - p) + b * (r - p));
    }
  return out;
}

TEST(FitToTolerance, VolumesStayWithinTheirToleranceAndHoldThePart) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<std::pair<std::string, km::Part>> parts;
  parts.emplace_back("cylinder, 64 sides", cylinder(64, 0.05, 0.0, 0.3));
  parts.emplace_back("flat disc, 48 sides", cylinder(48, 0.08, 0.0, 0.01));
  km::Part blob;  // a bumpy convex-ish cloud of triangles
  for (int i = 0; i < 300; ++i) {
    Vec3 a(g(rng), g(rng), g(rng));
    a = a.normalized().cwiseProduct(Vec3(0.2, 0.08, 0.05));
    blob.addTriangle(a, a + Vec3(0.004, 0, 0), a + Vec3(0, 0.004, 0));
  }
  parts.emplace_back("bumpy ellipsoid", blob);
  int cases = 0;
  for (const auto& [name, part] : parts) {
    std::vector<Vec3> hull;
    for (int i : km::convexHull(part.points).vertices) hull.push_back(part.points[i]);
    // Under the sanitizers without the finest tolerance (the most points: the slowest oracle).
    for (const double tol : {0.0005, 0.002, 0.008}) {
      if (kccd::testing::kSanitized && tol < 0.001) continue;
      SCOPED_TRACE(name + ", tolerance " + std::to_string(tol));
      const km::FitResult r = km::fitToTolerance(part, tol, {.points = 8, .max_evaluations = 600});
      ++cases;
      EXPECT_LE(r.outside, tol);
      // The bound holds (the sampled reach is never beyond it) and is not loose by much.
      const double sampled = sampledOutside(r.points, r.radius, hull);
      EXPECT_LE(sampled, r.outside + 1e-12);
      EXPECT_GE(sampled, 0.6 * r.outside - 1e-6);
      // Every point of the part is inside.
      EXPECT_LE(worstUncovered(part.points, {r}), 0.0);
      // Fewer points than the hull has vertices at the coarser tolerances.
      if (tol >= 0.002) {
        EXPECT_LT(r.points.size(), hull.size() / 2) << r.method;
      }
      std::cout << name << " at " << tol * 1e3 << " mm: " << r.points.size() << " points (" << r.method << ") of "
                << hull.size() << " hull vertices, radius " << r.radius * 1e3 << " mm, outside <= " << r.outside * 1e3
                << " mm (sampled " << sampled * 1e3 << ")\n";
    }
  }
  EXPECT_EQ(cases, kccd::testing::kSanitized ? 6 : 9);
}

TEST(FitToTolerance, TighterToleranceNeverLoosensAndBadTolerancesThrow) {
  const km::Part part = cylinder(40, 0.04, 0.0, 0.2);
  const km::FitResult loose = km::fitToTolerance(part, 0.01, {.max_evaluations = 600});
  const km::FitResult tight = km::fitToTolerance(part, 0.0005, {.max_evaluations = 600});
  EXPECT_LE(tight.outside, 0.0005);
  EXPECT_LE(loose.outside, 0.01);
  EXPECT_GE(tight.points.size(), loose.points.size());
  EXPECT_LE(tight.volume, loose.volume * (1 + 1e-9));
  for (const double bad : {0.0, -1.0, std::nan(""), INFINITY * 1.0})
    EXPECT_THROW(km::fitToTolerance(part, bad), std::invalid_argument) << bad;
  EXPECT_THROW(km::fitToTolerance(km::Part{}, 0.001), std::invalid_argument);
  // The K fit and the exact hull report their own reach too.
  const km::FitResult k8 = km::fit(part, {.points = 8, .max_evaluations = 600});
  EXPECT_GT(k8.outside, 0.0);
  EXPECT_LE(sampledOutside(k8.points, k8.radius, km::exactHull(part).points), k8.outside + 1e-9);
  EXPECT_LT(km::exactHull(part).outside, 1e-9);
}

TEST(ConvexPieces, AForkSplitsAndItsPiecesHoldEveryPointOfItsSurface) {
  const km::Part part = fork();
  const km::PieceSplit split = km::splitConcave(part, {.max_pieces = 8, .concavity = 0.01});
  ASSERT_TRUE(split.measured);
  ASSERT_GE(split.pieces.size(), 2u);
  ASSERT_LE(split.pieces.size(), 8u);
  // The gap is 6 cm wide and 12 cm deep: the hull's surface over it lies about 3 cm from the solid.
  EXPECT_GT(split.whole_concavity, 0.02);
  EXPECT_LT(split.whole_concavity, 0.045);
  std::vector<km::FitResult> volumes;
  for (std::size_t i = 0; i < split.pieces.size(); ++i) {
    EXPECT_LE(split.concavity[i], 0.01 + 1e-12) << "piece " << i;
    volumes.push_back(km::fitToTolerance(split.pieces[i], 0.001, {.max_evaluations = 300}));
  }
  std::mt19937_64 rng(3);
  EXPECT_LE(worstUncovered(surfaceSamples(part, 40, rng), volumes), 0.0);
  // A wrist in the gap: clear of every piece, inside the whole link's hull.
  const std::vector<Vec3> wrist{Vec3(0.26, -0.015, -0.02), Vec3(0.3, 0.015, 0.02), Vec3(0.26, 0.015, 0.02),
                                Vec3(0.3, -0.015, -0.02)};
  std::vector<Vec3> whole;
  for (int i : km::convexHull(part.points).vertices) whole.push_back(part.points[i]);
  EXPECT_EQ(kccd::testing::referenceHullDistance(wrist, whole), 0.0L);
  for (const km::FitResult& v : volumes)
    EXPECT_GT(static_cast<double>(kccd::testing::referenceSschDistance(wrist, 0.0, v.points, v.radius)), 0.005);
  std::cout << "fork: concavity " << split.whole_concavity * 1e3 << " mm, " << split.pieces.size() << " pieces\n";
}

TEST(ConvexPieces, ConvexAndNonMeshPartsStayWhole) {
  km::Part box;
  addBox(box, Vec3(0, 0, 0), Vec3(0.3, 0.1, 0.05));
  const km::PieceSplit b = km::splitConcave(box);
  EXPECT_TRUE(b.measured);
  ASSERT_EQ(b.pieces.size(), 1u);
  EXPECT_LT(b.whole_concavity, 0.01);
  // The cylinder: no empty space worth a cut at 2 cm.
  EXPECT_EQ(km::splitConcave(cylinder(32, 0.05, 0, 0.3)).pieces.size(), 1u);
  // A ball primitive is not a mesh: returned whole, unmeasured.
  km::Part ball;
  ball.addSphere(Eigen::Affine3d::Identity(), 0.1);
  const km::PieceSplit s = km::splitConcave(ball);
  EXPECT_FALSE(s.measured);
  ASSERT_EQ(s.pieces.size(), 1u);
  EXPECT_EQ(s.pieces[0].balls.size(), ball.balls.size());
  // One piece asked: the fork stays whole, measured.
  const km::PieceSplit one = km::splitConcave(fork(), {.max_pieces = 1});
  EXPECT_EQ(one.pieces.size(), 1u);
  EXPECT_GT(one.whole_concavity, 0.02);
  EXPECT_THROW(km::splitConcave(box, {.max_pieces = 0}), std::invalid_argument);
  EXPECT_THROW(km::splitConcave(box, {.concavity = 0.0}), std::invalid_argument);
  EXPECT_THROW(km::splitConcave(box, {.resolution = 4}), std::invalid_argument);
}

// Random concave parts (unions of boxes, translated and rotated far from the origin): the pieces
// cover every sampled surface point, whatever the cuts.
TEST(ConvexPieces, RandomUnionsOfBoxesAreCovered) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int trials = kccd::testing::kSanitized ? 2 : 6;
  for (int trial = 0; trial < trials; ++trial) {
    km::Part part;
    const int boxes = 2 + trial % 3;
    const Vec3 offset = (trial % 2 ? 50.0 : 0.0) * Vec3(u(rng), u(rng), u(rng));
    const double scale = trial % 3 == 0 ? 1e-3 : 1.0;  // millimetre parts too
    for (int b = 0; b < boxes; ++b) {
      const Vec3 c(0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng));
      const Vec3 h(0.02 + 0.1 * std::abs(u(rng)), 0.02 + 0.1 * std::abs(u(rng)), 0.02 + 0.05 * std::abs(u(rng)));
      addBox(part, offset + scale * (c - h), offset + scale * (c + h));
    }
    const km::PieceSplit split = km::splitConcave(part, {.max_pieces = 6, .concavity = 0.01 * scale});
    std::vector<km::FitResult> volumes;
    for (const km::Part& p : split.pieces) volumes.push_back(km::exactHull(p));
    SCOPED_TRACE("trial " + std::to_string(trial) + ": " + std::to_string(split.pieces.size()) + " pieces");
    EXPECT_LE(worstUncovered(surfaceSamples(part, 8, rng), volumes), 0.0);
  }
}

}  // namespace
