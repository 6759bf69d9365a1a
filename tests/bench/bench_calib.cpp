// Calibration benchmarks on one rendered 1280x720 frame with 8 tags on a floor and two walls
// (support/tag_scene.hpp; blur 0.8 px, noise 2 grey levels, textured background), seen from 2.2 m
// through a camera with mild lens distortion:
// - BM_DetectTags:     AprilTag detection alone (the baseline docs/explanation/benchmarks.md compares against);
// - BM_DetectAndSolve: detection, tagCorrespondences and solvePose (the calibration of one frame);
// - BM_Solve:          solvePose alone on the detected correspondences.
// And the robot-mask refinement (mask_refine.hpp) on 10 frames of 960x540 of the demo arm, masks
// by the tests' independent rasteriser (support/silhouette.hpp), against the label-only solve it
// starts from, in the same run:
// - BM_SolveLabels:           solvePose on 12 body labels over 3 frames, 8 px click error;
// - BM_RefineFromLabels:      refineToMasks from that solve (kccd calib --labels --masks);
// - BM_RefineFromTenDegrees:  refineToMasks from a pose 10 deg and 10 cm off (--camera ROUGH --masks);
// - BM_RefineEdgesFromLabels: refineToEdges from that solve, the labels as clicks, on pictures of the
//                             masks' robot (one shade) on a background with boxes (--refine edges).
// Run with --benchmark_repetitions=5 and read the medians; tables.py gives the ratios.
#include <benchmark/benchmark.h>

#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/edge_refine.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/model.hpp"
#include "support/cameras.hpp"
#include "support/silhouette.hpp"
#include "support/tag_scene.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
constexpr double kPi = 3.141592653589793;

Camera benchCamera() { return kccd::testing::hdCamera(Vec3(2.0, 1.6, 1.35), Vec3(0.45, 0.45, 0.3)); }

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

// The mask scene: demo_arm's pedestal, shoulder, upper arm, forearm and gripper in 10 random
// states, seen at 960x540 (f 780 px, mild distortion) from 1.6 m.
struct MaskScene {
  Model model = loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  std::vector<int> bodies = {0, 3, 4, 5, 6};
  Camera truth = testing::lookAt(Vec3(1.25, -0.95, 0.9), Vec3(0.2, 0.0, 0.35), 960, 540, 780.0,
                                 {-0.08, 0.03, 0.0005, -0.0003, 0.0});
  std::vector<MaskFrame> frames;
  std::vector<EdgeFrame> pictures;     // the robot in one shade on grey with boxes, blurred
  std::vector<Correspondence> labels;  // 4 per frame on the first 3 frames, 8 px off
  Camera rough;                        // 10 deg and 10 cm from the truth

  MaskScene() {
    std::mt19937_64 rng(7), boxes(8);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::normal_distribution<double> click(0.0, 8.0);
    for (int f = 0; f < 10; ++f) {
      const std::vector<double> state = {1.2 * u(rng), 0.6 * u(rng), 1.0 * u(rng)};
      MaskFrame frame{cv::Mat::zeros(truth.height, truth.width, CV_8UC1), placeVolumes(model, state, bodies)};
      for (const PlacedVolume& v : frame.volumes) frame.mask |= testing::cpuSilhouette(truth, v.points, v.radius);
      frame.mask *= 255;
      if (f < 3)
        for (std::size_t b = 1; b < frame.volumes.size(); ++b) {  // a click on each moving body's first core point
          const Vec3& p = frame.volumes[b].points.front();
          const cv::Point2d px = testing::cvProject(truth, p);
          labels.push_back({"f" + std::to_string(f) + "b" + std::to_string(b), px + cv::Point2d(click(rng), click(rng)),
                            cv::Point3d(p.x(), p.y(), p.z())});
        }
      cv::Mat grey(truth.height, truth.width, CV_8UC1, cv::Scalar(90));
      for (int k = 0; k < 8; ++k) {
        const cv::Point a(static_cast<int>(480 + 450 * u(boxes)), static_cast<int>(270 + 250 * u(boxes)));
        cv::rectangle(grey, a, a + cv::Point(60, 40), cv::Scalar(128 + 100 * u(boxes)), cv::FILLED);
      }
      grey.setTo(cv::Scalar(200), frame.mask);
      cv::GaussianBlur(grey, grey, cv::Size(5, 5), 0.8);
      pictures.push_back({grey, frame.volumes});
      frames.push_back(std::move(frame));
    }
    // 10 deg about a fixed skew axis through the camera, 10 cm along another.
    cv::Matx33d r, d;
    cv::Rodrigues(truth.rvec, r);
    cv::Rodrigues(cv::Vec3d(0.6, -0.5, 0.62) * (10.0 * kPi / 180.0 / cv::norm(cv::Vec3d(0.6, -0.5, 0.62))), d);
    const cv::Vec3d centre =
        testing::cameraCentre(truth) + cv::Vec3d(-0.5, 0.7, 0.5) * (0.10 / cv::norm(cv::Vec3d(-0.5, 0.7, 0.5)));
    rough = truth;
    cv::Rodrigues(d * r, rough.rvec);
    rough.tvec = -((d * r) * centre);
  }
};

