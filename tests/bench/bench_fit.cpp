// Fitting speed: seconds per part for K core points, on a generated 10,000-triangle part (in
// memory and read from a binary STL) and on real Open Inventor models; pairs proofs per model.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <random>

#include <benchmark/benchmark.h>

#include "kccd/checker.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "robots.hpp"

namespace km = kccd::modelling;
using kccd::Vec3;

namespace {

// A bumpy ellipsoid as a 50 x 100 latitude-longitude mesh: 9,800 triangles + 2 caps of 100.
std::vector<std::array<Vec3, 3>> bumpyTriangles() {
  const int rows = 50, cols = 100;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> noise(-0.01, 0.01);
  std::vector<std::vector<Vec3>> v(rows + 1, std::vector<Vec3>(cols));
  for (int i = 0; i <= rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double th = std::numbers::pi * i / rows, ph = 2 * std::numbers::pi * j / cols;
      const double r = 1.0 + 0.1 * std::sin(5 * ph) * std::sin(3 * th) + noise(rng);
      v[i][j] =
          Vec3(0.3 * r * std::sin(th) * std::cos(ph), 0.15 * r * std::sin(th) * std::sin(ph), 0.1 * r * std::cos(th));
    }
  std::vector<std::array<Vec3, 3>> t;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const int k = (j + 1) % cols;
      t.push_back({v[i][j], v[i + 1][j], v[i + 1][k]});
      t.push_back({v[i][j], v[i + 1][k], v[i][k]});
    }
  return t;  // 10,000 triangles
}

km::Part bumpyPart() {
  km::Part p;
  for (const auto& t : bumpyTriangles()) p.points.insert(p.points.end(), t.begin(), t.end());
  p.triangles = static_cast<int>(p.points.size() / 3);
  return p;
}

std::string bumpyStl() {
  const std::string path = (std::filesystem::temp_directory_path() / "kccd_bench_bumpy.stl").string();
  const auto tris = bumpyTriangles();
  std::ofstream out(path, std::ios::binary);
  char header[80] = "kccd benchmark part";
  out.write(header, 80);
  const std::uint32_t n = static_cast<std::uint32_t>(tris.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : tris) {
    float rec[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) rec[3 + 3 * k + c] = static_cast<float>(t[k](c));
    out.write(reinterpret_cast<const char*>(rec), 48);
    out.write("\0\0", 2);
  }
  return path;
}

void BM_Fit10kTriangles(benchmark::State& state) {
  const km::Part part = bumpyPart();
  km::FitResult r;
  for (auto _ : state) {
    r = km::fit(part, {.points = static_cast<int>(state.range(0))});
    benchmark::DoNotOptimize(r.radius);
  }
  state.counters["volume_ratio"] = r.volume / r.hull_volume;
  state.counters["hull_vertices"] = r.hull_vertices;
  state.counters["evaluations"] = r.evaluations;
}
BENCHMARK(BM_Fit10kTriangles)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

void BM_ReadAndFitStl10k(benchmark::State& state) {
  const std::string path = bumpyStl();
  for (auto _ : state) {
    const km::Part part = km::readPart(path);
    benchmark::DoNotOptimize(km::fit(part, {.points = 8}).radius);
  }
}
BENCHMARK(BM_ReadAndFitStl10k)->Unit(benchmark::kMillisecond);

// Reading alone: the 10,000-triangle part as binary STL, ASCII OBJ and ASCII PLY through Assimp,
// against a plain transcode of the STL's bytes into points (the work the earlier hand-written
// STL reader did) in the same run.
std::string bumpyText(const char* extension) {
  const std::string path =
      (std::filesystem::temp_directory_path() / (std::string("kccd_bench_bumpy") + extension)).string();
  const auto tris = bumpyTriangles();
  std::ofstream out(path);
  out.precision(9);
  if (std::string(extension) == ".ply")
    out << "ply\nformat ascii 1.0\nelement vertex " << 3 * tris.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << tris.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& t : tris)
    for (const Vec3& v : t) out << (extension[1] == 'o' ? "v " : "") << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (std::size_t i = 0; i < tris.size(); ++i)
    if (extension[1] == 'o')
      out << "f " << 3 * i + 1 << " " << 3 * i + 2 << " " << 3 * i + 3 << "\n";
    else
      out << "3 " << 3 * i << " " << 3 * i + 1 << " " << 3 * i + 2 << "\n";
  return path;
}

