// Engine benchmarks on the sample robots with typical braking intervals (2-20 degrees per joint):
// - time per query type and sweep mode (cold: no reuse; warm: a moving robot reusing its table),
//   median and 99.9th percentile of single queries;
// (the accuracy of each sweep mode and budget, against searched true minima: bench_trade);
// - side by side: FCL checking the same volumes at 10 configurations sampled along the interval
//   (what users do today), its time and the collisions it misses.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "kccd/checker.hpp"
#include "kccd/distance.hpp"

#ifdef KCCD_BENCH_WITH_FCL
#include <fcl/geometry/shape/convex.h>
#include <fcl/narrowphase/distance.h>
#endif

namespace {

using namespace kccd;
using Clock = std::chrono::steady_clock;
constexpr double kDeg = 3.141592653589793 / 180.0;

const char* kScenes[] = {"humanoid", "industrial_cell"};

struct Boxes {
  std::vector<std::vector<double>> lower, upper;
};

// The model with every revolute/prismatic joint set to `mode`.
std::shared_ptr<const Model> sceneModel(int scene, SweepMode mode) {
  static std::map<std::pair<int, int>, std::shared_ptr<const Model>> cache;
  auto& slot = cache[{scene, static_cast<int>(mode)}];
  if (!slot) {
    auto m = std::make_shared<Model>(loadModel(std::string(KCCD_DATA_DIR) + "/" + kScenes[scene] + ".yaml"));
    for (Joint& j : m->joints)
      if (j.type != JointType::Fixed) j.sweep = mode;
    if (const char* budget = std::getenv("KCCD_BENCH_BUDGET")) m->point_budget = std::atoi(budget);
    slot = m;
  }
  return slot;
}

// A random configuration inside the joint limits, and a braking box around it.
void randomBox(std::mt19937_64& rng, const Model& m, bool point, std::vector<double>& lo, std::vector<double>& hi,
               const std::vector<double>* previous_centre = nullptr, std::vector<double>* centre_out = nullptr) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  lo.assign(m.stateSize(), 0.0);
  hi.assign(m.stateSize(), 0.0);
  std::vector<double> centre(m.stateSize());
  for (const Joint& j : m.joints) {
    for (int k = 0; k < j.dof; ++k) {
      const int s = j.state_offset + k;
      double c = 0.0, width = 0.0;
      if (j.type == JointType::Revolute) {
        const double a = j.limits ? (*j.limits)[0] : -3.0, b = j.limits ? (*j.limits)[1] : 3.0;
        c = a + (b - a) * u(rng);
        width = (2.0 + 18.0 * u(rng)) * kDeg;
      } else if (j.type == JointType::Translation3d) {  // the cable robot's workspace
        const double lo_ws[3] = {1.0, -1.0, 1.2}, hi_ws[3] = {2.2, 1.0, 2.0};
        c = lo_ws[k] + (hi_ws[k] - lo_ws[k]) * u(rng);
        width = 0.01 + 0.04 * u(rng);
      } else if (j.type == JointType::Rotation3d) {
        c = (u(rng) - 0.5) * 2.0;
        width = 2.0 * kDeg * u(rng);
      } else {
        c = 0.1 * u(rng);
        width = 0.02 * u(rng);
      }
      if (previous_centre != nullptr) c = (*previous_centre)[s] + (u(rng) - 0.5) * 0.5 * kDeg;  // one cycle later
      centre[s] = c;
      if (point) width = 0.0;
      lo[s] = c - 0.5 * width;
      hi[s] = c + 0.5 * width;
    }
  }
  if (centre_out != nullptr) *centre_out = centre;
}

const Boxes& boxes(int scene, bool point, bool trajectory) {
  static std::map<std::tuple<int, bool, bool>, Boxes> cache;
  Boxes& b = cache[{scene, point, trajectory}];
  if (!b.lower.empty()) return b;
  std::mt19937_64 rng(42 + scene);
  const Model& m = *sceneModel(scene, SweepMode::Accurate);
  // Robots spend their time clear of collisions: the boxes surround configurations whose static
  // clearance exceeds the safety margin by 5 mm (rejection sampling over the joint limits).
  Checker statics(*sceneModel(scene, SweepMode::Exact));
  QueryOptions all;
  all.type = QueryType::Distances;
  std::vector<double> centre;
  for (int i = 0; i < 256; ++i) {
    std::vector<double> lo, hi, next;
    int tries = 0;
    do {
      if (++tries > 100000) {
        std::fprintf(stderr, "bench_engine: no configuration clear of the margin found for %s\n", kScenes[scene]);
        std::exit(1);
      }
      randomBox(rng, m, point, lo, hi, trajectory && i > 0 && tries < 1000 ? &centre : nullptr, &next);
      statics.reset();
    } while (statics.query(next, next, all).min_distance < m.safety_margin + 0.005);
    centre = next;
    b.lower.push_back(lo);
    b.upper.push_back(hi);
  }
  return b;
}

