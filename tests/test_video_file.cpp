// Video files through FFmpeg (VideoFileReader / VideoFileWriter) against OpenCV's FFmpeg back end,
// a second implementation over the same libraries that shares no code with them: files written
// by both are the same bytes, frames decoded by both the same pixels, the declared rate, frame
// count and codec the same; a rotated video comes out turned as FFmpeg's own player turns it.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/overlay/recording/video_file.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using kccd::overlay::VideoFileError;
using kccd::overlay::VideoFileReader;
using kccd::overlay::VideoFileWriter;

namespace {

class VideoFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_video_file_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Frame i: textured (so the codecs do real work), a square moving with i, colour edges.
  static cv::Mat frame(int i, int w, int h) {
    cv::Mat m(h, w, CV_8UC3);
    cv::RNG rng(1234 + i);
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(m, m, cv::Size(5, 5), 1.5);
    cv::rectangle(m, cv::Rect((7 * i) % (w / 2), h / 4, w / 5, h / 3), cv::Scalar(30, 200, 250), cv::FILLED);
    cv::line(m, {0, h - 1 - i % h}, {w - 1, i % h}, cv::Scalar(255, 0, 0), 3);
    return m;
  }
  fs::path dir_;
};

struct Case {
  const char* file;
  const char* fourcc;
  double fps;
  int width, height;
};

// mp4v in .mp4, Motion JPEG in .avi, FFV1 in .mkv; rates whole and not (29.97 is 2997/100);
// sizes that are and are not multiples of 16.
const Case kCases[] = {{"a.mp4", "mp4v", 30.0, 320, 240}, {"b.avi", "MJPG", 25.0, 200, 150},
                       {"c.mkv", "FFV1", 12.5, 96, 64},   {"d.mp4", "mp4v", 29.97, 176, 100},
                       {"e.avi", "XVID", 15.0, 160, 120}, {"f.mkv", "FFV1", 60.0, 130, 66}};

TEST_F(VideoFileTest, WritesTheBytesOpenCVsWriterWrites) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.file);
    const int n = 14;  // beyond one group of pictures (12)
    {
      VideoFileWriter ours(path(std::string("ours_") + c.file), c.fourcc, c.fps, c.width, c.height);
      cv::VideoWriter theirs(path(std::string("cv_") + c.file), cv::CAP_FFMPEG,
                             cv::VideoWriter::fourcc(c.fourcc[0], c.fourcc[1], c.fourcc[2], c.fourcc[3]), c.fps,
                             cv::Size(c.width, c.height), true);
      ASSERT_TRUE(theirs.isOpened());
      for (int i = 0; i < n; ++i) {
        const cv::Mat f = frame(i, c.width, c.height);
        ours.write(f);
        theirs.write(f);
      }
      ours.finish();
    }
    const std::string a = kccd::testing::readText(path(std::string("ours_") + c.file));
    const std::string b = kccd::testing::readText(path(std::string("cv_") + c.file));
    EXPECT_GT(a.size(), 1000u);
    ASSERT_EQ(a.size(), b.size());
    // Matroska gives each file random segment and track UIDs (and the CRCs over them): those bytes
    // may differ, no others.
    std::size_t differ = 0, last = 0;
    for (std::size_t k = 0; k < a.size(); ++k)
      if (a[k] != b[k]) ++differ, last = k;
    const bool mkv = fs::path(c.file).extension() == ".mkv";
    EXPECT_LE(differ, mkv ? 64u : 0u);  // 43 or 44 of ~150 kB here, all in the first 512 bytes
    EXPECT_LT(last, mkv ? 1024u : 1u);
  }
}

TEST_F(VideoFileTest, ReadsThePixelsRateCountAndCodecOpenCVsCaptureReads) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.file);
    const std::string p = path(c.file);
    {
      VideoFileWriter w(p, c.fourcc, c.fps, c.width, c.height);
      for (int i = 0; i < 20; ++i) w.write(frame(i, c.width, c.height));
      w.finish();
    }
    VideoFileReader ours(p);
    cv::VideoCapture theirs(p, cv::CAP_FFMPEG);
    ASSERT_TRUE(theirs.isOpened());
    EXPECT_DOUBLE_EQ(ours.fps(), theirs.get(cv::CAP_PROP_FPS));
    EXPECT_NEAR(ours.fps(), c.fps, 1e-9);
    EXPECT_EQ(static_cast<double>(ours.declaredFrames()), theirs.get(cv::CAP_PROP_FRAME_COUNT));
    EXPECT_EQ(ours.declaredFrames(), 20u);
    EXPECT_EQ(ours.fourcc().size(), 4u);
    cv::Mat a, b;
    int frames = 0;
    for (;;) {
      const bool got_a = ours.read(a), got_b = theirs.read(b);
      ASSERT_EQ(got_a, got_b) << "frame " << frames;
      if (!got_a) break;
      ASSERT_EQ(a.size(), b.size());
      ASSERT_EQ(a.type(), CV_8UC3);
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << frames;
      if (std::string(c.fourcc) == "FFV1") {
        EXPECT_EQ(cv::norm(a, frame(frames, c.width, c.height), cv::NORM_INF), 0.0);
      }
      ++frames;
    }
    EXPECT_EQ(frames, 20);
  }
}

