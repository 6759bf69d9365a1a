// kccd::overlay::synthesizeRecording called directly (no command line): a short, small recording of
// the demo arm whose files are all there, whose video reads back through the library's own
// VideoSource, whose reported result matches synth.json, and whose truth agrees with distance
// queries this test runs itself at the logged states. Options that cannot make a recording are a
// SynthError that leaves nothing at the target.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/checker.hpp"
#include "kccd/overlay/recording/video_source.hpp"
#include "kccd/overlay/synth/synth.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/state_log.hpp"
#include "support/files.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::overlay::SynthError;
using kccd::overlay::SynthOptions;
using kccd::overlay::SynthResult;
using nlohmann::json;

const std::string kArm = std::string(KCCD_DATA_DIR) + "/demo_arm.yaml";

// 1 s at 10 fps, 640 x 480 (the smallest default camera that sees four whole tags of the arm's room).
SynthOptions smallRecording(const fs::path& out) {
  SynthOptions o;
  o.model = kArm;
  o.output = out.string();
  o.seconds = 1.0;
  o.fps = 10.0;
  o.width = 640;
  o.height = 480;
  o.seed = 1;
  return o;
}

// One recording shared by the tests (the synthesis is the slow part).
class SynthLib : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(kccd::testing::scratchFolder("kccd_synth_lib"));
    progress_ = new std::vector<double>;
    result_ = new SynthResult(kccd::overlay::synthesizeRecording(
        smallRecording(*root_ / "rec"), [](double fraction) { progress_->push_back(fraction); }));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
    delete progress_;
    delete result_;
  }
  static fs::path dir() { return *root_ / "rec"; }
  static json truth() { return json::parse(kccd::testing::readText((dir() / "synth.json").string())); }
  static inline fs::path* root_ = nullptr;
  static inline std::vector<double>* progress_ = nullptr;
  static inline SynthResult* result_ = nullptr;
};

