// LeRobot datasets written at test time by other projects' tools (tests/datasets/write_lerobot.mjs:
// npm's parquet-wasm and hyparquet-writer for the tables, Debian's FFmpeg for AV1, h264 and mpeg4
// videos), read by `kccd dataset info`, `kccd overlay --lerobot` and `kccd check --lerobot`: every
// state value and frame equal to what was written, the overlay equal frame for frame to the same
// episode given as video + CSV, the check equal to the overlay's report, and bad datasets refused in
// one line with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "support/cameras.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::testing::Outcome;
using nlohmann::json;

const std::string kDemo = std::string(KCCD_SOURCE_DIR) + "/data/demo_arm.yaml";
constexpr int kRows = 24;
constexpr double kFps = 10.0;

Outcome run(const std::string& command) { return kccd::testing::runProgram(command); }
Outcome kccdRun(const std::string& args) { return run(std::string(KCCD_CLI) + " " + args); }

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The fixtures, written once for the whole program.
struct Fixtures {
  fs::path dir;
  std::string camera, states, frames;
  std::vector<std::string> names;

  fs::path dataset(const std::string& name) const { return dir / name; }
};
Fixtures* fx = nullptr;

std::string writeLerobot(const std::string& name, const std::string& options) {
  const fs::path out = fx->dir / name;
  const Outcome r = run(std::string(KCCD_NODE) + " " + KCCD_SOURCE_DIR + "/tests/datasets/write_lerobot.mjs " +
                        out.string() + " " + fx->states + " " + fx->frames + " " + options);
  if (r.code != 0) return "write_lerobot " + name + " failed: " + r.out + r.err;
  return {};
}

class Datasets : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fx = new Fixtures;
    fx->dir = fs::temp_directory_path() / ("kccd_datasets_" + std::to_string(::getpid()));
    fs::remove_all(fx->dir);
    fs::create_directories(fx->dir / "frames");
    // The camera: the demo camera at a quarter of its size (320 x 180).
    kccd::calib::Camera c = kccd::calib::loadCamera(std::string(KCCD_SOURCE_DIR) + "/data/demo_camera.yaml");
    c = kccd::testing::quarterSized(c);
    fx->camera = (fx->dir / "camera.yaml").string();
    kccd::calib::saveCamera(c, fx->camera);
    // The states: the demo arm swinging (one row per frame), the elbow close to the base at the end.
    const kccd::Model model = kccd::loadModel(kDemo);
    fx->names = model.stateNames();
    std::ofstream states(fx->dir / "states.csv");
    states << "time";
    for (const std::string& n : fx->names) states << "," << n;
    states << "\n";
    for (int i = 0; i < kRows; ++i) {
      states << i / kFps;
      for (std::size_t k = 0; k < fx->names.size(); ++k)
        states << "," << 0.9 * std::sin(0.21 * i + 0.7 * static_cast<double>(k)) * (k == 1 ? 2.2 : 1.0);
      states << "\n";
    }
    states.close();
    fx->states = (fx->dir / "states.csv").string();
    // The frames: FFmpeg's test pattern (a frame counter), one PNG per row.
    fx->frames = (fx->dir / "frames" / "frame_%06d.png").string();
    const Outcome f = run("ffmpeg -loglevel error -y -f lavfi -i testsrc=size=320x180:rate=10 -frames:v " +
                          std::to_string(kRows) + " -start_number 0 " + fx->frames);
    ASSERT_EQ(f.code, 0) << f.err;
    for (const auto& [name, options] : std::vector<std::pair<std::string, std::string>>{
             {"v21_av1", "--version v2.1 --writer pw --episodes 2 --codec libsvtav1"},
             {"v30_h264", "--version v3.0 --writer hy --episodes 3 --codec libx264"},
             {"v21_mpeg4_hy", "--version v2.1 --writer hy --episodes 2 --codec mpeg4"},
             {"v21_images", "--version v2.1 --writer pw --episodes 2 --image-feature"},
             {"v21_images_hy", "--version v3.0 --writer hy --episodes 2 --image-feature"},
             {"v21_drift",
              "--version v2.1 --writer pw --episodes 1 --codec libx264 --drift 0.3 --nested-names "
              "--info-codec av1 --extra-camera observation.images.wrist"}}) {
      const std::string problem = writeLerobot(name, options);
      ASSERT_TRUE(problem.empty()) << problem;
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(fx->dir);
    delete fx;
    fx = nullptr;
  }
  static fs::path out(const std::string& name) { return fx->dir / "out" / name; }
  void SetUp() override {
    ASSERT_NE(fx, nullptr);
    fs::create_directories(fx->dir / "out");
  }
};