void report(benchmark::State& state, std::vector<double>& us) {
  std::sort(us.begin(), us.end());
  if (us.empty()) return;
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99.9_us"] = us[std::min(us.size() - 1, static_cast<std::size_t>(0.999 * us.size()))];
  state.counters["max_us"] = us.back();
}

// Args: scene, mode (0 exact/static, 1 accurate), query type, warm (reuse across cycles).
void BM_Query(benchmark::State& state) {
  const int scene = static_cast<int>(state.range(0));
  const auto mode = static_cast<SweepMode>(state.range(1));
  const auto type = static_cast<QueryType>(state.range(2));
  const bool warm = state.range(3) != 0;
  const auto model = sceneModel(scene, mode);
  const Boxes& bx = boxes(scene, mode == SweepMode::Exact, warm);
  Checker checker(*model);
  QueryOptions opt;
  opt.type = type;
  opt.n = 5;
  std::vector<double> us;
  us.reserve(1 << 22);
  std::size_t i = 0;
  long collisions = 0;
  for (auto _ : state) {
    if (!warm) checker.reset();
    const auto t0 = Clock::now();
    const QueryResult& r = checker.query(bx.lower[i], bx.upper[i], opt);
    const double t = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    benchmark::DoNotOptimize(r.min_distance);
    collisions += r.collision ? 1 : 0;
    state.SetIterationTime(t * 1e-6);
    if (us.size() < us.capacity()) us.push_back(t);
    i = (i + 1) % bx.lower.size();
  }
  report(state, us);
  state.counters["collision_rate"] = static_cast<double>(collisions) / static_cast<double>(state.iterations());
  state.SetLabel(std::string(kScenes[scene]) + " " + toString(mode) + " " + toString(type) +
                 (warm ? " warm" : " cold"));
}

// Dense sampling of a box with exact (point) queries: per pair, the smallest distance seen.
std::vector<double> sampledMinimum(const Model& exact_model, const std::vector<double>& lo,
                                   const std::vector<double>& hi, int samples, std::mt19937_64& rng) {
  Checker exact(exact_model);
  QueryOptions opt;
  opt.type = QueryType::Distances;
  std::vector<double> best(exact_model.pairs.size(), std::numeric_limits<double>::infinity());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> q(lo.size());
  for (int s = 0; s < samples; ++s) {
    for (std::size_t k = 0; k < q.size(); ++k) {
      const double t = s % 2 == 0 ? (u(rng) < 0.5 ? 0.0 : 1.0) : u(rng);  // corners and interior
      q[k] = lo[k] + t * (hi[k] - lo[k]);
    }
    exact.reset();
    const QueryResult& r = exact.query(q, q, opt);
    for (const PairDistance& pd : r.pairs) best[pd.pair] = std::min(best[pd.pair], pd.distance);
  }
  return best;
}

#ifdef KCCD_BENCH_WITH_FCL
// FCL on the same volumes: hull distance minus both radii at 10 configurations evenly spaced
// from the lower to the upper end of the box, stopping at the first pair within the margin.
struct FclScene {
  std::vector<std::shared_ptr<fcl::Convexd>> shapes;
};

const FclScene& fclScene(int scene) {
  static std::map<int, FclScene> cache;
  FclScene& f = cache[scene];
  if (!f.shapes.empty()) return f;
  const Model& m = *sceneModel(scene, SweepMode::Exact);
  for (const Body& b : m.bodies) {
    auto verts = std::make_shared<std::vector<fcl::Vector3d>>(b.points.begin(), b.points.end());
    f.shapes.push_back(std::make_shared<fcl::Convexd>(verts, 0, std::make_shared<std::vector<int>>()));
  }
  return f;
}

std::vector<Pose> framePoses(const Model& m, const std::vector<double>& q) {
  std::vector<Pose> world(m.joints.size());
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    const Joint& j = m.joints[i];
    Pose motion = Pose::Identity();
    const double* v = q.data() + j.state_offset;
    if (j.type == JointType::Revolute) motion.linear() = Eigen::AngleAxisd(v[0], j.axis).toRotationMatrix();
    if (j.type == JointType::Prismatic) motion.translation() = v[0] * j.axis;
    if (j.type == JointType::Translation3d) motion.translation() = Vec3(v[0], v[1], v[2]);
    if (j.type == JointType::Rotation3d) {
      const Vec3 w(v[0], v[1], v[2]);
      if (w.norm() > 0) motion.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    }
    world[i] = (j.parent == kWorld ? Pose::Identity() : world[j.parent]) * j.origin * motion;
  }
  return world;
}

