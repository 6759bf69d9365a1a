// End-to-end: `kccd synth` writes a recording whose truth holds — the visible geometry lies inside
// the SSCHs, the state log has the documented rate, offset and velocities, the reported collision
// frames collide, calibration on the first frame recovers the true camera, and the same seed gives
// the same files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/checker.hpp"
#include "kccd/format_number.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/state_log.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::testing::Outcome;
using nlohmann::json;

Outcome runKccd(const std::string& args) { return kccd::testing::runProgram(std::string(KCCD_CLI) + " " + args); }

const std::string kData = KCCD_DATA_DIR;
const std::string kHumanoid = kData + "/humanoid.yaml";
constexpr double kSeconds = 2.4;
constexpr double kFps = 25.0;

// One recording shared by the tests (the synthesis is the slow part).
class Synth : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::path(::testing::TempDir()) / ("kccd_synth_" + std::to_string(getpid())));
    fs::create_directories(*root_);
    run_ = new Outcome(runKccd("synth " + kHumanoid + " -o " + dir("a") + " --seconds " + std::to_string(kSeconds) +
                               " --fps 25 --seed 3 --bag -q"));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
    delete run_;
  }
  void SetUp() override { ASSERT_EQ(run_->code, 0) << run_->err; }
  static std::string dir(const std::string& name) { return (*root_ / name).string(); }
  static json summary(const std::string& name = "a") {
    return json::parse(kccd::testing::readText(dir(name) + "/synth.json"));
  }
  static inline fs::path* root_ = nullptr;
  static inline Outcome* run_ = nullptr;
};

std::vector<cv::Mat> readVideo(const std::string& path) {
  cv::VideoCapture cap(path);
  std::vector<cv::Mat> frames;
  cv::Mat f;
  while (cap.read(f)) frames.push_back(f.clone());
  return frames;
}

TEST_F(Synth, WritesEveryFile) {
  for (const char* f :
       {"video.mkv", "states.csv", "states.mcap", "camera_true.yaml", "intrinsics.yaml", "tags.yaml", "synth.json"})
    EXPECT_TRUE(fs::is_regular_file(dir("a") + "/" + f)) << f;
  const json j = summary();
  const int frames = j["video"]["frames"];
  EXPECT_EQ(frames, static_cast<int>(std::floor(kSeconds * kFps + 1e-9)));
  EXPECT_EQ(j["frames"].size(), static_cast<std::size_t>(frames));
  const std::vector<cv::Mat> video = readVideo(dir("a") + "/video.mkv");
  ASSERT_EQ(video.size(), static_cast<std::size_t>(frames));
  const kccd::calib::Camera cam = kccd::calib::loadCamera(dir("a") + "/camera_true.yaml");
  EXPECT_EQ(video[0].cols, cam.width);
  EXPECT_EQ(video[0].rows, cam.height);
  for (int i = 0; i < frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/masks/frame_%06d.png", i);
    const cv::Mat mask = cv::imread(dir("a") + name, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_8UC1) << name;
    EXPECT_EQ(mask.size(), video[0].size());
  }
  // Nothing but the folder is left beside it (the temporary folder was renamed).
  int entries = 0;
  for (const auto& e : fs::directory_iterator(*root_)) entries += e.path().filename().string().rfind(".a.", 0) == 0;
  EXPECT_EQ(entries, 0);
  // The intrinsics file has no pose and loads as intrinsics only.
  const std::string intr = kccd::testing::readText(dir("a") + "/intrinsics.yaml");
  EXPECT_EQ(intr.find("rvec"), std::string::npos);
  EXPECT_THROW(kccd::calib::loadCamera(dir("a") + "/intrinsics.yaml"), kccd::calib::CameraError);
  const kccd::calib::Camera k =
      kccd::calib::loadCamera(dir("a") + "/intrinsics.yaml", kccd::calib::CameraPose::Optional);
  EXPECT_EQ(k.camera_matrix, cam.camera_matrix);
  EXPECT_EQ(k.distortion, cam.distortion);
}

TEST_F(Synth, StateLogHasRateOffsetAndVelocities) {
  const json j = summary();
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::StateLog log = kccd::loadStateLog(dir("a") + "/states.csv", m);
  const double rate = j["state_log"]["rate_hz"], offset = j["state_log"]["time_offset"];
  EXPECT_EQ(rate, 125.0);
  EXPECT_EQ(offset, 0.137);
  EXPECT_NE(rate, static_cast<double>(j["video"]["fps"]));
  EXPECT_NEAR(log.medianPeriod(), 1.0 / rate, 1e-9);
  ASSERT_TRUE(log.hasVelocities());
  for (std::uint8_t v : log.logged_velocity) EXPECT_EQ(v, 1);
  // Velocities integrate to the values: each step's change against the trapezoid rule (its error,
  // h^3 / 12 times the jerk, stays below 1e-3 rad for this motion at 125 Hz).
  const std::size_t n = log.stateSize();
  double worst = 0, fastest = 0;
  for (std::size_t r = 0; r + 1 < log.rows(); ++r)
    for (std::size_t i = 0; i < n; ++i) {
      const double h = log.times[r + 1] - log.times[r];
      const double step = log.values[(r + 1) * n + i] - log.values[r * n + i];
      const double integral = 0.5 * h * (log.velocities[r * n + i] + log.velocities[(r + 1) * n + i]);
      worst = std::max(worst, std::abs(step - integral));
      fastest = std::max(fastest, std::abs(log.velocities[r * n + i]));
    }
  EXPECT_LT(worst, 2e-3);
  EXPECT_GT(fastest, 0.1);  // it moves
  // Each frame's state is the log's state at video time + offset.
  std::vector<double> s(n);
  for (const json& f : j["frames"]) {
    const double t = f["time"];
    ASSERT_NE(kccd::stateAt(log, t + offset, 1.5 / rate, s), kccd::StateMatch::None) << t;
    const std::vector<double> logged = f["state"];
    for (std::size_t i = 0; i < n; ++i) ASSERT_DOUBLE_EQ(logged[i], s[i]) << "frame " << f["index"] << " value " << i;
  }
  // The log starts at or before the first frame's log time and ends after the last one's.
  EXPECT_LE(log.times.front(), offset);
  EXPECT_GE(log.times.back(), static_cast<double>(j["frames"].back()["time"]) + offset);
}