const MaskScene& maskScene() {
  static const MaskScene s;
  return s;
}

void addMaskErrors(benchmark::State& state, const Camera& truth, const Camera& got) {
  state.counters["rotation_error_deg"] = testing::rotationErrorDeg(got.rvec, truth.rvec);
  state.counters["position_error_mm"] = 1000 * cv::norm(testing::cameraCentre(got) - testing::cameraCentre(truth));
}

void BM_SolveLabels(benchmark::State& state) {
  const MaskScene& s = maskScene();
  PoseResult r;
  for (auto _ : state) {
    r = solvePose(s.truth, s.labels);
    benchmark::DoNotOptimize(r.camera.rvec);
  }
  if (r.status != PoseStatus::Solved) return state.SkipWithError(r.message.c_str());
  addMaskErrors(state, s.truth, r.camera);
  state.counters["labels"] = static_cast<double>(s.labels.size());
}

// Times `run` (a refinement of the mask scene) and counts its errors and agreement (mean_iou for
// masks, edge_share for edges).
void refine(benchmark::State& state, const std::function<RefineResult()>& run) {
  RefineResult r;
  for (auto _ : state) {
    r = run();
    benchmark::DoNotOptimize(r.camera.rvec);
  }
  if (!r.improved) return state.SkipWithError(r.message.c_str());
  addMaskErrors(state, maskScene().truth, r.camera);
  const bool edges = r.source == RefineSource::Edges;
  double agreement = 0.0;
  for (const FrameAgreement& a : r.frames)
    agreement += (edges ? a.matched_after : a.iou_after) / static_cast<double>(r.frames.size());
  state.counters[edges ? "edge_share" : "mean_iou"] = agreement;
  state.counters["frames"] = static_cast<double>(r.frames.size());
  state.counters["iterations"] = r.iterations;
}

void refine(benchmark::State& state, const Camera& start) {
  refine(state, [&] { return refineToMasks(start, maskScene().frames); });
}

void BM_RefineFromLabels(benchmark::State& state) {
  const MaskScene& s = maskScene();
  const PoseResult start = solvePose(s.truth, s.labels);
  if (start.status != PoseStatus::Solved) return state.SkipWithError(start.message.c_str());
  refine(state, start.camera);
}

void BM_RefineFromTenDegrees(benchmark::State& state) { refine(state, maskScene().rough); }

void BM_RefineEdgesFromLabels(benchmark::State& state) {
  const MaskScene& s = maskScene();
  const PoseResult start = solvePose(s.truth, s.labels);
  if (start.status != PoseStatus::Solved) return state.SkipWithError(start.message.c_str());
  refine(state, [&] { return refineToEdges(start.camera, s.pictures, {}, s.labels); });
}

BENCHMARK(BM_DetectTags)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_DetectAndSolve)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Solve)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_SolveLabels)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_RefineFromLabels)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RefineFromTenDegrees)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RefineEdgesFromLabels)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