// FFVHUFF (FourCC FFVH, `kccd synth`'s default) in .mkv, which OpenCV's writer does not offer: lossless
// through our reader and OpenCV's capture alike, odd frame sizes included.
TEST_F(VideoFileTest, FfvhuffInMatroskaIsLosslessForEveryReader) {
  for (const auto& [w, h] : {std::pair{96, 64}, std::pair{97, 63}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const std::string p = path("h" + std::to_string(w) + ".mkv");
    {
      VideoFileWriter writer(p, "ffvh", 25.0, w, h);
      for (int i = 0; i < 12; ++i) writer.write(frame(i, w, h));
      writer.finish();
    }
    VideoFileReader ours(p);
    EXPECT_EQ(ours.fourcc(), "FFVH");
    EXPECT_NEAR(ours.fps(), 25.0, 1e-9);
    cv::VideoCapture theirs(p, cv::CAP_FFMPEG);
    ASSERT_TRUE(theirs.isOpened());
    cv::Mat a, b;
    int frames = 0;
    while (ours.read(a)) {
      ASSERT_TRUE(theirs.read(b)) << frames;
      EXPECT_EQ(cv::norm(a, frame(frames, w, h), cv::NORM_INF), 0.0) << frames;
      EXPECT_EQ(cv::norm(b, frame(frames, w, h), cv::NORM_INF), 0.0) << frames;
      ++frames;
    }
    EXPECT_FALSE(theirs.read(b));
    EXPECT_EQ(frames, 12);
  }
}

// H.264 from FFmpeg's own encoder (a codec the suite reads but does not write by default): a
// coded picture taller than the shown one (1088 rows for 1080 is the usual case; 360 -> 368 here).
TEST_F(VideoFileTest, ReadsH264WithACodedSizeLargerThanThePictureAsOpenCVDoes) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) GTEST_SKIP() << "no ffmpeg program";
  const std::string p = path("h.mp4");
  const std::string cmd =
      "ffmpeg -v error -y -f lavfi -i testsrc2=size=640x360:rate=24 -frames:v 30 -c:v libx264 "
      "-pix_fmt yuv420p -g 10 -bf 2 " +
      p;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  VideoFileReader ours(p);
  cv::VideoCapture theirs(p, cv::CAP_FFMPEG);
  EXPECT_EQ(ours.fourcc(), "avc1");
  EXPECT_DOUBLE_EQ(ours.fps(), 24.0);
  EXPECT_EQ(ours.declaredFrames(), 30u);
  cv::Mat a, b;
  int frames = 0;
  while (ours.read(a)) {
    ASSERT_TRUE(theirs.read(b));
    ASSERT_EQ(a.size(), cv::Size(640, 360));
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "frame " << frames;
    ++frames;
  }
  EXPECT_FALSE(theirs.read(b));
  EXPECT_EQ(frames, 30);  // the decoder drained: frames held back for B-frames come out at the end
}

// A phone's portrait video: stored landscape with a display rotation. The reader turns it as
// FFmpeg's own program does (its decode, autorotated, is the oracle), not the other way round.
TEST_F(VideoFileTest, TurnsARotatedVideoAsFfmpegDoes) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) GTEST_SKIP() << "no ffmpeg program";
  const std::string flat = path("flat.mkv"), stored = path("stored.mp4"), turned = path("turned.mp4"),
                    raw = path("turned.bgr");
  {
    VideoFileWriter w(flat, "FFV1", 10.0, 120, 80);
    for (int i = 0; i < 3; ++i) w.write(frame(i, 120, 80));
    w.finish();
  }
  ASSERT_EQ(std::system(("ffmpeg -v error -y -i " + flat + " -c:v mpeg4 -q:v 1 " + stored).c_str()), 0);
  for (const int angle : {90, 180, 270}) {
    SCOPED_TRACE(angle);
    const std::string tag =
        "ffmpeg -v error -y -i " + stored + " -c copy -metadata:s:v:0 rotate=" + std::to_string(angle) + " " + turned;
    ASSERT_EQ(std::system(tag.c_str()), 0);
    const std::string decode = "ffmpeg -v error -y -i " + turned + " -frames:v 1 -f rawvideo -pix_fmt bgr24 " + raw;
    ASSERT_EQ(std::system(decode.c_str()), 0);
    const cv::Size size = angle == 180 ? cv::Size(120, 80) : cv::Size(80, 120);
    std::string bytes = kccd::testing::readText(raw);
    ASSERT_EQ(bytes.size(), static_cast<std::size_t>(size.area() * 3));
    const cv::Mat want(size, CV_8UC3, bytes.data());
    VideoFileReader r(turned);
    cv::Mat got;
    ASSERT_TRUE(r.read(got));
    ASSERT_EQ(got.size(), size);
    cv::Mat diff;
    cv::absdiff(got, want, diff);
    EXPECT_LT(cv::mean(diff)[0], 3.0);  // FFmpeg turns before its colour conversion, the reader after
    cv::Mat other;
    cv::rotate(want, other, cv::ROTATE_180);  // the other way round
    cv::absdiff(got, other, diff);
    EXPECT_GT(cv::mean(diff)[0], 20.0);
  }
}

