// Recordings in: a video file and the same frames as an image sequence read alike, frame by
// frame, and every way a recording cannot be read is one line naming it.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/overlay/recording/video_source.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using kccd::overlay::VideoError;
using kccd::overlay::VideoSource;

namespace {

class VideoSourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_video_source_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "seq");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Frame i: a grey level and a square whose place depends on i.
  static cv::Mat frame(int i) {
    cv::Mat m(48, 64, CV_8UC3, cv::Scalar(20 * i, 40, 200 - 20 * i));
    cv::rectangle(m, cv::Rect(4 * i, 8, 10, 10), cv::Scalar(255, 255, 255), cv::FILLED);
    return m;
  }
  static std::string errorOf(const std::string& p, const std::string& label = "") {
    try {
      VideoSource v(p, label);
      return "";
    } catch (const VideoError& e) {
      return e.what();
    }
  }
  fs::path dir_;
};

TEST_F(VideoSourceTest, AVideoAndItsImageSequenceGiveTheSameFrames) {
  constexpr int kFrames = 6;
  {
    cv::VideoWriter w(path("clip.mkv"), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 12.5,
                      cv::Size(64, 48), true);
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < kFrames; ++i) w.write(frame(i));
  }
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "seq/frame_%06d.png", i);
    ASSERT_TRUE(cv::imwrite(path(name), frame(i)));
  }
  VideoSource video(path("clip.mkv"), "--video clip.mkv");
  VideoSource sequence(path("seq/frame_%06d.png"));
  EXPECT_FALSE(video.isSequence());
  EXPECT_TRUE(sequence.isSequence());
  EXPECT_DOUBLE_EQ(video.fps(), 12.5);
  EXPECT_EQ(video.declaredFrames(), static_cast<std::size_t>(kFrames));
  cv::Mat a, b;
  for (int i = 0; i < kFrames; ++i) {
    EXPECT_EQ(video.nextIndex(), static_cast<std::size_t>(i));
    ASSERT_TRUE(video.read(a)) << i;
    ASSERT_TRUE(sequence.read(b)) << i;
    EXPECT_EQ(cv::norm(a, frame(i), cv::NORM_INF), 0.0) << "video frame " << i;  // FFV1 is lossless
    EXPECT_EQ(cv::norm(b, frame(i), cv::NORM_INF), 0.0) << "sequence frame " << i;
  }
  EXPECT_FALSE(video.read(a));
  EXPECT_FALSE(sequence.read(b));
}

TEST_F(VideoSourceTest, SequencesCountFromOneWithoutAFrameZeroAndNameADamagedFrame) {
  fs::create_directories(path("from1"));
  for (int i = 1; i <= 3; ++i) cv::imwrite(path("from1/f_" + std::to_string(i) + ".png"), frame(i));
  {
    VideoSource s(path("from1/f_%d.png"), "--video from1");
    EXPECT_EQ(s.declaredFrames(), 3u);
    EXPECT_EQ(s.fps(), 0.0);
    cv::Mat m;
    for (int i = 1; i <= 3; ++i) {
      ASSERT_TRUE(s.read(m));
      EXPECT_EQ(cv::norm(m, frame(i), cv::NORM_INF), 0.0) << i;
    }
    EXPECT_FALSE(s.read(m));
  }
  // Frame 2 (the sequence's index 1) cut in half: that frame's error names it and the file, and
  // the frames before it were read.
  const std::string f2 = kccd::testing::readText(path("from1/f_2.png"));
  std::ofstream(path("from1/f_2.png"), std::ios::binary) << f2.substr(0, f2.size() / 2);
  VideoSource s(path("from1/f_%d.png"), "--video from1");
  cv::Mat m;
  ASSERT_TRUE(s.read(m));
  try {
    s.read(m);
    ADD_FAILURE() << "a damaged frame read";
  } catch (const VideoError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(
                  "--video from1: frame 1 cannot be decoded (" + path("from1/f_2.png") + ": image: a damaged PNG (", 0),
              0u)
        << what;
  }
}

TEST_F(VideoSourceTest, UnreadableRecordingsAreOneLineNamingThem) {
  EXPECT_EQ(errorOf(path("missing.mkv"), "--video missing.mkv"),
            "--video missing.mkv: no such file (a video file, or an image sequence such as frames/frame_%06d.png)");
  EXPECT_EQ(errorOf(path("seq"), "--video seq"),
            "--video seq: not a regular file (a video file, or an image sequence such as frames/frame_%06d.png)");
  std::ofstream(path("junk.mp4")) << "not a video\n";
  EXPECT_EQ(errorOf(path("junk.mp4"), "--video junk.mp4"),
            "--video junk.mp4: cannot open the video: not a video FFmpeg reads (Invalid data found when processing "
            "input)");
  EXPECT_EQ(errorOf(path("seq/none_%06d.png"), "--video none"),
            "--video none: no image of the sequence can be read (no file " + path("seq/none_000000.png") + " or " +
                path("seq/none_000001.png") + ")");
  EXPECT_EQ(errorOf(path("seq/%s_%06d.png"), "--video s"),
            "--video s: an image sequence's name needs one printf number such as %06d, and no other %");
  EXPECT_EQ(errorOf(path("seq/%d_%d.png"), "--video dd"),
            "--video dd: an image sequence's name needs one printf number such as %06d, and no other %");
  // Without a label the path names it.
  EXPECT_EQ(errorOf(path("missing.mkv")).rfind(path("missing.mkv") + ": no such file", 0), 0u);
}

}  // namespace