TEST_F(SynthLib, WritesEveryFileAndReportsIt) {
  const SynthResult& r = *result_;
  EXPECT_EQ(r.folder, dir());
  EXPECT_EQ(r.video_file, "video.mkv");
  EXPECT_EQ(r.frames, 10);
  EXPECT_EQ(r.width, 640);
  EXPECT_EQ(r.height, 480);
  EXPECT_FALSE(r.visuals);  // demo_arm has no visuals: its shrunken volumes are drawn
  for (const char* f : {"video.mkv", "states.csv", "camera_true.yaml", "intrinsics.yaml", "tags.yaml", "synth.json"})
    EXPECT_TRUE(fs::is_regular_file(dir() / f)) << f;
  // Nothing but the folder is left in the parent (the staged folder was renamed into place).
  int entries = 0;
  for (const auto& e : fs::directory_iterator(*root_)) {
    EXPECT_EQ(e.path().filename(), "rec");
    ++entries;
  }
  EXPECT_EQ(entries, 1);

  // The video through the library's reader: every frame, at the camera's size.
  kccd::overlay::VideoSource video((dir() / r.video_file).string());
  cv::Mat frame;
  int frames = 0;
  const kccd::Model m = kccd::loadModel(kArm);
  long robot_pixels = 0;
  while (video.read(frame)) {
    EXPECT_EQ(frame.cols, r.width);
    EXPECT_EQ(frame.rows, r.height);
    char name[32];
    std::snprintf(name, sizeof name, "masks/frame_%06d.png", frames);
    const cv::Mat mask = cv::imread((dir() / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_8UC1) << name;
    EXPECT_EQ(mask.size(), frame.size()) << name;
    double top = 0;
    cv::minMaxLoc(mask, nullptr, &top);
    EXPECT_LE(top, static_cast<double>(m.bodies.size())) << name << ": labels are body index + 1";
    robot_pixels += cv::countNonZero(mask);
    ++frames;
  }
  EXPECT_EQ(frames, r.frames);
  EXPECT_GT(robot_pixels, 0);

  // The files agree with the result and with each other.
  const json j = truth();
  EXPECT_EQ(j["video"]["frames"], r.frames);
  EXPECT_EQ(j["video"]["file"], r.video_file);
  EXPECT_EQ(j["tags"]["count"], r.tags);
  EXPECT_GE(r.tags, 4u);
  EXPECT_EQ(kccd::calib::loadTagLayout((dir() / "tags.yaml").string()).tags.size(), r.tags);
  const kccd::calib::Camera cam = kccd::calib::loadCamera((dir() / "camera_true.yaml").string());
  EXPECT_EQ(cam.width, r.width);
  EXPECT_EQ(cam.height, r.height);
  EXPECT_EQ(kccd::loadStateLog((dir() / "states.csv").string(), m).rows(), r.log_rows);

  // Progress: once per frame, rising to 1.
  ASSERT_EQ(progress_->size(), static_cast<std::size_t>(r.frames));
  EXPECT_TRUE(std::is_sorted(progress_->begin(), progress_->end()));
  EXPECT_EQ(progress_->back(), 1.0);
}

// The truth against queries run here: each frame's state is the log's at video time + offset, its
// smallest distance bound is the Checker's at that state, its status the core vocabulary's word,
// and the colliding and within-margin frames are exactly those the queries say.
TEST_F(SynthLib, TruthAgreesWithOwnQueries) {
  const SynthResult& r = *result_;
  const json j = truth();
  const kccd::Model m = kccd::loadModel(kArm);
  const kccd::StateLog log = kccd::loadStateLog((dir() / "states.csv").string(), m);
  const double offset = j["state_log"]["time_offset"];
  EXPECT_EQ(offset, r.time_offset);
  kccd::Checker checker(m);
  std::vector<double> s(log.stateSize());
  std::vector<int> colliding, near;
  ASSERT_EQ(j["frames"].size(), static_cast<std::size_t>(r.frames));
  for (int i = 0; i < r.frames; ++i) {
    const json& f = j["frames"][i];
    ASSERT_EQ(f["index"], i);
    ASSERT_NE(kccd::stateAt(log, i / r.fps + offset, 1.5 / r.log_rate, s), kccd::StateMatch::None) << i;
    EXPECT_EQ(f["state"].get<std::vector<double>>(), s) << "frame " << i;
    checker.reset();
    const kccd::QueryResult& q = checker.query(s, s, kccd::QueryOptions{.type = kccd::QueryType::Distances});
    ASSERT_EQ(q.status, kccd::Status::Ok);
    EXPECT_EQ(q.min_distance, f["min_distance"].get<double>()) << "frame " << i;
    EXPECT_EQ(q.min_distance, r.min_distance[i]) << "frame " << i;
    const kccd::SafetyStatus status = kccd::safetyStatus(q.min_distance, m.safety_margin);
    EXPECT_EQ(f["status"], kccd::toString(status)) << "frame " << i;
    if (status == kccd::SafetyStatus::Colliding) colliding.push_back(i);
    if (status == kccd::SafetyStatus::WithinMargin) near.push_back(i);
  }
  EXPECT_EQ(colliding, j["collision"]["frames"].get<std::vector<int>>());
  EXPECT_EQ(near, j["near_collision_frames"].get<std::vector<int>>());
  EXPECT_EQ(colliding, r.colliding_frames);
  EXPECT_EQ(near, r.near_frames);
  // One real collision: a single run of colliding frames, inside the recording.
  ASSERT_FALSE(colliding.empty());
  ASSERT_EQ(r.collision_intervals.size(), 1u);
  EXPECT_EQ(r.collision_intervals[0][0], colliding.front());
  EXPECT_EQ(r.collision_intervals[0][1], colliding.back());
  EXPECT_EQ(colliding.back() - colliding.front() + 1, static_cast<int>(colliding.size()));
  EXPECT_LT(static_cast<int>(colliding.size()), r.frames);
}

// Options that cannot make a recording: SynthError (an InputError) naming the option's field, and
// nothing at the target.
TEST_F(SynthLib, BadOptionsAreSynthErrors) {
  struct Case {
    const char* says;
    void (*change)(SynthOptions&);
  };
  const Case cases[] = {
      {"fps", [](SynthOptions& o) { o.fps = 0.5; }},
      {"log_rate", [](SynthOptions& o) { o.log_rate = o.fps; }},
      {"time_offset", [](SynthOptions& o) { o.time_offset = -0.1; }},
      {"codec", [](SynthOptions& o) { o.codec = "h265"; }},
      {"visible_scale", [](SynthOptions& o) { o.visible_scale = 1.5; }},
      {"width", [](SynthOptions& o) { o.width = 32; }},
      {"appearance", [](SynthOptions& o) { o.appearance = kccd::overlay::SynthAppearance::Visuals; }},
      {"output", [](SynthOptions& o) { o.output = (fs::path(o.output).parent_path() / "rec").string(); }},  // exists
  };
  for (const Case& c : cases) {
    SynthOptions o = smallRecording(*root_ / "bad");
    c.change(o);
    try {
      kccd::overlay::synthesizeRecording(o);
      ADD_FAILURE() << c.says << ": no error";
    } catch (const SynthError& e) {
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
      // An option out of range is named by its field (no source), for each front end to spell.
      if (std::string(c.says) != "output") {  // a path: "output PATH: exists ..."
        EXPECT_TRUE(e.location().source.empty() && e.location().field == c.says) << e.what();
      }
    }
    EXPECT_FALSE(fs::exists(*root_ / "bad")) << c.says;
  }
  EXPECT_TRUE(fs::is_regular_file(dir() / "synth.json"));  // the existing recording is untouched
}

}  // namespace