void BM_ReadMesh10k(benchmark::State& state, const char* extension) {
  const std::string path = std::string(extension) == ".stl" ? bumpyStl() : bumpyText(extension);
  int triangles = 0;
  for (auto _ : state) {
    const km::Part part = km::readPart(path);
    triangles = part.triangles;
    benchmark::DoNotOptimize(part.points.data());
  }
  state.counters["triangles"] = triangles;
}
BENCHMARK_CAPTURE(BM_ReadMesh10k, stl, ".stl")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMesh10k, obj, ".obj")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMesh10k, ply, ".ply")->Unit(benchmark::kMillisecond);

void BM_TranscodeStl10k(benchmark::State& state) {
  const std::string path = bumpyStl();
  for (auto _ : state) {
    const std::string data = km::readInputFile(path);
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    std::vector<Vec3> points;
    points.reserve(3 * n);
    for (std::uint32_t t = 0; t < n; ++t)
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, data.data() + 84 + 50ull * t + 12 + 12 * k, 12);
        points.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
    benchmark::DoNotOptimize(points.data());
  }
}
BENCHMARK(BM_TranscodeStl10k)->Unit(benchmark::kMillisecond);

void BM_FitInventorModel(benchmark::State& state, const char* file) {
  const std::string path = std::string("/usr/share/inventor/data/models/") + file;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("inventor-data not installed");
    return;
  }
  const km::Part part = km::readPart(path, {.merge = true});
  km::FitResult r;
  for (auto _ : state) r = km::fit(part, {.points = 8});
  state.counters["triangles"] = part.triangles;
  state.counters["volume_ratio"] = r.volume / r.hull_volume;
  state.counters["sphere_ratio"] = r.sphere_volume / r.hull_volume;
  state.counters["capsule_ratio"] = r.capsule_volume / r.hull_volume;
}
BENCHMARK_CAPTURE(BM_FitInventorModel, mug, "household/mug.iv")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FitInventorModel, roboHand, "robots/roboHand.iv")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FitInventorModel, coarseGear, "machines/coarseGear.iv")->Unit(benchmark::kMillisecond);

void BM_ProvePairs(benchmark::State& state, const char* file) {
  const kccd::Model m = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/" + file);
  std::vector<km::PairReport> r;
  for (auto _ : state) r = km::provePairs(m);
  int never = 0, touching = 0;
  for (const auto& p : r)
    never += p.verdict == km::Verdict::Never, touching += p.verdict == km::Verdict::AlwaysTouching;
  state.counters["pairs"] = static_cast<double>(r.size());
  state.counters["never"] = never;
  state.counters["always_touching"] = touching;
}
BENCHMARK_CAPTURE(BM_ProvePairs, demo_arm, "demo_arm.yaml")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ProvePairs, industrial_cell, "industrial_cell.yaml")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ProvePairs, humanoid, "humanoid.yaml")->Unit(benchmark::kMillisecond);

// What a fit costs in clearance: a robot imported twice from its URDF, once fitted with K core
// points per link and once with each link's exact convex hull (kccd import --hulls), every body
// pair queried at random configurations inside the joint limits (exact distances on both). The
// looseness of a pair is hull distance - SSCH distance (>= 0: the SSCH contains the hull); it is
// reported for pairs whose hulls are apart but within 0.1 m, for neighbouring-but-one links (two
// moving joints between them) and for all pairs (rigid and adjacent ones left out), as p50 / p90
// in mm. `violations` counts SSCH distances
// above the hull's (must be 0). Skipped without Debian's dart-doc (the KR5 and WAM URDFs).
int movingJointsBetween(const kccd::Model& m, int a, int b) {
  const int lca = m.commonAncestor(m.bodies[a].frame, m.bodies[b].frame);
  int n = 0;
  for (int body : {a, b})
    for (int f = m.bodies[body].frame; f != lca && f != kccd::kWorld; f = m.joints[f].parent)
      n += m.joints[f].type != kccd::JointType::Fixed;
  return n;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(p * v.size())))];
}