TEST_F(Synth, CollisionFramesCollideAtTheLoggedState) {
  const json j = summary();
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::StateLog log = kccd::loadStateLog(dir("a") + "/states.csv", m);
  const double offset = j["state_log"]["time_offset"];
  kccd::Checker checker(m);
  std::vector<double> s(log.stateSize());
  std::vector<int> colliding, near;
  for (const json& f : j["frames"]) {
    ASSERT_NE(kccd::stateAt(log, static_cast<double>(f["time"]) + offset, 1.5 / 125.0, s), kccd::StateMatch::None);
    checker.reset();  // each frame on its own, as synth evaluates it
    const kccd::QueryResult& r = checker.query(s, s, kccd::QueryOptions{.type = kccd::QueryType::Distances});
    ASSERT_EQ(r.status, kccd::Status::Ok);
    EXPECT_DOUBLE_EQ(r.min_distance, static_cast<double>(f["min_distance"]));
    if (r.min_distance <= 0.0)
      colliding.push_back(f["index"]);
    else if (r.min_distance <= m.safety_margin)
      near.push_back(f["index"]);
  }
  EXPECT_EQ(colliding, j["collision"]["frames"].get<std::vector<int>>());
  EXPECT_EQ(near, j["near_collision_frames"].get<std::vector<int>>());
  ASSERT_FALSE(colliding.empty());
  EXPECT_EQ(colliding.back() - colliding.front() + 1, static_cast<int>(colliding.size())) << "one interval";
  ASSERT_EQ(j["collision"]["intervals"].size(), 1u);
  // A near-collision outside the collision's neighbourhood (an approach of its own).
  int apart = 0;
  for (int f : near) apart += f < colliding.front() - 3 || f > colliding.back() + 3;
  EXPECT_GE(apart, 1);
}

