// Conservative SSCH fitting: every point of the part inside (checked with the independent
// long-double point-to-hull distance), volumes against closed forms and the convex hull, and
// the Coin3D reader on generated and real Open Inventor / VRML / STL parts.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "kccd/modelling/convex_hull.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/part.hpp"
#include "support/reference_distance.hpp"
#include "support/sanitized.hpp"

namespace km = kccd::modelling;
using kccd::Vec3;
using kccd::testing::referencePointHullDistance;

namespace {

constexpr double kPi = std::numbers::pi;
const std::string kModels = "/usr/share/inventor/data/models/";

// The true surface of an analytic primitive, sampled exactly (not from any tessellation).
struct Truth {
  std::vector<Vec3> points;
  void sphere(const Eigen::Affine3d& t, double r, std::mt19937_64& rng, int n = 400) {
    std::normal_distribution<double> g;
    for (int i = 0; i < n; ++i) points.push_back(t * (r * Vec3(g(rng), g(rng), g(rng)).normalized()));
  }
  void circle(const Eigen::Affine3d& t, double r, double y, std::mt19937_64& rng, int n = 400) {
    std::uniform_real_distribution<double> u(0, 2 * kPi);
    for (int i = 0; i < n; ++i) {
      const double a = i < 8 ? i * kPi / 4 : u(rng);
      points.push_back(t * Vec3(r * std::cos(a), y, r * std::sin(a)));
    }
  }
};

// Every mesh point and every sampled true surface point is inside the fitted SSCH.
void expectContains(const km::FitResult& f, const km::Part& part, const Truth& truth, const std::string& what) {
  const std::vector<Vec3> core(f.points.begin(), f.points.end());
  long double worst = -1;
  for (const Vec3& p : part.points) worst = std::max(worst, referencePointHullDistance(p, core) - f.radius);
  for (const kccd::Sphere& b : part.balls)
    worst = std::max(worst, referencePointHullDistance(b.center, core) + b.radius - f.radius);
  for (const Vec3& p : truth.points) worst = std::max(worst, referencePointHullDistance(p, core) - f.radius);
  EXPECT_LE(worst, 0.0L) << what << ": a point of the part lies " << static_cast<double>(worst)
                         << " outside the fitted volume";
}

Eigen::Affine3d randomPose(std::mt19937_64& rng, double offset) {
  std::normal_distribution<double> g;
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.linear() = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  t.translation() = offset * Vec3(g(rng), g(rng), g(rng));
  return t;
}

km::FitOptions quick(int k) {
  km::FitOptions o;
  o.points = k;
  o.max_evaluations = 1500;
  return o;
}

}  // namespace

TEST(SschVolume, ClosedFormsOfSimpleCores) {
  const double r = 0.3, a = 2.0;
  const std::vector<Vec3> point{Vec3(1, 2, 3)};
  EXPECT_NEAR(km::sschVolume(point, r), 4.0 / 3.0 * kPi * r * r * r, 1e-12);
  const std::vector<Vec3> segment{Vec3(0, 0, 0), Vec3(a, 0, 0)};
  EXPECT_NEAR(km::sschVolume(segment, r), kPi * r * r * a + 4.0 / 3.0 * kPi * r * r * r, 1e-12);
  const std::vector<Vec3> square{Vec3(0, 0, 0), Vec3(a, 0, 0), Vec3(a, a, 0), Vec3(0, a, 0), Vec3(a / 2, a / 2, 0)};
  EXPECT_NEAR(km::sschVolume(square, r), 2 * a * a * r + kPi * 2 * a * r * r + 4.0 / 3.0 * kPi * r * r * r, 1e-12);
  std::vector<Vec3> cube;
  for (int i = 0; i < 8; ++i) cube.emplace_back(i & 1 ? a : 0, i & 2 ? a : 0, i & 4 ? a : 0);
  cube.emplace_back(a / 2, a / 2, a / 2);  // an interior point changes nothing
  EXPECT_NEAR(km::sschVolume(cube, r), a * a * a + 6 * a * a * r + 3 * kPi * a * r * r + 4.0 / 3.0 * kPi * r * r * r,
              1e-10);
}