void BM_PairLooseness(benchmark::State& state, const char* urdf) {
  const std::string path = std::string("/usr/share/doc/dart/data/urdf/") + urdf;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("dart-doc not installed (apt-get install dart-doc)");
    return;
  }
  const int k = static_cast<int>(state.range(0));
  auto load = [&](bool hulls) {
    km::ImportOptions o;
    o.fit = {.method = hulls ? km::FitMethod::Hull : km::FitMethod::Points,
             .points = k,
             .max_pieces = 1};  // K points per link, whole
    o.visuals = false;
    o.packages["herb_description"] = std::filesystem::path(path).parent_path().string();
    kccd::Model m = kccd::parseModel(km::importUrdf(path, o), path);
    m.finalize(true, {}, {});  // every pair, ignored or not
    return m;
  };
  const kccd::Model fitted = load(false), hull = load(true);
  kccd::Checker cf(fitted), ch(hull);
  const auto ranges = km::jointRanges(fitted);
  std::mt19937_64 rng(3);
  std::vector<double> near_all, near_nb1, q(fitted.stateSize());
  int violations = 0, samples = 0;
  double fit_seconds = 0.0, hull_seconds = 0.0;
  const kccd::QueryOptions opt{.type = kccd::QueryType::Distances, .exact_below = INFINITY};
  for (auto _ : state) {
    for (int sample = 0; sample < 400; ++sample) {
      for (int s = 0; s < fitted.stateSize(); ++s)
        q[s] = std::uniform_real_distribution<double>(ranges[s][0], ranges[s][1])(rng);
      const auto t0 = std::chrono::steady_clock::now();
      const kccd::QueryResult& rf = cf.query(q, q, opt);
      const auto t1 = std::chrono::steady_clock::now();
      const std::vector<kccd::PairDistance> df(rf.pairs.begin(), rf.pairs.end());
      const auto t2 = std::chrono::steady_clock::now();
      const kccd::QueryResult& rh = ch.query(q, q, opt);
      const auto t3 = std::chrono::steady_clock::now();
      fit_seconds += std::chrono::duration<double>(t1 - t0).count();
      hull_seconds += std::chrono::duration<double>(t3 - t2).count();
      for (const kccd::PairDistance& h : rh.pairs) {
        const kccd::BodyPair& p = hull.pairs[h.pair];
        if (km::connection(hull, p.a, p.b) != km::Connection::Distant) continue;
        for (const kccd::PairDistance& f : df)
          if (fitted.pairs[f.pair].a == p.a && fitted.pairs[f.pair].b == p.b) {
            ++samples;
            violations += f.distance > h.distance + 1e-9;
            if (!(h.distance > 0.0 && h.distance <= 0.1)) continue;  // apart, and near
            near_all.push_back(1e3 * (h.distance - f.distance));
            if (movingJointsBetween(hull, p.a, p.b) == 2) near_nb1.push_back(1e3 * (h.distance - f.distance));
          }
      }
    }
  }
  state.counters["p50_mm"] = percentile(near_all, 0.5);
  state.counters["p90_mm"] = percentile(near_all, 0.9);
  state.counters["nb1_p50_mm"] = percentile(near_nb1, 0.5);
  state.counters["nb1_p90_mm"] = percentile(near_nb1, 0.9);
  state.counters["near_pairs"] = static_cast<double>(near_all.size());
  state.counters["samples"] = samples;
  state.counters["violations"] = violations;
  // What the hulls cost against the fit, in the same run: the exact all-pairs query's time.
  state.counters["fit_query_us"] = 1e6 * fit_seconds / 400.0;
  state.counters["hull_query_x"] = hull_seconds / fit_seconds;
}
BENCHMARK_CAPTURE(BM_PairLooseness, kr5, "KR5/KR5 sixx R650.urdf")
    ->Arg(8)
    ->Arg(12)
    ->Arg(16)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PairLooseness, wam, "wam/wam.urdf")
    ->Arg(8)
    ->Arg(12)
    ->Arg(16)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// What the import's defaults cost and buy (kccd import: each link within --tolerance of its hull,
// concave links in pieces) against the expert knob K = 8 and the exact hulls, on real robots, all
// measured in this run: per model the collision query (point states, the library's defaults) and
// the all-pairs distances query (exact) over the same 400 random states inside the joint limits,
// and per pair of links (pieces of a link together) the looseness hull distance - model distance
// in mm over the pairs whose hulls are apart but within 0.1 m (negative: tighter than the hulls,
// which pieces can be). `ratio_*` divide by K = 8's time, measured interleaved in the same loop.
// `gjk_iterations_per_pair*`: GJK iterations per pair of the distances query, the model and K = 8.
// The robots and their imports: robots.hpp.
using kccd::bench::importedModel;
using kccd::bench::kDefault;
using kccd::bench::kEight;
using kccd::bench::kHulls;
using kccd::bench::linkDistances;
using kccd::bench::robotNamed;