// The truth file's rows: time, then the float32 values written.
std::vector<std::vector<double>> truthRows(const std::string& dataset, int episode) {
  std::ifstream in(fx->dataset(dataset) / "truth" / ("episode_" + std::to_string(episode) + ".csv"));
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream s(line);
    std::string field;
    while (std::getline(s, field, ',')) row.push_back(std::stod(field));
    rows.push_back(row);
  }
  return rows;
}

TEST_F(Datasets, InfoSaysWhatTheDatasetHolds) {
  const Outcome r = kccdRun("dataset info " + fx->dataset("v30_h264").string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["version"], "v3.0");
  EXPECT_EQ(j["episodes"], 3);
  EXPECT_EQ(j["frames"], kRows);
  EXPECT_DOUBLE_EQ(j["fps"].get<double>(), kFps);
  ASSERT_EQ(j["cameras"].size(), 1u);
  EXPECT_EQ(j["cameras"][0]["codec"], "h264");
  EXPECT_EQ(j["cameras"][0]["width"], 320);
  EXPECT_EQ(j["cameras"][0]["videos_present"], 3);
  bool state = false;
  for (const json& v : j["vectors"])
    if (v["key"] == "observation.state") {
      state = true;
      EXPECT_EQ(v["names"], json(fx->names));
    }
  EXPECT_TRUE(state);
  // Nested names are flattened; the text form names the cameras.
  const Outcome d = kccdRun("dataset info " + fx->dataset("v21_drift").string());
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_NE(d.out.find("observation.images.wrist"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find(fx->names[0]), std::string::npos) << d.out;
}

TEST_F(Datasets, EveryStateValueIsWhatWasWritten) {
  const kccd::Model model = kccd::loadModel(kDemo);
  for (const auto& [dataset, episodes] : std::vector<std::pair<std::string, int>>{
           {"v21_av1", 2}, {"v30_h264", 3}, {"v21_mpeg4_hy", 2}, {"v21_images_hy", 2}}) {
    for (int e = 0; e < episodes; ++e) {
      SCOPED_TRACE(dataset + " episode " + std::to_string(e));
      const kccd::overlay::LerobotRecording rec = kccd::overlay::readLerobotRecording(
          {.dataset = fx->dataset(dataset).string(), .episode = e, .frames = false}, model);
      const std::vector<std::vector<double>> truth = truthRows(dataset, e);
      ASSERT_EQ(rec.log.rows(), truth.size());
      EXPECT_EQ(rec.frame_by, kccd::overlay::FrameBy::Timestamp);
      for (std::size_t i = 0; i < truth.size(); ++i) {
        EXPECT_EQ(rec.log.times[i], truth[i][0]);
        for (std::size_t k = 0; k < rec.log.stateSize(); ++k) EXPECT_EQ(rec.log.row(i)[k], truth[i][k + 1]) << i;
      }
    }
  }
}

// The decoded frame against the PNG it was encoded from: close, and closer than its neighbours.
void expectFrame(const cv::Mat& frame, int row, double tolerance) {
  const auto png = [](int i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", i);
    return cv::imread((fx->dir / "frames" / name).string(), cv::IMREAD_COLOR);
  };
  const auto diff = [&](int i) {
    return cv::norm(frame, png(i), cv::NORM_L1) / static_cast<double>(frame.total() * 3);
  };
  const double own = diff(row);
  EXPECT_LE(own, tolerance) << "row " << row;
  for (const int other : {row - 1, row + 1}) {
    if (other >= 0 && other < kRows) {
      EXPECT_LT(own, diff(other)) << "row " << row << " against " << other;
    }
  }
}

TEST_F(Datasets, EveryFrameIsTheOneWritten) {
  const kccd::Model model = kccd::loadModel(kDemo);
  for (const auto& [dataset, episodes, tolerance] :
       std::vector<std::tuple<std::string, int, double>>{{"v21_av1", 2, 12.0},
                                                         {"v30_h264", 3, 6.0},
                                                         {"v21_mpeg4_hy", 2, 12.0},
                                                         {"v21_images", 2, 0.0},
                                                         {"v21_images_hy", 2, 0.0}}) {
    int first = 0;
    for (int e = 0; e < episodes; ++e) {
      SCOPED_TRACE(dataset + " episode " + std::to_string(e));
      const kccd::overlay::LerobotRecording rec =
          kccd::overlay::readLerobotRecording({.dataset = fx->dataset(dataset).string(), .episode = e}, model);
      const std::unique_ptr<kccd::overlay::FrameSource> frames = rec.open_frames();
      cv::Mat frame;
      int n = 0;
      while (frames->read(frame)) expectFrame(frame, first + n++, tolerance);
      EXPECT_EQ(static_cast<std::size_t>(n), rec.log.rows());
      first += n;
    }
    EXPECT_EQ(first, kRows);
  }
}

TEST_F(Datasets, OverlayEqualsTheSameEpisodeAsVideoAndCsv) {
  const std::string ds = fx->dataset("v21_av1").string();
  const std::string common = "overlay " + kDemo + " --camera " + fx->camera + " -q ";
  const Outcome a = kccdRun(common + "--lerobot " + ds + " --episode 1 --png-dir " + out("a").string() + " --report " +
                            out("a.json").string());
  ASSERT_EQ(a.code, 0) << a.err;
  const std::string video = ds + "/videos/chunk-000/observation.images.front/episode_000001.mp4";
  const Outcome b = kccdRun(common + "--video " + video + " --states " + ds + "/truth/episode_1.csv --png-dir " +
                            out("b").string() + " --report " + out("b.json").string());
  ASSERT_EQ(b.code, 0) << b.err;
  std::size_t frames = 0;
  for (const auto& f : fs::directory_iterator(out("a"))) {
    ++frames;
    EXPECT_EQ(readText(f.path()), readText(out("b") / f.path().filename())) << f.path().filename();
  }
  EXPECT_EQ(frames, static_cast<std::size_t>(kRows - kRows / 2));
  const json ja = json::parse(readText(out("a.json"))), jb = json::parse(readText(out("b.json")));
  EXPECT_EQ(ja["frames"], jb["frames"]);
  EXPECT_EQ(ja["source"]["lerobot"], ds);
  EXPECT_EQ(ja["source"]["frame_by"], "timestamp");

  // kccd check on the same episode: the overlay's records (time, state, status, distance, pairs).
  const Outcome c =
      kccdRun("check " + kDemo + " --lerobot " + ds + " --episode 1 -q --report " + out("c.json").string());
  ASSERT_EQ(c.code, 0) << c.err;
  const json jc = json::parse(readText(out("c.json")));
  ASSERT_EQ(jc["frames"].size(), ja["frames"].size());
  for (std::size_t i = 0; i < jc["frames"].size(); ++i)
    for (const char* key :
         {"time", "state", "status", "min_distance", "pairs_within_margin", "state_values", "query_status"})
      EXPECT_EQ(jc["frames"][i][key], ja["frames"][i][key]) << i << " " << key;
  for (const char* key : {"frames_total", "within_margin", "colliding", "no_state", "unsafe"}) {
    EXPECT_FALSE(ja[key].is_null()) << key;
    EXPECT_EQ(jc[key], ja[key]) << key;
  }
}

TEST_F(Datasets, TimestampsOffTheGridArePairedByIndexWithAWarning) {
  const std::string ds = fx->dataset("v21_drift").string();
  const std::string common = "overlay " + kDemo + " --camera " + fx->camera + " -q --lerobot " + ds + " --episode 0 ";
  const Outcome several = kccdRun(common + "--report " + out("d0.json").string());
  EXPECT_EQ(several.code, 2);
  EXPECT_NE(several.err.find("several cameras"), std::string::npos) << several.err;
  EXPECT_NE(several.err.find("--camera-key"), std::string::npos) << several.err;
  const Outcome r = kccdRun(common + "--camera-key observation.images.front --report " + out("d.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("off the 10 fps frame grid"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--frame-by index"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("says codec av1, the video is"), std::string::npos) << r.err;
  const json j = json::parse(readText(out("d.json")));
  EXPECT_EQ(j["source"]["frame_by"], "index");
  EXPECT_EQ(j["frames"].size(), static_cast<std::size_t>(kRows));
  EXPECT_EQ(j["no_state"], 0);
  const Outcome strict =
      kccdRun(common + "--camera-key observation.images.front --frame-by timestamp --report " + out("e.json").string());
  EXPECT_EQ(strict.code, 2);
  EXPECT_NE(strict.err.find("column timestamp, row "), std::string::npos) << strict.err;
  EXPECT_FALSE(fs::exists(out("e.json")));
}

// A copy of a dataset to break.
fs::path copyOf(const std::string& dataset, const std::string& name) {
  const fs::path to = fx->dir / "broken" / name;
  fs::remove_all(to);
  fs::create_directories(to.parent_path());
  fs::copy(fx->dataset(dataset), to, fs::copy_options::recursive);
  return to;
}

TEST_F(Datasets, BadDatasetsAreOneLineExitTwoAndNothingWritten) {
  const auto expectRefused = [](const fs::path& ds, const std::string& extra, const std::string& expected) {
    SCOPED_TRACE(ds.string() + " " + extra);
    const fs::path report = out("bad.json");
    const Outcome r = kccdRun("overlay " + kDemo + " --camera " + fx->camera + " -q --lerobot " + ds.string() + " " +
                              extra + " --report " + report.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(report));
  };
  expectRefused(fx->dataset("v21_av1"), "--episode 7", "episode 7: not in the dataset (its episodes: 0 ... 1)");
  expectRefused(fx->dataset("v21_av1"), "", "--episode: give the episode");
  {  // a Parquet file cut short
    const fs::path ds = copyOf("v21_av1", "cut");
    const fs::path table = ds / "data/chunk-000/episode_000001.parquet";
    fs::resize_file(table, fs::file_size(table) / 2);
    expectRefused(ds, "--episode 1", table.string());
  }
  {  // a missing video
    const fs::path ds = copyOf("v21_av1", "novideo");
    const fs::path video = ds / "videos/chunk-000/observation.images.front/episode_000000.mp4";
    fs::remove(video);
    expectRefused(ds, "--episode 0", video.string() + ": not found");
  }
  {  // a video that is not one
    const fs::path ds = copyOf("v21_av1", "junkvideo");
    std::ofstream(ds / "videos/chunk-000/observation.images.front/episode_000000.mp4") << "not a video";
    expectRefused(ds, "--episode 0", "episode_000000.mp4: cannot open the video");
  }
  {  // a video holding fewer frames than the rows need
    const fs::path ds = copyOf("v21_av1", "short");
    const fs::path video = ds / "videos/chunk-000/observation.images.front/episode_000000.mp4";
    const Outcome f = run("ffmpeg -loglevel error -y -framerate 10 -i " + fx->frames + " -frames:v 5 -c:v libx264 " +
                          "-pix_fmt yuv420p " + (ds / "short.mp4").string());
    ASSERT_EQ(f.code, 0) << f.err;
    fs::rename(ds / "short.mp4", video);
    expectRefused(ds, "--episode 0", "needs frame 11 of the episode");
  }
  {  // info.json broken
    const fs::path ds = copyOf("v21_av1", "badinfo");
    std::ofstream(ds / "meta/info.json") << "{\"codebase_version\": \"v2.1\",\n \"fps\": }";
    expectRefused(ds, "--episode 0", "meta/info.json:2:");
  }
  {  // a version not read
    const fs::path ds = copyOf("v21_av1", "v1");
    std::string info = readText(ds / "meta/info.json");
    info.replace(info.find("\"v2.1\""), 6, "\"v1.6\"");
    std::ofstream(ds / "meta/info.json") << info;
    expectRefused(ds, "--episode 0", "codebase_version: 'v1.6' is not read");
  }
  {  // a state feature the table lacks
    expectRefused(fx->dataset("v21_av1"), "--episode 0 --state-key observation.effort",
                  "no column 'observation.effort'");
  }
}

TEST_F(Datasets, CheckReadsTheEpisodeAloneAtARate) {
  const std::string ds = fx->dataset("v30_h264").string();
  const Outcome r = kccdRun("check " + kDemo + " --lerobot " + ds + " --episode 2 --rate 40 --json -q --timeline " +
                            out("t.png").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  // Episode 2 holds rows 16 ... 23: 0.7 s at 40 Hz is 29 samples.
  EXPECT_EQ(j["samples"], 29);
  EXPECT_EQ(j["no_state"], 0);
  EXPECT_TRUE(fs::exists(out("t.png")));
  // The same samples from the CSV path.
  const Outcome c = kccdRun("check " + kDemo + " --states " + ds + "/truth/episode_2.csv --rate 40 --json -q");
  ASSERT_EQ(c.code, 0) << c.err;
  const json jc = json::parse(c.out);
  for (const char* key : {"samples", "within_margin", "colliding", "no_state", "unsafe"}) {
    EXPECT_FALSE(j[key].is_null()) << key;
    EXPECT_EQ(jc[key], j[key]) << key;
  }
  const Outcome bad = kccdRun("check " + kDemo + " --states " + ds + "/truth/episode_2.csv --episode 2");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--episode: goes with --lerobot"), std::string::npos) << bad.err;
}

}  // namespace

namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

cv::Point2d projected(const kccd::calib::Camera& c, const kccd::Vec3& p) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, c.rvec, c.tvec, c.camera_matrix, c.distortion,
                    out);
  return out[0];
}

}  // namespace