TEST(SschVolume, AgreesWithMonteCarloOnRandomCores) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<Vec3> core;
    for (int i = 0; i < 6; ++i) core.emplace_back(g(rng), 0.5 * g(rng), 0.3 * g(rng));
    const double r = 0.2 + 0.3 * trial;
    Vec3 lo = Vec3::Constant(1e9), hi = Vec3::Constant(-1e9);
    for (const Vec3& p : core) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    lo.array() -= r, hi.array() += r;
    std::uniform_real_distribution<double> u(0, 1);
    const int n = 20000;
    int inside = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 x = lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
      if (referencePointHullDistance(x, core) <= r) ++inside;
    }
    const double box = (hi - lo).prod();
    const double mc = box * inside / n, sigma = box * std::sqrt(inside * (1.0 - double(inside) / n)) / n;
    EXPECT_NEAR(km::sschVolume(core, r), mc, 4 * sigma + 1e-9) << "trial " << trial;
  }
}

TEST(Fit, GeneratedPartsAreContainedForEveryK) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  // 12 trials; 4 under the sanitizers (each kind of part once, every scale once).
  for (int trial = 0; trial < kccd::testing::casesFor(12, 4); ++trial) {
    km::Part part;
    Truth truth;
    const double scale = std::pow(10.0, trial % 4 - 2);  // 1 cm ... 10 m parts
    const Eigen::Affine3d pose = randomPose(rng, 3 * scale);
    Eigen::Affine3d scaled = pose;
    scaled.linear() *= scale;
    switch (trial % 4) {
      case 0:  // a blob of random points
        for (int i = 0; i < 300; ++i) part.points.push_back(scaled * Vec3(g(rng), 0.5 * g(rng), 0.2 * g(rng)));
        break;
      case 1:  // a cylinder and a sphere
        part.addCylinderY(scaled, 0.3, 1.5);
        truth.circle(scaled, 0.3, -0.75, rng);
        truth.circle(scaled, 0.3, 0.75, rng);
        part.addSphere(scaled * Eigen::Translation3d(0, 0.9, 0), 0.4);
        truth.sphere(scaled * Eigen::Translation3d(0, 0.9, 0), 0.4, rng);
        break;
      case 2: {  // a cone and an unevenly scaled sphere (an ellipsoid)
        part.addConeY(scaled, 0.5, 1.0);
        truth.circle(scaled, 0.5, -0.5, rng);
        truth.points.push_back(scaled * Vec3(0, 0.5, 0));
        Eigen::Affine3d squash = scaled * Eigen::Translation3d(0.8, 0, 0);
        squash.linear() = squash.linear() * Eigen::Vector3d(1.0, 0.3, 2.0).asDiagonal();
        part.addSphere(squash, 0.25);
        truth.sphere(squash, 0.25, rng);
        break;
      }
      default:  // flat and collinear point sets
        for (int i = 0; i < 40; ++i) part.points.push_back(scaled * Vec3(g(rng), g(rng), 0));
        for (int i = 0; i < 10; ++i) part.points.push_back(scaled * Vec3(0, 0, 3 + g(rng)));
        break;
    }
    for (int k : {1, 2, 3, 5, 8, 16}) {
      if (kccd::testing::kSanitized && k == 16 && trial > 0) continue;  // K = 16 once: K = 8's paths, more points
      const km::FitResult f = km::fit(part, quick(k));
      ASSERT_EQ(static_cast<int>(f.points.size()), k);
      expectContains(f, part, truth, "trial " + std::to_string(trial) + " K " + std::to_string(k));
      EXPECT_GE(f.volume, f.hull_volume * (1 - 1e-9));
    }
  }
}

TEST(Fit, SinglePointsAndDegenerateParts) {
  km::Part one;
  one.points = {Vec3(1, 2, 3)};
  km::FitResult f = km::fit(one, quick(1));
  EXPECT_NEAR((f.points[0] - Vec3(1, 2, 3)).norm(), 0.0, 1e-6);
  EXPECT_LE(f.radius, 1e-6);
  expectContains(f, one, {}, "one point");
  km::Part segment;
  segment.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 0, 0)};
  f = km::fit(segment, quick(2));
  EXPECT_LE(f.radius, 1e-4);
  expectContains(f, segment, {}, "segment");
  EXPECT_THROW(km::fit(segment, quick(0)), std::invalid_argument);
  EXPECT_THROW(km::fit(segment, quick(17)), std::invalid_argument);
  EXPECT_THROW(km::fit(km::Part{}, quick(4)), std::invalid_argument);
}