// The visible geometry (the masks) never shows outside the full volumes: every frame's visible
// mask pixels are covered by the label mask of the full SSCHs drawn by the normal renderer at the
// same state with the same options. Both masks sample pixel centres (no anti-aliasing) through the
// same pinhole image and map, and each visible mesh lies inside its full mesh (same core points,
// radius scaled by 0.8, tessellation error 0.3 % of the radius outwards at most), so no boundary
// allowance is needed: 0 violations.
TEST_F(Synth, VisibleGeometryLiesInsideTheVolumes) {
  const json j = summary();
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::calib::Camera cam = kccd::calib::loadCamera(dir("a") + "/camera_true.yaml");
  kccd::render::RenderOptions ro;
  ro.supersample = j["render"]["supersample"];
  ro.mask_supersample = j["render"]["mask_supersample"];
  kccd::render::Renderer renderer(cam, ro);
  kccd::Checker checker(m);
  long visible_total = 0;
  for (const json& f : j["frames"]) {
    const std::vector<double> s = f["state"];
    checker.query(s, s, kccd::QueryOptions{.type = kccd::QueryType::Distances});
    const std::vector<kccd::render::Volume> full = kccd::render::staticSceneVolumes(m, checker, s, {});
    const kccd::render::Frame frame = renderer.render(full, {}, false, true);
    char name[32];
    std::snprintf(name, sizeof name, "/masks/frame_%06d.png", static_cast<int>(f["index"]));
    const cv::Mat visible = cv::imread(dir("a") + name, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(visible.size(), frame.mask.size());
    const cv::Mat outside = (visible > 0) & (frame.mask == 0);
    EXPECT_EQ(cv::countNonZero(outside), 0) << name;
    const int shown = cv::countNonZero(visible);
    visible_total += shown;
    EXPECT_LT(shown, cv::countNonZero(frame.mask)) << name << ": strictly smaller";
  }
  EXPECT_GT(visible_total, 0);
}

// `kccd calib` on the first frame, with the written intrinsics and tag layout, recovers the camera.
TEST_F(Synth, CalibrationRecoversTheTrueCamera) {
  const std::vector<cv::Mat> video = readVideo(dir("a") + "/video.mkv");
  ASSERT_FALSE(video.empty());
  const std::string frame = dir("frame0.png"), solved = dir("solved.yaml");
  ASSERT_TRUE(cv::imwrite(frame, video[0]));
  const Outcome r = runKccd("calib --intrinsics " + dir("a") + "/intrinsics.yaml --image " + frame + " --tags " +
                            dir("a") + "/tags.yaml -o " + solved + " -q");
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  {  // The same frame as an image sequence gives the same camera: one rule opens recordings.
    cv::VideoCapture cap(dir("a") + "/video.mkv");
    cv::Mat first;
    ASSERT_TRUE(cap.read(first));
    fs::create_directories(dir("seq"));
    ASSERT_TRUE(cv::imwrite(dir("seq") + "/frame_000000.png", first));
    const std::string from_sequence = dir("overlay_camera_seq.yaml");
    const Outcome q =
        runKccd("calib --intrinsics " + dir("a") + "/intrinsics.yaml --video " + dir("seq") +
                "/frame_%06d.png --frame 0 --tags " + dir("a") + "/tags.yaml -o " + from_sequence + " -q");
    ASSERT_EQ(q.code, 0) << q.err << q.out;
    EXPECT_EQ(kccd::testing::readText(from_sequence), kccd::testing::readText(solved));
  }
  const kccd::calib::Camera truth = kccd::calib::loadCamera(dir("a") + "/camera_true.yaml");
  const kccd::calib::Camera got = kccd::calib::loadCamera(solved);
  cv::Matx33d rt, rg;
  cv::Rodrigues(truth.rvec, rt);
  cv::Rodrigues(got.rvec, rg);
  cv::Vec3d angle;
  cv::Rodrigues(rg * rt.t(), angle);
  const cv::Vec3d ct = -(rt.t() * truth.tvec), cg = -(rg.t() * got.tvec);
  EXPECT_LT(cv::norm(angle) * 180.0 / M_PI, 0.05);
  EXPECT_LT(cv::norm(ct - cg), 0.005);
}

// The recording written as a ROS 2 MCAP bag by other projects' writers (tests/bags/write_recording.mjs:
// its first frames as PNG CompressedImages, its state log as JointState stamped on the video's clock,
// names rotated per message): `kccd calib --bag` solves the same camera and draws the same check
// image (the model at the bag's state of the frame) as `calib --video --states --time`, and
// `overlay --bag` finds the same states, bounds and statuses as the overlay of the files.
TEST_F(Synth, ARecordingAsABagCalibratesAndOverlaysAsItsFiles) {
  const json j = summary();
  const double offset = j["state_log"]["time_offset"], fps = j["video"]["fps"];
  const std::vector<cv::Mat> video = readVideo(dir("a") + "/video.mkv");
  ASSERT_GE(video.size(), 10u);
  fs::create_directories(dir("bagrec"));
  std::string times = "frame,time\n";
  for (int i = 0; i < 10; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/f_%06d.png", i);
    ASSERT_TRUE(cv::imwrite(dir("bagrec") + name, video[static_cast<std::size_t>(i)]));
    times += std::to_string(i) + "," + kccd::shortestNumber(i / fps) + "\n";
  }
  std::ofstream(dir("bagrec") + "/times.csv") << times;
  const std::string bag = dir("bagrec") + "/rec.mcap";
  const Outcome w = kccd::testing::runProgram(
      std::string(KCCD_NODE) + " " + KCCD_SOURCE_DIR + "/tests/bags/write_recording.mjs " + bag + " --images " +
          dir("bagrec") + "/f_%06d.png --frame-times " + dir("bagrec") + "/times.csv --states " + dir("a") +
          "/states.csv --state-offset " + kccd::shortestNumber(offset),
      true);
  ASSERT_EQ(w.code, 0) << "the bag writer failed (npm ci in tests/bags?): " << w.out;
  // calib: frame 0 of the video with the log's state at its time, against frame 0 of the bag.
  const std::string common = "calib --intrinsics " + dir("a") + "/intrinsics.yaml --tags " + dir("a") +
                             "/tags.yaml --model " + kHumanoid + " -q";
  const Outcome files = runKccd(common + " --video " + dir("a") + "/video.mkv --frame 3 --states " + dir("a") +
                                "/states.csv --time " + kccd::shortestNumber(3 / fps + offset) + " -o " +
                                dir("bagrec") + "/cam_files.yaml --check " + dir("bagrec") + "/check_files.png");
  const Outcome from_bag = runKccd(common + " --bag " + bag + " --frame 3 -o " + dir("bagrec") +
                                   "/cam_bag.yaml --check " + dir("bagrec") + "/check_bag.png");
  ASSERT_EQ(files.code, 0) << files.err;
  ASSERT_EQ(from_bag.code, 0) << from_bag.err;
  EXPECT_EQ(from_bag.err, "");
  EXPECT_EQ(kccd::testing::readText(dir("bagrec") + "/cam_bag.yaml"),
            kccd::testing::readText(dir("bagrec") + "/cam_files.yaml"));
  EXPECT_EQ(kccd::testing::readText(dir("bagrec") + "/check_bag.png"),
            kccd::testing::readText(dir("bagrec") + "/check_files.png"));
  // A frame the bag does not have, and options that do not go with --bag: one line each.
  const Outcome beyond = runKccd(common + " --bag " + bag + " --frame 10 -o " + dir("bagrec") + "/x.yaml");
  EXPECT_EQ(beyond.code, 2);
  EXPECT_NE(beyond.err.find("--frame 10: " + bag + " has 10 images on /camera/image_raw/compressed (frames 0 ... 9)"),
            std::string::npos)
      << beyond.err;
  const Outcome both = runKccd(common + " --bag " + bag + " --frame 0 --states " + dir("a") +
                               "/states.csv --time 0 -o " + dir("bagrec") + "/x.yaml");
  EXPECT_EQ(both.code, 2);
  EXPECT_NE(both.err.find("not with --bag"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(dir("bagrec") + "/x.yaml"));
  // overlay: the bag's ten frames against the first ten of the files' run.
  const std::string camera = dir("a") + "/camera_true.yaml";
  const Outcome a = runKccd("overlay " + kHumanoid + " --camera " + camera + " --bag " + bag + " --report " +
                            dir("bagrec") + "/bag.json -q");
  const Outcome b =
      runKccd("overlay " + kHumanoid + " --camera " + camera + " --video " + dir("a") + "/video.mkv --states " +
              dir("a") + "/states.csv --time-offset " + kccd::shortestNumber(offset) + " --frames 0:10 --report " +
              dir("bagrec") + "/files.json -q");
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const json ra = json::parse(kccd::testing::readText(dir("bagrec") + "/bag.json")).at("frames");
  const json rb = json::parse(kccd::testing::readText(dir("bagrec") + "/files.json")).at("frames");
  ASSERT_EQ(ra.size(), 10u);
  int with_state = 0;
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(ra[i].at("status"), rb[i].at("status")) << i;
    EXPECT_EQ(ra[i].at("state"), rb[i].at("state")) << i;
    if (rb[i].at("state") == "none") continue;
    ++with_state;
    const std::vector<double> p = ra[i].at("state_values"), q = rb[i].at("state_values");
    ASSERT_EQ(p.size(), q.size());
    for (std::size_t k = 0; k < p.size(); ++k) EXPECT_NEAR(p[k], q[k], 1e-9) << i << " " << k;
    EXPECT_NEAR(ra[i].at("min_distance").get<double>(), rb[i].at("min_distance").get<double>(), 1e-9) << i;
  }
  EXPECT_GE(with_state, 9);
}

// --bag: states.mcap holds states.csv as a ROS 2 bag. Read back by the suite's reader (`kccd bag
// export`), it is states.csv, every sample (times to the nanosecond, values and velocities
// exactly); `bag info` lists its two topics, every row and every frame; `check --bag` reports what
// `check --states` reports. (Other projects' readers: BagHoldsTheFramesOnTheLogClock.)
TEST_F(Synth, StateLogAsABagIsStatesCsv) {
  const std::string bag = dir("a") + "/states.mcap";
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::StateLog csv = kccd::loadStateLog(dir("a") + "/states.csv", m);
  ASSERT_EQ(csv.times.front(), 0.0);  // the log starts at log time 0: the bag's first stamp
  const json truth = summary()["state_log"]["bag"];
  EXPECT_EQ(truth["file"], "states.mcap");
  EXPECT_EQ(truth["topic"], "/joint_states");
  EXPECT_EQ(truth["type"], "sensor_msgs/msg/JointState");
  EXPECT_EQ(truth["origin_ns"], "1700000000000000000");
  // The suite's own reader.
  const Outcome exported = runKccd("bag export " + bag + " --states " + dir("bagcsv.csv") + " -q");
  ASSERT_EQ(exported.code, 0) << exported.err;
  EXPECT_EQ(exported.err, "");
  const kccd::StateLog back = kccd::loadStateLog(dir("bagcsv.csv"), m);
  ASSERT_EQ(back.rows(), csv.rows());
  for (std::size_t i = 0; i < csv.rows(); ++i) ASSERT_NEAR(back.times[i], csv.times[i], 0.5e-9) << i;
  EXPECT_EQ(back.values, csv.values);
  EXPECT_EQ(back.velocities, csv.velocities);
  // bag info: JointState with every row, CompressedImage with every frame; all messages stamped
  // at their log times (no skew), from the first row's time to the last row's.
  const Outcome info = runKccd("bag info " + bag + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  const json ij = json::parse(info.out);
  EXPECT_TRUE(ij.at("damage").is_null()) << info.out;
  const std::size_t frames = summary()["video"]["frames"];
  EXPECT_EQ(ij.at("messages"), csv.rows() + frames);
  EXPECT_EQ(ij.at("first_log_time_ns"), "1700000000000000000");
  EXPECT_EQ(ij.at("last_log_time_ns"),
            std::to_string(1'700'000'000'000'000'000 + std::llround(csv.times.back() * 1e9)));
  std::map<std::string, json> topics;
  for (const json& t : ij.at("topics")) topics[t.at("topic")] = t;
  ASSERT_EQ(topics.size(), 2u) << info.out;
  const json& joints = topics["/joint_states"];
  const json& images = topics["/camera/image_raw/compressed"];
  EXPECT_EQ(joints.at("type"), "sensor_msgs/msg/JointState");
  EXPECT_EQ(joints.at("count"), csv.rows());
  EXPECT_EQ(images.at("type"), "sensor_msgs/msg/CompressedImage");
  EXPECT_EQ(images.at("count"), frames);
  for (const json* t : {&joints, &images}) {
    EXPECT_EQ(t->at("stamped"), t->at("count"));
    EXPECT_EQ(t->at("skew_s").at("max"), 0.0);
    EXPECT_EQ(t->at("skew_s").at("min"), 0.0);
  }
  EXPECT_NEAR(images.at("rate_hz").get<double>(), kFps, 1e-6);
  // check --bag reports what check --states reports.
  const Outcome by_bag = runKccd("check " + kHumanoid + " --bag " + bag + " --report " + dir("check_bag.json") + " -q");
  const Outcome by_csv =
      runKccd("check " + kHumanoid + " --states " + dir("a") + "/states.csv --report " + dir("check_csv.json") + " -q");
  ASSERT_EQ(by_bag.code, by_csv.code) << by_bag.err << by_csv.err;
  EXPECT_EQ(by_bag.err, "");
  const json rb = json::parse(kccd::testing::readText(dir("check_bag.json"))).at("frames");
  const json rc = json::parse(kccd::testing::readText(dir("check_csv.json"))).at("frames");
  ASSERT_EQ(rb.size(), csv.rows());
  ASSERT_EQ(rb.size(), rc.size());
  for (std::size_t i = 0; i < rb.size(); ++i) {
    EXPECT_EQ(rb[i].at("status"), rc[i].at("status")) << i;
    EXPECT_EQ(rb[i].at("min_distance"), rc[i].at("min_distance")) << i;
  }
}

// Mean absolute difference of two images of one size and type, per channel value, over the pixels
// where `where` is not 0 (all when empty).
double meanAbsDiff(const cv::Mat& a, const cv::Mat& b, const cv::Mat& where = {}) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar m = cv::mean(d, where);
  return (m[0] + m[1] + m[2]) / 3.0;
}

// --bag: the frames are in states.mcap as a robot's camera driver publishes them — JPEG
// CompressedImages stamped on the log's clock, frame i at origin + its log time (synth.json), in
// log-time order with the joint states. The suite's decoder (`kccd bag export --video`, lossless)
// gives every video frame at its log time (up to JPEG's loss; where the robot moved, it is that
// frame and not the one before); other projects' readers (tests/bags/check_mcap.mjs: @mcap/core's stream reader with
// CRCs validated and log-time order checked across topics, its indexed reader of the summary,
// @foxglove/rosmsg2-serialization's CDR decoder) find every joint state as states.csv says and
// every frame's header and format, and the JPEG bytes they take out decode to the same pixels.
TEST_F(Synth, BagHoldsTheFramesOnTheLogClock) {
  const std::string bag = dir("a") + "/states.mcap";
  const json j = summary();
  const json images = j["state_log"]["bag"]["images"];
  EXPECT_EQ(images["topic"], "/camera/image_raw/compressed");
  EXPECT_EQ(images["type"], "sensor_msgs/msg/CompressedImage");
  EXPECT_EQ(images["format"], "bgr8; jpeg compressed bgr8");
  EXPECT_EQ(images["frame_id"], "camera");
  EXPECT_EQ(images["jpeg_quality"], 90);
  const int frames = j["video"]["frames"];
  EXPECT_EQ(images["count"], frames);
  const std::int64_t origin = 1'700'000'000'000'000'000;
  std::vector<std::int64_t> stamps;
  for (const json& f : j["frames"]) stamps.push_back(origin + std::llround(f["log_time"].get<double>() * 1e9));
  ASSERT_EQ(stamps.size(), static_cast<std::size_t>(frames));
  EXPECT_EQ(stamps[0], origin + 137'000'000);  // frame 0 at video time 0 = log time 0.137 s
  // The suite's decoder: every frame, at its log time, showing the video's frame.
  fs::create_directories(dir("bagframes"));
  const Outcome exported =
      runKccd("bag export " + bag + " --states " + dir("bagframes") + "/states.csv --video " + dir("bagframes") +
              "/frames.mkv --frame-times " + dir("bagframes") + "/times.csv -q");
  ASSERT_EQ(exported.code, 0) << exported.err;
  EXPECT_EQ(exported.err, "");
  std::istringstream times(kccd::testing::readText(dir("bagframes") + "/times.csv"));
  std::string line;
  std::getline(times, line);
  EXPECT_EQ(line, "frame,time");
  for (int i = 0; std::getline(times, line); ++i) {
    ASSERT_LT(i, frames);
    const std::string want =
        std::to_string(i) + "," + kccd::shortestNumber(static_cast<double>(stamps[i] - origin) / 1e9);
    EXPECT_EQ(line, want);
    EXPECT_NEAR(std::stod(line.substr(line.find(',') + 1)), j["frames"][i]["log_time"].get<double>(), 1e-9) << i;
  }
  const std::vector<cv::Mat> video = readVideo(dir("a") + "/video.mkv");
  const std::vector<cv::Mat> decoded = readVideo(dir("bagframes") + "/frames.mkv");
  ASSERT_EQ(video.size(), static_cast<std::size_t>(frames));
  ASSERT_EQ(decoded.size(), video.size());
  // Where the robot moved between frame i and the one before (their masks differ), the bag's frame
  // i is video frame i, not the one before; and everywhere it is frame i up to JPEG's loss.
  const auto mask = [&](std::size_t i) {
    char name[32];
    std::snprintf(name, sizeof name, "/masks/frame_%06zu.png", i);
    return cv::imread(dir("a") + name, cv::IMREAD_UNCHANGED);
  };
  double worst = 0, moved_self = 0, moved_other = 1e9;
  int compared = 0;
  for (std::size_t i = 0; i < video.size(); ++i) {
    ASSERT_EQ(decoded[i].size(), video[i].size()) << i;
    worst = std::max(worst, meanAbsDiff(decoded[i], video[i]));
    if (i == 0) continue;
    const cv::Mat moved = mask(i) != mask(i - 1);
    if (cv::countNonZero(moved) < 200) continue;
    const double self = meanAbsDiff(decoded[i], video[i], moved), other = meanAbsDiff(decoded[i], video[i - 1], moved);
    EXPECT_LT(2 * self, other) << "frame " << i << " looks like video frame " << i - 1 << " where the robot moved";
    moved_self = std::max(moved_self, self), moved_other = std::min(moved_other, other);
    ++compared;
  }
  std::printf(
      "bag frames against the video: mean |difference| at most %.3f; where the robot moved at most %.3f, "
      "against the frame before at least %.3f (%d frames)\n",
      worst, moved_self, moved_other, compared);
  EXPECT_LT(worst, 3.0);
  EXPECT_GT(compared, frames / 2);
  // Other projects' readers, against what states.csv and synth.json say the messages hold.
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::StateLog csv = kccd::loadStateLog(dir("a") + "/states.csv", m);
  fs::create_directories(dir("bagcheck"));
  fs::copy_file(bag, dir("bagcheck") + "/states.mcap", fs::copy_options::overwrite_existing);
  json messages = json::array(), jpegs = json::array();
  for (std::size_t i = 0; i < csv.rows(); ++i) {
    const std::int64_t t = origin + std::llround(csv.times[i] * 1e9);
    const auto row = csv.row(i);
    messages.push_back(
        {{"log_time_ns", std::to_string(t)},
         {"stamp_sec", t / 1'000'000'000},
         {"stamp_nanosec", t % 1'000'000'000},
         {"frame_id", ""},
         {"name", csv.names},
         {"position", std::vector<double>(row.begin(), row.end())},
         {"velocity",
          std::vector<double>(csv.velocities.begin() + static_cast<std::ptrdiff_t>(i * csv.stateSize()),
                              csv.velocities.begin() + static_cast<std::ptrdiff_t>((i + 1) * csv.stateSize()))},
         {"effort", json::array()}});
  }
  for (const std::int64_t t : stamps)
    jpegs.push_back({{"log_time_ns", std::to_string(t)},
                     {"stamp_sec", t / 1'000'000'000},
                     {"stamp_nanosec", t % 1'000'000'000},
                     {"frame_id", "camera"},
                     {"format", "bgr8; jpeg compressed bgr8"},
                     {"data_ends", {0xFF, 0xD8, 0xFF, 0xD9}}});  // a JPEG's SOI and EOI markers
  const auto topic = [](const std::string& name, const std::string& type, const json& msgs) {
    return json{{"topic", name},
                {"schema_name", type},
                {"schema_encoding", "ros2msg"},
                {"message_encoding", "cdr"},
                {"count", msgs.size()},
                {"first_log_time_ns", msgs.front()["log_time_ns"]},
                {"last_log_time_ns", msgs.back()["log_time_ns"]}};
  };
  const json want = {{"profile", "ros2"},
                     {"library", "kccd"},
                     {"files",
                      {{"states.mcap",
                        {{"compression", nullptr},
                         {"topics",
                          {topic("/joint_states", "sensor_msgs/msg/JointState", messages),
                           topic("/camera/image_raw/compressed", "sensor_msgs/msg/CompressedImage", jpegs)}}}}}},
                     {"joint_states", messages},
                     {"compressed_images", jpegs},
                     {"dump_images", "jpeg"},
                     {"images", json::array()},
                     {"camera_infos", json::array()}};
  std::ofstream(dir("bagcheck") + "/truth.json") << want.dump();
  const Outcome independent = kccd::testing::runProgram(
      std::string(KCCD_NODE) + " " + KCCD_SOURCE_DIR + "/tests/bags/check_mcap.mjs " + dir("bagcheck"), true);
  EXPECT_EQ(independent.code, 0) << "@mcap/core's readers (npm ci in tests/bags?): " << independent.out;
  EXPECT_NE(independent.out.find("OK: all files match truth.json"), std::string::npos) << independent.out;
  for (int i = 0; i < frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/jpeg/%06d.jpg", i);
    const cv::Mat f = cv::imread(dir("bagcheck") + name, cv::IMREAD_COLOR);
    ASSERT_FALSE(f.empty()) << name;
    EXPECT_EQ(cv::norm(f, decoded[static_cast<std::size_t>(i)], cv::NORM_INF), 0.0) << name;
  }
}

// overlay --bag on states.mcap: the camera's frames with the joint states at their own times, no
// clock offset given, show what the overlay of video.mkv and states.csv shows at the true offset
// (synth.json's): per frame the same state, bound and status, and the colliding frames are
// synth.json's. The files at no offset do not: the bag's clock is the log's.
TEST_F(Synth, OverlayOnTheBagIsTheOverlayOfTheFiles) {
  const json j = summary();
  const double offset = j["state_log"]["time_offset"];
  const std::string camera = dir("a") + "/camera_true.yaml";
  fs::create_directories(dir("bagoverlay"));
  const std::string out = dir("bagoverlay");
  const Outcome a = runKccd("overlay " + kHumanoid + " --camera " + camera + " --bag " + dir("a") + "/states.mcap -o " +
                            out + "/bag.mp4 --report " + out + "/bag.json -q");
  const Outcome b = runKccd("overlay " + kHumanoid + " --camera " + camera + " --video " + dir("a") +
                            "/video.mkv --states " + dir("a") + "/states.csv --time-offset " +
                            kccd::shortestNumber(offset) + " --report " + out + "/files.json -q");
  const Outcome c = runKccd("overlay " + kHumanoid + " --camera " + camera + " --video " + dir("a") +
                            "/video.mkv --states " + dir("a") + "/states.csv --report " + out + "/no_offset.json -q");
  ASSERT_EQ(a.code, b.code) << a.err << b.err;
  EXPECT_EQ(a.err, "");
  EXPECT_TRUE(fs::is_regular_file(out + "/bag.mp4"));
  const json bag = json::parse(kccd::testing::readText(out + "/bag.json"));
  const json ra = bag.at("frames");
  const json rb = json::parse(kccd::testing::readText(out + "/files.json")).at("frames");
  const json rc = json::parse(kccd::testing::readText(out + "/no_offset.json")).at("frames");
  EXPECT_EQ(bag.at("source").at("image_topic"), "/camera/image_raw/compressed");
  EXPECT_EQ(bag.at("source").at("joint_topic"), "/joint_states");
  EXPECT_EQ(bag.at("source").at("origin_ns"), "1700000000000000000");
  const json& truth = j["frames"];
  ASSERT_EQ(ra.size(), truth.size());
  ASSERT_EQ(rb.size(), truth.size());
  std::vector<int> colliding;
  int differ_without_offset = 0;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    EXPECT_NEAR(ra[i].at("time").get<double>(), truth[i]["log_time"].get<double>(), 1e-9) << i;
    EXPECT_EQ(ra[i].at("status"), rb[i].at("status")) << i;
    EXPECT_EQ(ra[i].at("status"), truth[i]["status"]) << i;
    EXPECT_EQ(ra[i].at("state"), rb[i].at("state")) << i;
    ASSERT_NE(ra[i].at("state"), "none") << i;
    const std::vector<double> p = ra[i].at("state_values"), q = rb[i].at("state_values");
    ASSERT_EQ(p.size(), q.size());
    for (std::size_t k = 0; k < p.size(); ++k) EXPECT_NEAR(p[k], q[k], 1e-7) << i << " " << k;
    EXPECT_NEAR(ra[i].at("min_distance").get<double>(), rb[i].at("min_distance").get<double>(), 1e-7) << i;
    if (ra[i].at("status") == "colliding") colliding.push_back(static_cast<int>(i));
    differ_without_offset += ra[i].at("status") != rc[i].at("status");
  }
  EXPECT_FALSE(colliding.empty());
  EXPECT_EQ(colliding, j["collision"]["frames"].get<std::vector<int>>());
  EXPECT_EQ(bag.at("colliding"), colliding.size());
  EXPECT_GT(differ_without_offset, 0);
}

// Two runs with one seed write the same bytes: a short recording each (the fixture's is long
// enough for a collision; determinism does not need one), so the check costs little.
// kccd overlay --masks: the recording's own masks (drawn by the GL renderer at 0.8 of the volumes'
// radius; the IoU is computed from calib's CPU silhouette of the volumes, which shares no code with
// it) agree evenly with the logged states at the true clock offset; 0.2 s off, the agreement drops
// and the frames where the robot moves fast stand out as low.
TEST_F(Synth, OverlayMasksAgreeAtTheTrueClockAndNotAtAWrongOne) {
  const double offset = summary()["state_log"]["time_offset"].get<double>();
  const auto agreement = [&](double t, const std::string& name) {
    const Outcome r =
        runKccd("overlay " + kHumanoid + " --camera " + dir("a") + "/camera_true.yaml --video " + dir("a") +
                "/video.mkv --states " + dir("a") + "/states.csv --masks " + dir("a") + "/masks --time-offset " +
                kccd::formatNumber(t, 17) + " --report " + dir(name) + ".json --timeline " + dir(name) + ".png -q");
    EXPECT_EQ(r.code, 0) << r.err;
    return json::parse(kccd::testing::readText(dir(name) + ".json"));
  };
  const json right = agreement(offset, "agree_right"), wrong = agreement(offset + 0.2, "agree_wrong");
  const json& a = right["mask_agreement"];
  const json& b = wrong["mask_agreement"];
  std::printf("true clock: mean IoU %.3f (smallest %.3f, %d low); 0.2 s off: %.3f (smallest %.3f, %d low)\n",
              a["mean_iou"].get<double>(), a["min_iou"].get<double>(), a["low_frames"].get<int>(),
              b["mean_iou"].get<double>(), b["min_iou"].get<double>(), b["low_frames"].get<int>());
  EXPECT_EQ(a["frames"].get<int>(), static_cast<int>(std::lround(kSeconds * kFps)));
  EXPECT_GT(a["min_iou"].get<double>(), 0.7);
  EXPECT_EQ(a["low_frames"].get<int>(), 0);
  EXPECT_LT(b["mean_iou"].get<double>(), a["mean_iou"].get<double>() - 0.05);
  EXPECT_GT(b["low_frames"].get<int>(), 3);
  for (const json& f : right["frames"]) EXPECT_TRUE(f.contains("mask_iou")) << f.dump();
  EXPECT_TRUE(fs::exists(dir("agree_wrong") + ".png"));
}

TEST_F(Synth, SameSeedSameFiles) {
  for (const char* name : {"b1", "b2"}) {
    const Outcome r = runKccd("synth " + kHumanoid + " -o " + dir(name) + " --seconds 0.6 --fps 10 --seed 3 --bag -q");
    ASSERT_EQ(r.code, 0) << r.err;
  }
  for (const char* f : {"states.csv", "states.mcap", "camera_true.yaml", "intrinsics.yaml", "tags.yaml"})
    EXPECT_EQ(kccd::testing::readText(dir("b1") + "/" + f), kccd::testing::readText(dir("b2") + "/" + f)) << f;
  json ja = summary("b1"), jb = summary("b2");
  ja.erase("timing"), jb.erase("timing");
  EXPECT_EQ(ja, jb);
  int masks = 0;
  for (const auto& e : fs::directory_iterator(dir("b1") + "/masks")) {
    EXPECT_EQ(kccd::testing::readText(e.path().string()),
              kccd::testing::readText(dir("b2") + "/masks/" + e.path().filename().string()))
        << e.path();
    ++masks;
  }
  EXPECT_EQ(masks, 6);
  const std::vector<cv::Mat> va = readVideo(dir("b1") + "/video.mkv"), vb = readVideo(dir("b2") + "/video.mkv");
  ASSERT_EQ(va.size(), 6u);
  ASSERT_EQ(va.size(), vb.size());
  for (std::size_t i = 0; i < va.size(); ++i) EXPECT_EQ(cv::norm(va[i], vb[i], cv::NORM_INF), 0.0) << i;
  // A different seed: a different recording.
  const Outcome other = runKccd("synth " + kHumanoid + " -o " + dir("b3") + " --seconds 0.6 --fps 10 --seed 4 -q");
  ASSERT_EQ(other.code, 0) << other.err;
  EXPECT_NE(kccd::testing::readText(dir("b1") + "/states.csv"), kccd::testing::readText(dir("b3") + "/states.csv"));
}

TEST_F(Synth, NoCollisionOption) {
  const Outcome r =
      runKccd("synth " + kHumanoid + " -o " + dir("c") + " --seconds 1 --fps 8 --seed 5 --no-collision -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = summary("c");
  EXPECT_TRUE(j["collision"]["frames"].empty());
  EXPECT_EQ(j["video"]["frames"], 8);
  for (const json& f : j["frames"]) EXPECT_GT(static_cast<double>(f["min_distance"]), 0.0);
}

// A model with visuals: the recording shows the visual meshes (an OBJ for the upper arm, boxes
// and a cylinder), the masks label them with the body in their frame, and synth.json says so.
// The demo arm with three visuals (a cylinder, an OBJ mesh, a box), written as `path`, its mesh
// as upper_arm.obj beside it.
void writeVisualArm(const std::string& path) {
  std::string model = kccd::testing::readText(kData + "/demo_arm.yaml");
  {
    std::ofstream obj(fs::path(path).parent_path() / "upper_arm.obj");
    for (int i = 0; i < 8; ++i)
      obj << "v " << (i & 1 ? 0.4 : 0.0) << " " << (i & 2 ? 0.04 : -0.04) << " " << (i & 4 ? 0.04 : -0.04) << "\n";
    obj << "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 "
           "6\n";
  }
  model +=
      "visuals:\n"
      "  - frame: world\n    cylinder: {radius: 0.08, length: 0.35}\n    origin: {xyz: [0, 0, 0.175]}\n"
      "  - frame: shoulder_pitch\n    mesh: upper_arm.obj\n    colour: [0.9, 0.4, 0.1]\n"
      "  - frame: elbow\n    box: [0.4, 0.07, 0.07]\n    origin: {xyz: [0.2, 0, 0]}\n";
  std::ofstream(path) << model;
}

// kccd calib --masks draws what the robot looks like: masks of the visual geometry (drawn by the
// GL renderer in synth) give the true camera back from the visuals (a CPU raster of the same
// meshes, sharing no code with it), closer than from the volumes, which are wider than the visuals.
TEST_F(Synth, MaskRefinementDrawsTheModelsVisuals) {
  writeVisualArm(dir("visual_arm_masks.yaml"));
  const Outcome r = runKccd("synth " + dir("visual_arm_masks.yaml") + " -o " + dir("vm") +
                            " --seconds 0.4 --fps 10 --seed 4 --no-collision -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const double offset = summary("vm")["state_log"]["time_offset"].get<double>();
  kccd::calib::Camera rough = kccd::calib::loadCamera(dir("vm") + "/camera_true.yaml");
  rough.tvec[0] += 0.05;
  rough.tvec[1] -= 0.03;
  kccd::calib::saveCamera(rough, dir("vm_rough.yaml"));
  const auto calib = [&](const std::string& draw, const std::string& bodies) {
    const Outcome c =
        runKccd("calib --intrinsics " + dir("vm") + "/intrinsics.yaml --video " + dir("vm") +
                "/video.mkv --frame 0 --frame 3" + " --time " + kccd::formatNumber(offset, 17) + " --time " +
                kccd::formatNumber(offset + 0.3, 17) + " --model " + dir("visual_arm_masks.yaml") + " --states " +
                dir("vm") + "/states.csv --masks " + dir("vm") + "/masks/frame_000000.png " + dir("vm") +
                "/masks/frame_000003.png --camera " + dir("vm_rough.yaml") + " --truth " + dir("vm") +
                "/camera_true.yaml --draw " + draw + bodies + " -o " + dir("vm_" + draw + ".yaml") + " --json");
    EXPECT_EQ(c.code, 0) << c.err << c.out;
    return json::parse(c.out);
  };
  const json visuals = calib("visuals", ""), volumes = calib("volumes", " --mask-bodies pedestal,upper_arm,forearm");
  EXPECT_EQ(visuals["refinement"]["drawn"], "visual meshes");
  EXPECT_EQ(volumes["refinement"]["drawn"], "collision volumes (asked for)");
  const double vis_deg = visuals["truth_error"]["rotation_deg"].get<double>(),
               vis_m = visuals["truth_error"]["position_m"].get<double>();
  const double vol_deg = volumes["truth_error"]["rotation_deg"].get<double>(),
               vol_m = volumes["truth_error"]["position_m"].get<double>();
  std::printf("drawn visuals: %.3f deg, %.2f mm; volumes: %.3f deg, %.2f mm from the true camera\n", vis_deg,
              vis_m * 1e3, vol_deg, vol_m * 1e3);
  EXPECT_LT(vis_deg, 0.1);
  EXPECT_LT(vis_m, 0.004);
  EXPECT_LT(vis_m, vol_m);
  for (const json& f : visuals["refinement"]["frames"]) EXPECT_GT(f["iou_after"].get<double>(), 0.95);
}

TEST_F(Synth, DrawsTheModelsVisualGeometry) {
  writeVisualArm(dir("visual_arm.yaml"));
  const Outcome info = runKccd("info " + dir("visual_arm.yaml") + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  const json ij = json::parse(info.out);
  ASSERT_TRUE(ij.contains("visuals")) << info.out;
  EXPECT_EQ(ij.at("totals").at("visuals"), 3);
  EXPECT_EQ(ij.at("visuals").at(1).at("shape"), "mesh");
  EXPECT_EQ(fs::path(ij.at("visuals").at(1).at("mesh").get<std::string>()).filename(), "upper_arm.obj");
  const Outcome r = runKccd("synth " + dir("visual_arm.yaml") + " -o " + dir("v") +
                            " --seconds 0.4 --fps 10 --seed 2 --no-collision -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = summary("v");
  EXPECT_EQ(j.at("masks").at("appearance"), "visuals") << j.at("masks").dump();
  // Labels: body i + 1 of the first body in each visual's frame (pedestal 1, upper_arm 5, forearm 6).
  std::vector<int> seen(256, 0);
  for (int f = 0; f < 4; ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "/masks/frame_%06d.png", f);
    const cv::Mat mask = cv::imread(dir("v") + name, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty()) << name;
    for (int y = 0; y < mask.rows; ++y)
      for (int x = 0; x < mask.cols; ++x) ++seen[mask.at<uchar>(y, x)];
  }
  EXPECT_GT(seen[1], 0);
  EXPECT_GT(seen[5], 0);
  EXPECT_GT(seen[6], 0);
  for (int label = 2; label < 256; ++label) {
    if (label != 5 && label != 6) {
      EXPECT_EQ(seen[label], 0) << label;  // no visual for the other bodies
    }
  }
  // `kccd overlay --visuals` draws the same appearance over the recording: where the visuals'
  // mask says the robot is, the overlay with --visuals differs from the one without.
  const std::string common = "overlay " + dir("visual_arm.yaml") + " --camera " + dir("v") +
                             "/camera_true.yaml --video " + dir("v") + "/video.mkv --states " + dir("v") +
                             "/states.csv --time-offset 0.137 -q --plain";
  const Outcome with = runKccd(common + " --visuals --png-dir " + dir("ov_with"));
  ASSERT_EQ(with.code, 0) << with.err;
  const Outcome without = runKccd(common + " --png-dir " + dir("ov_without"));
  ASSERT_EQ(without.code, 0) << without.err;
  const cv::Mat a = cv::imread(dir("ov_with") + "/frame_000000.png"),
                b = cv::imread(dir("ov_without") + "/frame_000000.png");
  const cv::Mat robot = cv::imread(dir("v") + "/masks/frame_000000.png", cv::IMREAD_UNCHANGED) > 0;
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), robot.size());
  cv::Mat diff, changed;
  cv::absdiff(a, b, diff);
  cv::cvtColor(diff, changed, cv::COLOR_BGR2GRAY);
  changed = changed > 0;
  EXPECT_GT(cv::countNonZero(changed & robot), cv::countNonZero(robot) / 2);
  const Outcome none =
      runKccd("overlay " + kData + "/demo_arm.yaml --camera " + dir("v") + "/camera_true.yaml --video " + dir("v") +
              "/video.mkv --states " + dir("v") + "/states.csv -q --visuals --png-dir " + dir("ov_none"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("has no visuals"), std::string::npos) << none.err;
  const Outcome scale =
      runKccd("synth " + dir("visual_arm.yaml") + " -o " + dir("s") + " --seconds 0.2 --visible-scale 0.5 -q");
  EXPECT_EQ(scale.code, 2);
  EXPECT_NE(scale.err.find("--visible-scale"), std::string::npos) << scale.err;
  // A visual mesh that cannot be read is one line naming the visual and the file.
  std::ofstream(dir("broken_visual.yaml"))
      << kccd::testing::readText(kData + "/demo_arm.yaml") << "visuals:\n  - frame: world\n    mesh: missing.obj\n";
  const Outcome e = runKccd("synth " + dir("broken_visual.yaml") + " -o " + dir("w") + " --seconds 0.2 -q");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("visuals[0]: "), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("missing.obj"), std::string::npos) << e.err;
  EXPECT_EQ(std::count(e.err.begin(), e.err.end(), '\n'), 1) << e.err;
}

TEST_F(Synth, BadInputIsOneLineExitTwo) {
  struct Case {
    std::string args, says;
  };
  fs::create_directories(dir("full"));
  { std::ofstream(dir("full") + "/keep.txt") << "mine"; }
  const Case cases[] = {
      {"synth " + kData + "/no_such_model.yaml -o " + dir("x"), "no_such_model.yaml"},
      {"synth " + kHumanoid + " -o " + dir("x") + " --codec h265", "--codec"},
      {"synth " + kHumanoid + " -o " + dir("x") + " --fps 0", "--fps"},
      {"synth " + kHumanoid + " -o " + dir("x") + " --log-rate 25", "--log-rate"},
      {"synth " + kHumanoid + " -o " + dir("nowhere/x"), "does not exist"},
      {"synth " + kHumanoid + " -o " + dir("full"), "--force"},
      {"synth " + kHumanoid + " -o " + dir("x") + " --camera " + dir("nothing.yaml"), "nothing.yaml"},
      {"synth " + kHumanoid + " -o " + dir("x") + " --camera " + dir("a") + "/camera_true.yaml --width 640", "--width"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("kccd: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir("x")));
  }
  EXPECT_EQ(kccd::testing::readText(dir("full") + "/keep.txt"), "mine");
}

}  // namespace

namespace {

// The main job's chain, end to end: the camera calibrated from the recording's tags, each frame's
// state matched from the log by time (log clock = video clock + the offset), the volumes drawn
// as the overlay draws them: every pixel of the robot's visible geometry lies inside them.
TEST_F(Synth, CalibratedOverlayCoversTheVisibleGeometry) {
  const json j = summary();
  const std::string solved = dir("overlay_camera.yaml");
  const Outcome r = runKccd("calib --intrinsics " + dir("a") + "/intrinsics.yaml --video " + dir("a") +
                            "/video.mkv --frame 0 --tags " + dir("a") + "/tags.yaml -o " + solved + " -q");
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const kccd::Model m = kccd::loadModel(kHumanoid);
  const kccd::StateLog log = kccd::loadStateLog(dir("a") + "/states.csv", m);
  const double offset = j["state_log"]["time_offset"], fps = j["video"]["fps"];
  kccd::render::Renderer renderer(kccd::calib::loadCamera(solved));  // the overlay's default options
  kccd::Checker checker(m);
  std::vector<double> s(static_cast<std::size_t>(m.stateSize()));
  int frames_checked = 0;
  for (const json& f : j["frames"]) {
    const int index = f["index"];
    if (kccd::stateAt(log, index / fps + offset, 1.5 * log.medianPeriod(), s) == kccd::StateMatch::None) continue;
    checker.query(s, s, kccd::QueryOptions{.type = kccd::QueryType::Distances});
    const kccd::render::Frame frame =
        renderer.render(kccd::render::staticSceneVolumes(m, checker, s, {}), {}, false, true);
    char name[32];
    std::snprintf(name, sizeof name, "/masks/frame_%06d.png", index);
    const cv::Mat visible = cv::imread(dir("a") + name, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(visible.size(), frame.mask.size());
    EXPECT_EQ(cv::countNonZero((visible > 0) & (frame.mask == 0)), 0) << name;
    ++frames_checked;
  }
  EXPECT_EQ(frames_checked, static_cast<int>(j["frames"].size()));  // the log covers every frame
}

}  // namespace
