// ns per distance call for separated, near-touching and overlapping pairs, with FCL 0.7's GJK on
// the same convex point sets in the same run when FCL is available.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "kccd/distance.hpp"

#ifdef KCCD_BENCH_WITH_FCL
#include <fcl/geometry/shape/convex.h>
#include <fcl/narrowphase/distance.h>
extern "C" {
#include <libqhull_r/qhull_ra.h>
}
#endif

namespace {

using kccd::Vec3;
using Points = std::vector<Vec3>;

enum Regime { kSeparated = 0, kNearTouching = 1, kOverlapping = 2 };
constexpr int kPairs = 64;

// Points on a random ellipsoid's surface: every point is a hull vertex.
Points ellipsoidPoints(std::mt19937_64& rng, int n, const Vec3& centre) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.3, 1.0);
  const Vec3 axes(u(rng), u(rng), u(rng));
  const Eigen::Matrix3d rot = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  Points pts;
  for (int i = 0; i < n; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    d.normalize();
    pts.push_back(centre + rot * axes.cwiseProduct(d));
  }
  return pts;
}

struct PairSet {
  std::vector<Points> a, b;
};

// Pairs whose hull distance is ~0.5 (separated), ~1e-4 (near touching) or < 0 (overlapping).
const PairSet& pairs(int regime, int n) {
  static std::vector<std::unique_ptr<PairSet>> cache(3 * 65);
  auto& slot = cache[regime * 65 + n];
  if (slot) return *slot;
  slot = std::make_unique<PairSet>();
  std::mt19937_64 rng(1000 + regime * 100 + n);
  std::normal_distribution<double> g;
  while (static_cast<int>(slot->a.size()) < kPairs) {
    Points a = ellipsoidPoints(rng, n, Vec3::Zero());
    Vec3 dir(g(rng), g(rng), g(rng));
    dir.normalize();
    Points b = ellipsoidPoints(rng, n, Vec3::Zero());
    // Both ellipsoids contain the ball of radius 0.3 about their centre: an offset of 0.3 overlaps.
    double offset = 0.3;
    if (regime != kOverlapping) {
      // The hull distance is convex and non-decreasing in the offset: bisect for the target.
      const double target = regime == kSeparated ? 0.5 : 1e-4;
      double lo = 0.0, hi = 4.0;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        Points moved = b;
        for (Vec3& p : moved) p += mid * dir;
        (kccd::distance({a, 0.0}, {moved, 0.0}).hull_upper < target ? lo : hi) = mid;
      }
      offset = hi;
    }
    for (Vec3& p : b) p += offset * dir;
    slot->a.push_back(std::move(a));
    slot->b.push_back(std::move(b));
  }
  return *slot;
}

void BM_KccdGjk(benchmark::State& state) {
  const PairSet& ps = pairs(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::size_t i = 0;
  long iterations = 0;
  for (auto _ : state) {
    const auto r = kccd::distance({ps.a[i], 0.0}, {ps.b[i], 0.0});
    benchmark::DoNotOptimize(r);
    iterations += r.iterations;
    i = (i + 1) % ps.a.size();
  }
  // GJK iterations per call (each makes one support call per set).
  state.counters["iterations"] =
      benchmark::Counter(static_cast<double>(iterations), benchmark::Counter::kAvgIterations);
  state.SetLabel(state.range(0) == kSeparated ? "separated" : state.range(0) == kNearTouching ? "near" : "overlap");
}

#ifdef KCCD_BENCH_WITH_FCL
std::shared_ptr<fcl::Convexd> makeConvex(const Points& pts) {
  auto verts = std::make_shared<std::vector<fcl::Vector3d>>(pts.begin(), pts.end());
  std::vector<double> coords;
  for (const Vec3& p : pts) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, stderr);
  char options[] = "qhull Qt";
  auto faces = std::make_shared<std::vector<int>>();
  int count = 0;
  if (qh_new_qhull(qh, 3, static_cast<int>(pts.size()), coords.data(), False, options, nullptr, stderr) == 0) {
    facetT* facet;
    vertexT *vertex, **vertexp;
    FORALLfacets {
      faces->push_back(qh_setsize(qh, facet->vertices));
      FOREACHvertex_(facet->vertices) faces->push_back(qh_pointid(qh, vertex->point));
      ++count;
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return std::make_shared<fcl::Convexd>(verts, count, faces);
}

void BM_FclGjk(benchmark::State& state, fcl::GJKSolverType solver) {
  const PairSet& ps = pairs(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::vector<std::shared_ptr<fcl::Convexd>> ca, cb;
  for (std::size_t k = 0; k < ps.a.size(); ++k) {
    ca.push_back(makeConvex(ps.a[k]));
    cb.push_back(makeConvex(ps.b[k]));
  }
  fcl::DistanceRequestd request;
  request.enable_nearest_points = true;
  request.gjk_solver_type = solver;
  const fcl::Transform3d id = fcl::Transform3d::Identity();
  std::size_t i = 0;
  for (auto _ : state) {
    fcl::DistanceResultd result;
    benchmark::DoNotOptimize(fcl::distance(ca[i].get(), id, cb[i].get(), id, request, result));
    i = (i + 1) % ca.size();
  }
}
void BM_FclGjkLibccd(benchmark::State& state) { BM_FclGjk(state, fcl::GST_LIBCCD); }
void BM_FclGjkIndep(benchmark::State& state) { BM_FclGjk(state, fcl::GST_INDEP); }
#endif

void Args(benchmark::internal::Benchmark* b) {
  for (int regime : {kSeparated, kNearTouching, kOverlapping})
    for (int n : {4, 8, 16, 64}) b->Args({regime, n});
  b->ArgNames({"regime", "points"});
}

}  // namespace

BENCHMARK(BM_KccdGjk)->Apply(Args);
#ifdef KCCD_BENCH_WITH_FCL
BENCHMARK(BM_FclGjkLibccd)->Apply(Args);
BENCHMARK(BM_FclGjkIndep)->Apply(Args);
#endif
BENCHMARK_MAIN();