// An episode's frames calibrate like a video's: --lerobot --episode --frame, each frame's state
// from its row placing the body labels; the camera it was filmed with comes back.
TEST_F(Datasets, CalibrationTakesAnEpisodesFrames) {
  const kccd::Model model = kccd::loadModel(kDemo);
  const kccd::calib::Camera camera = kccd::calib::loadCamera(fx->camera);
  const std::string ds = fx->dataset("v21_av1").string();
  const kccd::overlay::LerobotRecording rec =
      kccd::overlay::readLerobotRecording({.dataset = ds, .episode = 1, .frames = false}, model);
  std::string args;
  for (const int frame : {2, 5}) {
    std::vector<kccd::Pose> poses(model.joints.size());
    ASSERT_TRUE(kccd::framePoses(model, rec.log.row(static_cast<std::size_t>(frame)), poses));
    const std::string path = out("labels_" + std::to_string(frame) + ".yaml").string();
    std::ofstream labels(path);
    labels << "labels:\n";
    for (int i = 0; i < 8; ++i) {
      const kccd::Vec3 w(0.1 + 0.15 * (i % 4), -0.3 + 0.6 * (i / 4), 0.05 * (i % 3));
      const cv::Point2d px = projected(camera, w);
      labels << "  - {name: w" << i << ", pixel: [" << num(px.x) << ", " << num(px.y) << "], world: [" << num(w.x())
             << ", " << num(w.y()) << ", " << num(w.z()) << "]}\n";
    }
    const kccd::Body& forearm = model.bodies[static_cast<std::size_t>(model.bodyIndex("forearm"))];
    const kccd::Vec3 tip = kccd::framePose(poses, forearm.frame) * forearm.points.back();
    const cv::Point2d px = projected(camera, tip);
    labels << "  - {name: tip, pixel: [" << num(px.x) << ", " << num(px.y) << "], body: forearm, point: ["
           << num(forearm.points.back().x()) << ", " << num(forearm.points.back().y()) << ", "
           << num(forearm.points.back().z()) << "]}\n";
    args += " --frame " + std::to_string(frame) + " --labels " + path;
  }
  const Outcome r = kccdRun("calib --intrinsics " + fx->camera + " --model " + kDemo + " --lerobot " + ds +
                            " --episode 1" + args + " -o " + out("cam.yaml").string() + " --json -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const kccd::calib::Camera solved = kccd::calib::loadCamera(out("cam.yaml").string());
  EXPECT_LT(cv::norm(solved.rvec - camera.rvec), 1e-4);
  EXPECT_LT(cv::norm(solved.tvec - camera.tvec), 1e-4);
  const Outcome beyond =
      kccdRun("calib --intrinsics " + fx->camera + " --model " + kDemo + " --lerobot " + ds +
              " --episode 1 --frame 40 --labels " + out("labels_2.yaml").string() + " -o " + out("none.yaml").string());
  EXPECT_EQ(beyond.code, 2);
  EXPECT_NE(beyond.err.find("--frame 40: the episode has 12 frames (0 ... 11)"), std::string::npos) << beyond.err;
  EXPECT_FALSE(fs::exists(out("none.yaml")));
}

// A golden case on an episode's frame: updated, then run against itself; a case without its
// episode is a manifest error at its line.
TEST_F(Datasets, GoldenCasesTakeAnEpisodesFrame) {
  const std::string ds = fx->dataset("v30_h264").string();
  const fs::path manifest = out("golden.yaml");
  std::ofstream(manifest) << "kccd_golden: 1\ngoldens: goldens\ndefaults: {model: " << kDemo
                          << ", camera: " << fx->camera << "}\ncases:\n  - {id: ep2-f3, lerobot: " << ds
                          << ", episode: 2, frame: 3, outputs: [overlay, mask]}\n";
  const Outcome update = kccdRun("golden update " + manifest.string() + " -q");
  ASSERT_EQ(update.code, 0) << update.err << update.out;
  const json sidecar = json::parse(readText(out("goldens") / "ep2-f3" / "golden.json"));
  EXPECT_EQ(sidecar["inputs"]["lerobot"]["episode"], 2);
  EXPECT_EQ(sidecar["inputs"]["lerobot"]["frame"], 3);
  const Outcome again = kccdRun("golden run " + manifest.string() + " --out " + out("golden_run").string() + " -q");
  EXPECT_EQ(again.code, 0) << again.err << again.out;
  std::ofstream(manifest) << "kccd_golden: 1\ndefaults: {model: " << kDemo << ", camera: " << fx->camera
                          << "}\ncases:\n  - {id: x, lerobot: " << ds << ", frame: 3}\n";
  const Outcome bad = kccdRun("golden run " + manifest.string() + " --out " + out("golden_bad").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("golden.yaml:4:5: case 'x'.episode: a lerobot frame case needs its episode"),
            std::string::npos)
      << bad.err;
}