TEST_F(VideoFileTest, RefusalsAreErrorsInWords) {
  const auto errorOf = [](auto&& make) -> std::string {
    try {
      make();
      return "";
    } catch (const VideoFileError& e) {
      return e.what();
    }
  };
  std::ofstream(path("junk.mp4")) << "not a video at all";
  EXPECT_EQ(errorOf([&] { VideoFileReader r(path("junk.mp4")); }).rfind("not a video FFmpeg reads (", 0), 0u);
  EXPECT_EQ(errorOf([&] { VideoFileReader r(path("missing.mp4")); }).rfind("not a video FFmpeg reads (", 0), 0u);
  EXPECT_EQ(errorOf([&] { VideoFileWriter w(path("a.xyz"), "mp4v", 30, 64, 48); }),
            "a container FFmpeg does not write (use .mp4, .mkv or .avi)");
  EXPECT_EQ(errorOf([&] { VideoFileWriter w(path("a.mp4"), "ABCD", 30, 64, 48); }), "no encoder for the codec ABCD");
  EXPECT_EQ(errorOf([&] { VideoFileWriter w(path("a.mp4"), "mp4v", 0.0, 64, 48); }), "a frame rate not in (0, 1000]");
  EXPECT_EQ(errorOf([&] { VideoFileWriter w(path("a.mp4"), "mp4v", 30, 0, 48); }), "a frame size not in 1..16384");
  EXPECT_EQ(errorOf([&] { VideoFileWriter w(path("a.avi"), "FFV1", 30, 64, 48); }), "");
  VideoFileWriter w(path("b.mp4"), "mp4v", 30, 64, 48);
  EXPECT_THROW(w.write(cv::Mat(48, 64, CV_8UC1)), std::logic_error);
  EXPECT_THROW(w.write(cv::Mat(40, 64, CV_8UC3)), std::logic_error);
  // Destroyed unfinished: no crash, no leak (the sanitizer builds would tell), a file its owner removes.
}

TEST_F(VideoFileTest, AWriterWithNoFrameLeavesAContainerAReaderOpensEmpty) {
  {
    VideoFileWriter w(path("none.avi"), "MJPG", 30, 64, 48);
    w.finish();
  }
  VideoFileReader r(path("none.avi"));
  EXPECT_EQ(r.declaredFrames(), 0u);
  cv::Mat m;
  EXPECT_FALSE(r.read(m));
}

TEST(FourccCode, FirstCharacterInTheLowestByte) {
  EXPECT_EQ(kccd::overlay::fourccCode("mp4v"), static_cast<std::uint32_t>(cv::VideoWriter::fourcc('m', 'p', '4', 'v')));
  EXPECT_EQ(kccd::overlay::fourccCode("MJPG"), static_cast<std::uint32_t>(cv::VideoWriter::fourcc('M', 'J', 'P', 'G')));
  EXPECT_EQ(kccd::overlay::fourccCode("abc"), 0u);
}

// The writer encodes on a thread of its own: a failure there (a full disk) reaches the caller as a
// VideoFileError from a later write() or from finish(), never as a file passed off as whole; a
// writer destroyed with frames still queued stops cleanly (the sanitizer builds would tell a leak).
TEST_F(VideoFileTest, AFullDiskFailsAWriteOrTheFinishInWords) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  fs::create_symlink("/dev/full", path("full.avi"));
  std::string error;
  VideoFileWriter w(path("full.avi"), "MJPG", 30, 320, 240);
  try {
    for (int i = 0; i < 60; ++i) w.write(frame(i, 320, 240));
    w.finish();
  } catch (const VideoFileError& e) {
    error = e.what();
  }
  // Asked again after the failure, finish() does not pass the file off as whole.
  EXPECT_THROW(w.finish(), VideoFileError);
  EXPECT_TRUE(error.rfind("cannot write to the file (", 0) == 0 || error.rfind("cannot finish the file (", 0) == 0 ||
              error.rfind("cannot close the file", 0) == 0 ||
              error.rfind("cannot write the container's header (", 0) == 0)
      << "error: '" << error << "'";
  {
    VideoFileWriter queued(path("queued.avi"), "MJPG", 30, 320, 240);
    for (int i = 0; i < 8; ++i) queued.write(frame(i, 320, 240));
  }  // destroyed unfinished, frames in flight
  VideoFileWriter again(path("again.avi"), "MJPG", 30, 320, 240);
  for (int i = 0; i < 8; ++i) again.write(frame(i, 320, 240));
  again.finish();
  VideoFileReader r(path("again.avi"));
  cv::Mat m;
  int n = 0;
  while (r.read(m)) ++n;
  EXPECT_EQ(n, 8);
}

}  // namespace