// What K = 8 buys on three simple parts, as ratios to the convex hull's volume.
TEST(Fit, VolumeRatiosForEightPoints) {
  km::Part box;
  box.addBox(Eigen::Affine3d::Identity(), Vec3(0.4, 0.2, 0.1));
  km::Part cylinder;
  cylinder.addCylinderY(Eigen::Affine3d::Identity(), 0.05, 0.3);
  km::Part ell;  // an L of two boxes
  ell.addBox(Eigen::Affine3d(Eigen::Translation3d(0.2, 0, 0)), Vec3(0.4, 0.1, 0.1));
  ell.addBox(Eigen::Affine3d(Eigen::Translation3d(0.05, 0.15, 0)), Vec3(0.1, 0.4, 0.1));
  struct Case {
    const char* name;
    const km::Part* part;
    double max_ratio;
  };
  for (const Case& c : {Case{"box", &box, 1.01}, Case{"cylinder", &cylinder, 1.35}, Case{"L", &ell, 1.40}}) {
    const km::FitResult f = km::fit(*c.part, {.points = 8});
    const double ratio = f.volume / f.hull_volume;
    RecordProperty(std::string(c.name) + "_ratio", std::to_string(ratio));
    EXPECT_LE(ratio, c.max_ratio) << c.name;
    EXPECT_LT(f.volume, f.capsule_volume) << c.name;
    EXPECT_LT(f.volume, f.sphere_volume) << c.name;
    expectContains(f, *c.part, {}, c.name);
  }
}

namespace {

// The smallest SSCH, over a closed-form family, covering a cylinder of radius 1 and half-length
// h: two regular n-gons (circumradius a, at z = ±c, aligned) rounded by r. The rim's farthest
// points from the prism lie in the middle of an edge's direction, so r = |(1 − a cos(π/n),
// h − c)|; the volume is Steiner's V + S r + M r² + 4/3 π r³ of the n-gon prism. Returned as a
// ratio to the cylinder's volume 2πh. Shares no code with the fit.
double bestPrismFamilyRatio(double h, int n) {
  const double best_a = 1.0 / std::cos(kPi / n);  // the n-gon around the rim
  double best = INFINITY;
  for (int i = 0; i <= 400; ++i) {
    const double a = best_a * i / 400.0;
    const double side = 2.0 * a * std::sin(kPi / n), area = n * a * a * std::sin(2.0 * kPi / n) / 2.0;
    for (int j = 0; j <= 400; ++j) {
      const double c = h * j / 400.0;
      const double r = std::hypot(std::max(0.0, 1.0 - a * std::cos(kPi / n)), h - c);
      const double volume = area * 2.0 * c;
      const double surface = 2.0 * area + n * side * 2.0 * c;
      // Mean-curvature term: each edge's length times its exterior angle, halved (2n cap
      // edges at π/2, n side edges at 2π/n).
      const double mean = (2.0 * n * side * kPi / 2.0 + n * 2.0 * c * 2.0 * kPi / n) / 2.0;
      best = std::min(best, volume + surface * r + mean * r * r + 4.0 / 3.0 * kPi * r * r * r);
    }
  }
  return best / (2.0 * kPi * h);
}

}  // namespace

// How close K = 8 and K = 16 come to the best of the prism family on cylinders, the shape of
// most robot links. For a cylinder no longer than four radii the family's best 8-point SSCH is
// the square box around it, 4/π = 1.273 times its volume: a volume ratio of 1.2 at K = 8 is out
// of reach of such cores (and of the family up to six radii: beyond, the capsule gets below
// 1.2); octagons (K = 16) give 8 tan(π/8)/π = 1.055.
TEST(Fit, CylindersComeCloseToTheBestPrismFamily) {
  EXPECT_NEAR(bestPrismFamilyRatio(1.0, 4), 4.0 / kPi, 1e-9);
  EXPECT_NEAR(bestPrismFamilyRatio(1.0, 8), 8.0 * std::tan(kPi / 8.0) / kPi, 1e-9);
  // Under the sanitizers one length only (the fit's code paths are the same for each).
  const std::vector<double> lengths =
      kccd::testing::kSanitized ? std::vector<double>{1.0} : std::vector<double>{0.5, 1.0, 3.0};
  for (const double h : lengths) {
    km::Part cylinder;  // radius 1 along y
    cylinder.addCylinderY(Eigen::Affine3d::Identity(), 1.0, 2.0 * h);
    // Under the sanitizers K = 8 only (K = 16 takes the same paths with twice the points).
    for (const int k : kccd::testing::kSanitized ? std::vector<int>{8} : std::vector<int>{8, 16}) {
      const km::FitResult f = km::fit(cylinder, {.points = k});
      const double ratio = f.volume / (2.0 * kPi * h), family = bestPrismFamilyRatio(h, k / 2);
      RecordProperty("h" + std::to_string(h) + "_k" + std::to_string(k), std::to_string(ratio));
      // Measured: K = 8 within 0.1 % of the family's best, K = 16 within 4.3 %.
      EXPECT_LE(ratio, (k == 8 ? 1.01 : 1.05) * family)
          << "half-length " << h << ", K = " << k << ", family " << family;
      expectContains(f, cylinder, {}, "cylinder");
    }
  }
}