// True when FCL sees some pair within the margin at one of the 10 sampled configurations.
bool fclSampledCollision(int scene, const std::vector<double>& lo, const std::vector<double>& hi) {
  const Model& m = *sceneModel(scene, SweepMode::Exact);
  const FclScene& f = fclScene(scene);
  fcl::DistanceRequestd request;
  std::vector<double> q(lo.size());
  for (int k = 0; k < 10; ++k) {
    for (std::size_t s = 0; s < q.size(); ++s) q[s] = lo[s] + (hi[s] - lo[s]) * k / 9.0;
    const std::vector<Pose> poses = framePoses(m, q);
    for (const BodyPair& p : m.pairs) {
      const Body& a = m.bodies[p.a];
      const Body& b = m.bodies[p.b];
      const fcl::Transform3d ta =
          a.frame == kWorld ? fcl::Transform3d::Identity() : fcl::Transform3d(poses[a.frame].matrix());
      const fcl::Transform3d tb =
          b.frame == kWorld ? fcl::Transform3d::Identity() : fcl::Transform3d(poses[b.frame].matrix());
      fcl::DistanceResultd result;
      const double d = fcl::distance(f.shapes[p.a].get(), ta, f.shapes[p.b].get(), tb, request, result);
      if (d - a.radius - b.radius <= m.safety_margin) return true;
    }
  }
  return false;
}

void BM_FclSampled10(benchmark::State& state) {
  const int scene = static_cast<int>(state.range(0));
  const Boxes& bx = boxes(scene, false, false);
  std::vector<double> us;
  us.reserve(1 << 20);
  std::size_t i = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(fclSampledCollision(scene, bx.lower[i], bx.upper[i]));
    const double t = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    state.SetIterationTime(t * 1e-6);
    us.push_back(t);
    i = (i + 1) % bx.lower.size();
  }
  report(state, us);
  state.SetLabel(std::string(kScenes[scene]) + " FCL, 10 samples per interval");
}

// Collisions missed: boxes where dense sampling finds a pair within the margin.
void BM_MissedCollisions(benchmark::State& state) {
  const int scene = static_cast<int>(state.range(0));
  const auto exact_model = sceneModel(scene, SweepMode::Exact);
  const auto model = sceneModel(scene, SweepMode::Accurate);
  long real = 0, fcl_missed = 0, kccd_missed = 0, kccd_false_alarms = 0, boxes_checked = 0;
  for (auto _ : state) {
    std::mt19937_64 rng(11);
    for (int i = 0; i < 200; ++i) {
      // Wider intervals than typical (fast motions) make the difference visible.
      std::vector<double> lo, hi;
      randomBox(rng, *model, false, lo, hi);
      for (std::size_t s = 0; s < lo.size(); ++s) {
        const double c = 0.5 * (lo[s] + hi[s]), w = 3.0 * (hi[s] - lo[s]);
        lo[s] = c - 0.5 * w;
        hi[s] = c + 0.5 * w;
      }
      const std::vector<double> truth = sampledMinimum(*exact_model, lo, hi, 600, rng);
      const bool collides = *std::min_element(truth.begin(), truth.end()) <= exact_model->safety_margin;
      Checker checker(*model);
      const bool kccd_says = checker.query(lo, hi).collision;
      const bool fcl_says = fclSampledCollision(scene, lo, hi);
      ++boxes_checked;
      if (collides) {
        ++real;
        fcl_missed += fcl_says ? 0 : 1;
        kccd_missed += kccd_says ? 0 : 1;
      } else {
        kccd_false_alarms += kccd_says ? 1 : 0;
      }
    }
  }
  state.counters["boxes"] = static_cast<double>(boxes_checked);
  state.counters["real_collisions"] = static_cast<double>(real);
  state.counters["fcl10_missed"] = static_cast<double>(fcl_missed);
  state.counters["kccd_missed"] = static_cast<double>(kccd_missed);
  state.counters["kccd_extra_stops"] = static_cast<double>(kccd_false_alarms);
  state.SetLabel(kScenes[scene]);
}
#endif

void QueryArgs(benchmark::internal::Benchmark* b) {
  for (int scene : {0, 1})
    for (int mode : {0, 1})  // SweepMode: exact (point state), accurate
      for (int type : {0, 1, 2, 3})
        for (int warm : {0, 1}) b->Args({scene, mode, type, warm});
  b->ArgNames({"scene", "mode", "type", "warm"});
}

}  // namespace

BENCHMARK(BM_Query)->Apply(QueryArgs)->UseManualTime()->MinTime(0.3);
#ifdef KCCD_BENCH_WITH_FCL
BENCHMARK(BM_FclSampled10)->Arg(0)->Arg(1)->ArgName("scene")->UseManualTime()->MinTime(0.3);
BENCHMARK(BM_MissedCollisions)->Arg(0)->Arg(1)->ArgName("scene")->Iterations(1);
#endif
BENCHMARK_MAIN();
