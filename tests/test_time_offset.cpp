// The video clock and the time-offset search: a recording whose image motion follows a state
// log shifted by a known offset gives that offset back; too short a recording is one line.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/recording/time_offset.hpp"
#include "kccd/overlay/recording/video_source.hpp"
#include "kccd/state_log.hpp"

namespace fs = std::filesystem;
using kccd::overlay::FrameClock;

namespace {

TEST(FrameClock, FrameTimesWinOverTheRate) {
  const FrameClock rate({}, 25.0);
  EXPECT_DOUBLE_EQ(rate(0), 0.0);
  EXPECT_DOUBLE_EQ(rate(50), 2.0);
  EXPECT_DOUBLE_EQ(rate.nominalFps(), 25.0);
  EXPECT_FALSE(rate.fromFrameTimes());
  const FrameClock listed({0.0, 0.1, 0.25, 0.35}, 25.0);
  EXPECT_DOUBLE_EQ(listed(2), 0.25);
  EXPECT_TRUE(std::isnan(listed(4)));  // past the list: no time, never index / fps
  EXPECT_DOUBLE_EQ(listed.nominalFps(), 25.0);
  const FrameClock times_only({0.0, 0.1, 0.25, 0.35}, 0.0);
  EXPECT_NEAR(times_only.nominalFps(), 10.0, 1e-9);  // the median step, 0.1 s
  EXPECT_DOUBLE_EQ(FrameClock({}, 0.0).nominalFps(), 25.0);
  EXPECT_TRUE(std::isnan(FrameClock({}, 0.0)(3)));
}

// One prismatic joint; the video shows a square whose speed follows the joint's, `shift` seconds
// later on the log's clock (log time = video time + shift).
class TimeOffsetSearch : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_time_offset_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    model_ = kccd::parseModel(
        "kccd: 1\njoints:\n  - {name: x, parent: world, type: prismatic, axis: [1, 0, 0], limits: [-10, 10]}\n"
        "bodies:\n  - {name: b, frame: x, points: [[0, 0, 0]], radius: 0.1}\n",
        "slide.yaml");
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The joint's position at log time t: bursts of motion of different lengths and speeds.
  static double position(double t) { return std::sin(1.3 * t) + 0.5 * std::sin(3.1 * t + 0.4) + 0.2 * t; }
  void write(int frames, double fps, double shift) {
    std::ofstream log(dir_ / "states.csv");
    log << "time,x\n";
    for (int i = 0; i <= 800; ++i) log << i * 0.01 << "," << position(i * 0.01) << "\n";
    log.close();
    cv::VideoWriter w((dir_ / "clip.mkv").string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), fps,
                      cv::Size(160, 120), true);
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < frames; ++i) {
      cv::Mat m(120, 160, CV_8UC3, cv::Scalar(40, 40, 40));
      const double x = 80 + 30 * position(i / fps + shift);
      cv::rectangle(m, cv::Rect(static_cast<int>(std::lround(x)) - 10, 50, 20, 20), cv::Scalar(255, 255, 255),
                    cv::FILLED);
      w.write(m);
    }
  }
  fs::path dir_;
  kccd::Model model_;
};

TEST_F(TimeOffsetSearch, FindsTheShiftWithinOneGridStep) {
  const double fps = 20.0, shift = 0.35;
  write(80, fps, shift);
  const kccd::StateLog log = kccd::loadStateLog((dir_ / "states.csv").string(), model_);
  kccd::overlay::VideoSource video((dir_ / "clip.mkv").string());
  const kccd::overlay::TimeOffset found =
      kccd::overlay::findTimeOffset(video, FrameClock({}, fps), log, 0.05, 0.0, 1.0, "--time-offset auto:0:1");
  EXPECT_NEAR(found.offset, shift, 0.5 * 0.01 + 1e-9);  // grid: half the log period
  EXPECT_GT(found.correlation, 0.9);
  EXPECT_EQ(found.pairs, 79u);
}

TEST_F(TimeOffsetSearch, TooShortARecordingIsOneLine) {
  write(6, 20.0, 0.0);
  const kccd::StateLog log = kccd::loadStateLog((dir_ / "states.csv").string(), model_);
  kccd::overlay::VideoSource video((dir_ / "clip.mkv").string());
  try {
    kccd::overlay::findTimeOffset(video, FrameClock({}, 20.0), log, 0.05, 0.0, 1.0, "--time-offset auto:0:1");
    FAIL() << "6 frames were enough";
  } catch (const kccd::overlay::TimeOffsetError& e) {
    EXPECT_EQ(std::string(e.what()), "--time-offset auto:0:1: needs at least 11 frames, the video has 6");
  }
}

}  // namespace