// The exact hull as an SSCH: every hull vertex, a radius of rounding only, and still every point
// of the part inside (balls through their circumscribed polytopes, checked on the true spheres).
TEST(Fit, ExactHullContainsThePartAndAddsOnlyRounding) {
  std::mt19937_64 rng(11);
  km::Part part;
  part.addBox(Eigen::Affine3d(Eigen::Translation3d(0.1, 0, 0)), Vec3(0.4, 0.2, 0.1));
  const Eigen::Affine3d ball_pose(Eigen::Translation3d(-0.2, 0.05, 0.02));
  part.addSphere(ball_pose, 0.08);
  part.addCylinderY(Eigen::Affine3d(Eigen::Translation3d(0.3, 0, 0)), 0.06, 0.3);
  Truth truth;
  truth.sphere(ball_pose, 0.08, rng);
  truth.circle(Eigen::Affine3d(Eigen::Translation3d(0.3, 0, 0)), 0.06, 0.15, rng);
  truth.circle(Eigen::Affine3d(Eigen::Translation3d(0.3, 0, 0)), 0.06, -0.15, rng);
  const km::FitResult h = km::exactHull(part);
  km::Part without_balls = part;  // the ball is checked on its true surface (truth), not as a ball
  without_balls.balls.clear();
  expectContains(h, without_balls, truth, "exact hull");
  EXPECT_EQ(static_cast<int>(h.points.size()), h.hull_vertices);
  EXPECT_LT(h.radius, 1e-9);  // analytic input: rounding only
  // Above the hull of the sampled surface only by the ball's circumscribed polytope.
  EXPECT_GE(h.volume, h.hull_volume * (1.0 - 1e-9));
  EXPECT_LT(h.volume, 1.05 * h.hull_volume);
  const km::FitResult f = km::fit(part, quick(16));  // a fit is larger
  EXPECT_GT(f.volume, h.volume);
  EXPECT_THROW(km::exactHull(km::Part{}), std::invalid_argument);
}

TEST(ReadPart, InventorPrimitivesAreCoveredAnalytically) {
  const km::Part cyl = km::readPart(kModels + "simple/cylinder.iv");
  EXPECT_EQ(cyl.triangles, 0);
  EXPECT_EQ(cyl.primitives, 1);
  const km::Part sphere = km::readPart(kModels + "simple/sphere.iv");
  ASSERT_EQ(sphere.balls.size(), 1u);
  EXPECT_NEAR(sphere.balls[0].radius, 1.0, 1e-9);
  // Coin's default cylinder: radius 1, height 2 along y. Its true rim must be inside the fit.
  std::mt19937_64 rng(3);
  Truth truth;
  truth.circle(Eigen::Affine3d::Identity(), 1.0, -1.0, rng);
  truth.circle(Eigen::Affine3d::Identity(), 1.0, 1.0, rng);
  for (int k : {1, 4, 8}) expectContains(km::fit(cyl, quick(k)), cyl, truth, "cylinder.iv");
}

TEST(ReadPart, RealInventorModelsAreContained) {
  struct File {
    const char* path;
    bool merge;
  };
  for (const File& f :
       {File{"household/mug.iv", false}, File{"simple/cone.iv", false}, File{"robots/roboHand.iv", true},
        File{"machines/coarseGear.iv", true}, File{"toys/top.iv", true}}) {
    if (!std::filesystem::exists(kModels + f.path)) GTEST_SKIP() << "inventor-data not installed";
    const km::Part part = km::readPart(kModels + f.path, {.merge = f.merge});
    EXPECT_GT(part.triangles + part.primitives, 0) << f.path;
    // Under the sanitizers each file is read and fitted once with K = 1, and K = 8 only for the
    // first (the reader is what differs between the files; the fit's paths are the same).
    const bool first = std::string(f.path) == "household/mug.iv";
    for (int k : {1, 8})
      if (!kccd::testing::kSanitized || k == 1 || first) expectContains(km::fit(part, quick(k)), part, {}, f.path);
  }
}

