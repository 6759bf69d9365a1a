// Renderer benchmarks: ms per frame at 1280x720 for the humanoid through a camera with mild lens
// distortion, including the query, mesh building, drawing, read-back, distortion warp and
// straight-alpha conversion.
// - Static/fixed:  the same state every frame (every mesh comes from the cache);
// - Static/moving: a new state every frame (every moving body's mesh is rebuilt);
// - Swept:         a new braking box every frame (2-20 degrees per joint), swept volumes;
// each for the colour layer alone and for colour + label mask.
// - Swept_HullMeshing: Swept with the previous mesh construction (qhull over circumscribed
//   sphere polytopes around every core point), for comparison in the same run.
// Run with --benchmark_repetitions=5 and read the medians.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "kccd/checker.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "support/cameras.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
constexpr double kDeg = 3.141592653589793 / 180.0;

const Model& humanoid() {
  static const Model m = loadModel(std::string(KCCD_DATA_DIR) + "/humanoid.yaml");
  return m;
}

Camera benchCamera() {
  // 3.2 m in front and to the side of the humanoid, looking at its chest.
  return kccd::testing::hdCamera(Vec3(3.0, -1.2, 1.6), Vec3(0.0, 0.0, 1.1));
}

// Boxes around random states within the joint limits; width 0 for static frames.
std::vector<std::pair<std::vector<double>, std::vector<double>>> boxes(bool swept) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Model& m = humanoid();
  std::vector<std::pair<std::vector<double>, std::vector<double>>> out;
  for (int i = 0; i < 4096; ++i) {
    std::vector<double> lo(m.stateSize()), hi(m.stateSize());
    for (const Joint& j : m.joints)
      for (int k = 0; k < j.dof; ++k) {
        const int s = j.state_offset + k;
        const double a = j.limits ? (*j.limits)[0] : -1.0, b = j.limits ? (*j.limits)[1] : 1.0;
        const double c = a + (b - a) * (0.25 + 0.5 * u(rng));
        const double w = swept ? (2.0 + 18.0 * u(rng)) * kDeg : 0.0;
        lo[s] = c - 0.5 * w;
        hi[s] = c + 0.5 * w;
      }
    out.emplace_back(lo, hi);
  }
  return out;
}

// Knobs for profiling: KCCD_BENCH_MSAA, KCCD_BENCH_SUPERSAMPLE, KCCD_BENCH_TOLERANCE_PX.
RenderOptions benchOptions() {
  RenderOptions o;
  if (const char* v = std::getenv("KCCD_BENCH_MSAA")) o.msaa_samples = std::atoi(v);
  if (const char* v = std::getenv("KCCD_BENCH_SUPERSAMPLE")) o.supersample = std::atof(v);
  if (const char* v = std::getenv("KCCD_BENCH_TOLERANCE_PX")) o.tolerance_px = std::atof(v);
  return o;
}

// One renderer per mesh construction, made on first use.
Renderer& renderer(SschMeshing meshing) {
  static Renderer direct(benchCamera(), benchOptions());
  if (meshing == SschMeshing::Direct) return direct;
  static Renderer hull(benchCamera(), [] {
    RenderOptions o = benchOptions();
    o.meshing = SschMeshing::Hull;
    return o;
  }());
  return hull;
}

void frame(benchmark::State& state, bool swept, bool moving, bool mask, SschMeshing meshing = SschMeshing::Direct) {
  const Model& m = humanoid();
  Renderer& r = renderer(meshing);
  Checker checker(m);
  static const auto static_list = boxes(false), swept_list = boxes(true);
  const auto& list = swept ? swept_list : static_list;
  static std::size_t i = 0;  // continues across runs, so repeated runs do not revisit cached shapes
  double triangles = 0, built = 0, frames = 0, hull_input = 0, level = 0;
  for (auto _ : state) {
    const auto& [lo, hi] = list[moving ? i++ % list.size() : 0];
    const QueryResult& q = checker.query(lo, hi, QueryOptions{.type = QueryType::Distances});
    const std::vector<Volume> volumes =
        swept ? sceneVolumes(m, checker, bodyStatus(m, q)) : staticSceneVolumes(m, checker, lo, bodyStatus(m, q));
    const Frame f = r.render(volumes, Style{}, true, mask);
    benchmark::DoNotOptimize(f.bgra.data);
    triangles += f.triangles;
    built += f.meshes_built;
    hull_input += f.hull_input;
    level = std::max(level, static_cast<double>(f.max_level));
    ++frames;
  }
  state.counters["triangles"] = triangles / frames;
  state.counters["meshes_built"] = built / frames;
  state.counters["bodies"] = static_cast<double>(m.bodies.size());
  state.counters["qhull_points"] = hull_input / frames;
  state.counters["max_level"] = level;
}

void BM_Static_Fixed(benchmark::State& s) { frame(s, false, false, s.range(0) != 0); }
void BM_Static_Moving(benchmark::State& s) { frame(s, false, true, s.range(0) != 0); }
void BM_Swept(benchmark::State& s) { frame(s, true, true, s.range(0) != 0); }
void BM_Swept_HullMeshing(benchmark::State& s) { frame(s, true, true, s.range(0) != 0, SschMeshing::Hull); }

// One swept volume's mesh alone (core points of the humanoid's swept volumes: a few tens), built
// directly (arg 0) or by the previous qhull construction (arg 1); level 3.
void BM_SweptMesh(benchmark::State& state) {
  const Model& m = humanoid();
  Checker checker(m);
  const auto list = boxes(true);
  std::vector<std::pair<std::vector<Vec3>, double>> volumes;
  for (int k = 0; k < 8; ++k) {
    const auto& [lo, hi] = list[static_cast<std::size_t>(k)];
    const QueryResult& q = checker.query(lo, hi, QueryOptions{.type = QueryType::Distances});
    for (const Volume& v : sceneVolumes(m, checker, bodyStatus(m, q)))
      volumes.emplace_back(std::vector<Vec3>(v.points.begin(), v.points.end()), v.radius);
  }
  const SschMeshing meshing = state.range(0) != 0 ? SschMeshing::Hull : SschMeshing::Direct;
  std::size_t i = 0;
  double points = 0, n = 0;
  for (auto _ : state) {
    const auto& [points_of, radius] = volumes[i++ % volumes.size()];
    const Mesh mesh = buildSschMesh(points_of, radius, 3, kMinDrawRadius, meshing);
    benchmark::DoNotOptimize(mesh.triangles.data());
    points += static_cast<double>(points_of.size());
    ++n;
  }
  state.counters["core_points"] = points / n;
}
BENCHMARK(BM_SweptMesh)->ArgName("hull")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

BENCHMARK(BM_Static_Fixed)->ArgName("mask")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Static_Moving)->ArgName("mask")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Swept)->ArgName("mask")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Swept_HullMeshing)->ArgName("mask")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