void BM_ImportCost(benchmark::State& state, const char* robot) {
  const int mode = static_cast<int>(state.range(0));
  if (!std::filesystem::exists(robotNamed(robot).urdf)) {
    state.SkipWithError("robot not found (dart-doc, or $KCCD_REAL_ROBOTS)");
    return;
  }
  const kccd::Model& m = importedModel(robot, mode);
  const kccd::Model& eight = importedModel(robot, kEight);
  const kccd::Model& hulls = importedModel(robot, kHulls);
  kccd::Checker cm(m), c8(eight), ch(hulls);
  const auto ranges = km::jointRanges(m);
  std::mt19937_64 rng(5);
  std::vector<std::vector<double>> states(400, std::vector<double>(m.stateSize()));
  for (auto& q : states)
    for (int s = 0; s < m.stateSize(); ++s)
      q[s] = std::isnan(ranges[s][0]) ? 0.0 : std::uniform_real_distribution<double>(ranges[s][0], ranges[s][1])(rng);
  const kccd::QueryOptions collision{.type = kccd::QueryType::Collision};
  const kccd::QueryOptions distances{.type = kccd::QueryType::Distances, .exact_below = INFINITY};
  double t_col = 0, t_col8 = 0, t_dist = 0, t_dist8 = 0;
  std::vector<double> loose;
  int tighter = 0;
  double calls = 0, iterations = 0, calls8 = 0, iterations8 = 0;  // GJK's, in the distances query
  auto seconds = [](auto&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  for (auto _ : state) {
    // The two models alternate which goes first, state by state (what runs first pays for the
    // caches the other warmed).
    bool first = true;
    for (int round = 0; round < 5; ++round)
      for (const auto& q : states) {
        first = !first;
        auto mine = [&] {
          t_col += seconds([&] { benchmark::DoNotOptimize(cm.query(q, q, collision).min_distance); });
          t_dist += seconds([&] { benchmark::DoNotOptimize(cm.query(q, q, distances).min_distance); });
        };
        auto theirs = [&] {
          t_col8 += seconds([&] { benchmark::DoNotOptimize(c8.query(q, q, collision).min_distance); });
          t_dist8 += seconds([&] { benchmark::DoNotOptimize(c8.query(q, q, distances).min_distance); });
        };
        if (first)
          mine(), theirs();
        else
          theirs(), mine();
      }
    for (const auto& q : states) {
      const kccd::QueryResult& r8 = c8.query(q, q, distances);
      calls8 += r8.stats.gjk_calls;
      iterations8 += r8.stats.gjk_iterations;
      const kccd::QueryResult& rm = cm.query(q, q, distances);
      calls += rm.stats.gjk_calls;
      iterations += rm.stats.gjk_iterations;
      const auto dm = linkDistances(m, rm);
      const auto dh = linkDistances(hulls, ch.query(q, q, distances));
      for (const auto& [pair, h] : dh) {
        const auto it = dm.find(pair);
        if (it == dm.end() || !(h > 0.0 && h <= 0.1)) continue;
        loose.push_back(1e3 * (h - it->second));
        tighter += it->second > h + 1e-9;
      }
    }
  }
  const double n = 5.0 * states.size();
  int points = 0;
  for (const kccd::Body& b : m.bodies) points += static_cast<int>(b.points.size());
  state.counters["bodies"] = static_cast<double>(m.bodies.size());
  state.counters["points"] = points;
  state.counters["pairs"] = static_cast<double>(m.pairs.size());
  state.counters["pairs_k8"] = static_cast<double>(eight.pairs.size());
  // Where the distances ratio comes from: pairs x GJK iterations per pair x time per iteration.
  state.counters["gjk_iterations_per_pair"] = iterations / calls;
  state.counters["gjk_iterations_per_pair_k8"] = iterations8 / calls8;
  state.counters["collision_us"] = 1e6 * t_col / n;
  state.counters["distances_us"] = 1e6 * t_dist / n;
  state.counters["ratio_collision"] = t_col / t_col8;
  state.counters["ratio_distances"] = t_dist / t_dist8;
  state.counters["loose_p50_mm"] = percentile(loose, 0.5);
  state.counters["loose_p90_mm"] = percentile(loose, 0.9);
  state.counters["tighter_than_hull"] = tighter;
  state.counters["near_link_pairs"] = static_cast<double>(loose.size());
}
BENCHMARK_CAPTURE(BM_ImportCost, panda, "panda")->DenseRange(0, 2)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ImportCost, wam, "wam")->DenseRange(0, 2)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ImportCost, kr5, "kr5")->DenseRange(0, 2)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ImportCost, xarm, "xarm")->DenseRange(0, 2)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