TEST(ReadPart, VrmlStlAndBinaryInventor) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kccd_test_fit";
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "part.wrl")
        << "#VRML V2.0 utf8\n"
           "Transform { translation 1 0 0 children [\n"
           "  Shape { geometry Sphere { radius 0.5 } }\n"
           "  Transform { translation 0 2 0 children Shape { geometry Box { size 1 1 1 } } }\n"
           "  Shape { geometry Cylinder { radius 0.2 height 3 } }\n"
           "] }\n";
  }
  const km::Part vrml = km::readPart((dir / "part.wrl").string());
  ASSERT_EQ(vrml.balls.size(), 1u);
  EXPECT_NEAR((vrml.balls[0].center - Vec3(1, 0, 0)).norm(), 0.0, 1e-6);
  EXPECT_EQ(vrml.primitives, 2);  // sphere and cylinder; the box comes as 12 triangles
  EXPECT_EQ(vrml.triangles, 12);
  std::mt19937_64 rng(5);
  Truth truth;
  truth.circle(Eigen::Affine3d(Eigen::Translation3d(1, 0, 0)), 0.2, 1.5, rng);
  expectContains(km::fit(vrml, quick(6)), vrml, truth, "VRML");

  // The binary robot files of inventor-data read like the ASCII ones.
  if (std::filesystem::exists(kModels + "robots/cylMan.iv")) {
    const km::Part binary = km::readPart(kModels + "robots/cylMan.iv", {.merge = true});
    EXPECT_GT(binary.primitives, 5);
  }
  {
    std::ofstream(dir / "tet.stl")
        << "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
           "   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n"
           "   vertex 0 0 0\n   vertex 0 1 0\n   vertex 0 0 1\n  endloop\n endfacet\nendsolid t\n";
  }
  const km::Part stl = km::readPart((dir / "tet.stl").string());
  EXPECT_EQ(stl.triangles, 2);
  expectContains(km::fit(stl, quick(4)), stl, {}, "STL");
}

TEST(ReadPart, ClearErrors) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kccd_test_fit";
  std::filesystem::create_directories(dir);
  auto message = [](const std::string& path, km::ReadOptions o = {}) {
    try {
      km::readPart(path, o);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message((dir / "missing.iv").string()).find("cannot open"), std::string::npos);
  std::ofstream(dir / "garbage.iv") << "this is not a scene graph {{{\n";
  EXPECT_NE(message((dir / "garbage.iv").string()).find("not a readable"), std::string::npos);
  std::ofstream(dir / "empty.iv") << "#Inventor V2.1 ascii\n";
  EXPECT_NE(message((dir / "empty.iv").string()).find("no triangles"), std::string::npos);
  std::ofstream(dir / "lines.iv") << "#Inventor V2.1 ascii\nSeparator { Coordinate3 { point [0 0 0, 1 0 0] }"
                                     " LineSet { numVertices 2 } }\n";
  EXPECT_NE(message((dir / "lines.iv").string()).find("no triangles"), std::string::npos);
  std::ofstream(dir / "two.iv") << "#Inventor V2.1 ascii\nDEF first Separator { Cube {} }\n"
                                   "DEF second Separator { Translation { translation 5 0 0 } Sphere {} }\n";
  const std::string two = message((dir / "two.iv").string());
  EXPECT_NE(two.find("2 top-level parts (first, second)"), std::string::npos) << two;
  const km::Part second = km::readPart((dir / "two.iv").string(), {.part = "second"});
  ASSERT_EQ(second.balls.size(), 1u);
  EXPECT_NEAR(second.balls[0].center.x(), 5.0, 1e-6);  // the translation before it is applied
  EXPECT_EQ(km::readPart((dir / "two.iv").string(), {.merge = true}).primitives, 1);
  EXPECT_NE(message((dir / "two.iv").string(), {.part = "third"}).find("no node named 'third'"), std::string::npos);
}

TEST(ConvexHull, DimensionsAndVertices) {
  std::vector<Vec3> pts{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(0.1, 0.1, 0.1)};
  km::ConvexHull h = km::convexHull(pts);
  EXPECT_EQ(h.dimension, 3);
  EXPECT_EQ(h.vertices.size(), 4u);
  EXPECT_NEAR(h.volume, 1.0 / 6.0, 1e-12);
  pts = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0)};
  h = km::convexHull(pts);
  EXPECT_EQ(h.dimension, 1);
  pts = {Vec3(3, 3, 3), Vec3(3, 3, 3)};
  EXPECT_EQ(km::convexHull(pts).dimension, 0);
}
