// Calibration benchmarks on one rendered 1280x720 frame with 8 tags on a floor and two walls
// (support/tag_scene.hpp; blur 0.8 px, noise 2 grey levels, textured background), seen from 2.2 m
// through a camera with mild lens distortion:
// - BM_DetectTags:     AprilTag detection alone (the baseline docs/explanation/benchmarks.md compares against);
// - BM_DetectAndSolve: detection, tagCorrespondences and solvePose (the calibration of one frame);
// - BM_Solve:          solvePose alone on the detected correspondences.
// Run with --benchmark_repetitions=5 and read the medians; tables.py gives the ratios.
#include <benchmark/benchmark.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "support/cameras.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "support/tag_scene.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
constexpr double kPi = 3.141592653589793;

Camera benchCamera() {
  return kccd::testing::hdCamera(Vec3(2.0, 1.6, 1.35), Vec3(0.45, 0.45, 0.3));
}

// Three tags on the floor (z = 0), three on the wall x = 0, two on the wall y = 0; two tilted.
TagLayout benchLayout() {
  const auto tag = [](int id, double size, Vec3 xyz, Vec3 rpy) {
    Tag t;
    t.id = id, t.size = size, t.xyz = xyz, t.rpy = rpy;
    return t;
  };
  const double h = kPi / 2;
  TagLayout l;
  l.tags = {tag(0, 0.16, {0.35, 0.40, 0.0}, {0, 0, 0.3}),      tag(1, 0.12, {0.75, 0.30, 0.0}, {0, 0, 1.2}),
            tag(2, 0.18, {0.60, 0.80, 0.05}, {0.4, 0, -0.5}),  tag(3, 0.15, {0.0, 0.35, 0.45}, {h, 0, h}),
            tag(4, 0.10, {0.02, 0.75, 0.30}, {h + 0.2, 0, h}), tag(5, 0.20, {0.0, 0.65, 0.75}, {h, -0.3, h}),
            tag(6, 0.14, {0.40, 0.0, 0.55}, {h, 0, kPi}),      tag(7, 0.12, {0.80, 0.0, 0.30}, {h, 0.4, kPi})};
  return l;
}

struct Fixture {
  Camera camera = benchCamera();
  TagLayout layout = benchLayout();
  cv::Mat frame;
  Camera intrinsics;
  std::vector<Correspondence> points;

  Fixture() {
    testing::TagSceneOptions o;
    o.blur_sigma = 0.8;
    o.noise_sigma = 2.0;
    o.texture = true;
    frame = testing::renderTagScene(camera, layout, o);
    intrinsics = camera;
    intrinsics.rvec = cv::Vec3d(0, 0, 0);
    intrinsics.tvec = cv::Vec3d(0, 0, 0);
    points = tagCorrespondences(detectTags(frame), layout, "bench").points;
    if (points.size() != 4 * layout.tags.size()) throw std::runtime_error("bench_calib: not every tag is detected");
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

void BM_DetectTags(benchmark::State& state) {
  const Fixture& f = fixture();
  std::size_t found = 0;
  for (auto _ : state) {
    const std::vector<TagDetection> d = detectTags(f.frame);
    found = d.size();
    benchmark::DoNotOptimize(d.data());
  }
  state.counters["tags"] = static_cast<double>(found);
}

void addErrors(benchmark::State& state, const Fixture& f, const PoseResult& r) {
  if (r.status != PoseStatus::Solved) {
    state.SkipWithError(r.message.c_str());
    return;
  }
  cv::Matx33d a, b;
  cv::Rodrigues(r.camera.rvec, a);
  cv::Rodrigues(f.camera.rvec, b);
  const cv::Matx33d d = a * b.t();
  const double s = 0.5 * std::hypot(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  state.counters["rotation_error_deg"] = std::atan2(s, 0.5 * (d(0, 0) + d(1, 1) + d(2, 2) - 1.0)) * 180.0 / kPi;
  state.counters["position_error_mm"] = 1000 * cv::norm(a.t() * r.camera.tvec - b.t() * f.camera.tvec);
  state.counters["points"] = r.inliers;
}

void BM_DetectAndSolve(benchmark::State& state) {
  const Fixture& f = fixture();
  PoseResult r;
  for (auto _ : state) {
    const TagCorrespondences c = tagCorrespondences(detectTags(f.frame), f.layout, "bench");
    r = solvePose(f.intrinsics, c.points);
    benchmark::DoNotOptimize(r.camera.rvec);
  }
  addErrors(state, f, r);
}

void BM_Solve(benchmark::State& state) {
  const Fixture& f = fixture();
  PoseResult r;
  for (auto _ : state) {
    r = solvePose(f.intrinsics, f.points);
    benchmark::DoNotOptimize(r.camera.rvec);
  }
  addErrors(state, f, r);
}

BENCHMARK(BM_DetectTags)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_DetectAndSolve)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Solve)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
