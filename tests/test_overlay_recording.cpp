// kccd::overlay::overlayRecording called as a library: every frame checked against a query run
// here at a state interpolated here, the drawn frames handed on in order, the same answer with any
// number of threads, bad recordings named on one line, and the video sink's staged outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/checker.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/recording/timeline.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/overlay/recording/video_source.hpp"

namespace {

namespace fs = std::filesystem;
using namespace kccd;

const std::string kData = KCCD_DATA_DIR;
constexpr int kW = 256, kH = 144, kFrames = 16;
constexpr double kFps = 8.0;

// The log: rows (time, three joint values); a gap between 0.75 and 1.5 s (median period 0.25 s,
// so at most 0.375 s is bridged). At 0.5 s the arm points straight at the post.
const std::vector<std::array<double, 4>> kRows = {
    {0.0, -1.0, -0.5, 0.5}, {0.25, -0.8, -0.4, 0.4}, {0.5, 0.0, 0.0, 0.0},  {0.75, -0.6, -0.2, 0.2},
    {1.5, -1.0, -0.6, 0.6}, {1.75, -1.2, -0.6, 0.6}, {2.0, -1.4, -0.6, 0.6}};

// The state at time t by linear interpolation between the rows around it, if they are at most
// `max_gap` apart (written here, independently of the library's state log).
std::optional<std::vector<double>> stateHere(double t, double max_gap) {
  for (std::size_t i = 0; i + 1 < kRows.size(); ++i) {
    const auto &a = kRows[i], &b = kRows[i + 1];
    if (t < a[0] - 1e-9 || t > b[0] + 1e-9) continue;
    if (std::fabs(t - a[0]) < 1e-9) return std::vector<double>{a[1], a[2], a[3]};
    if (std::fabs(t - b[0]) < 1e-9) return std::vector<double>{b[1], b[2], b[3]};
    if (b[0] - a[0] > max_gap) return std::nullopt;
    const double w = (t - a[0]) / (b[0] - a[0]);
    return std::vector<double>{a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3])};
  }
  return std::nullopt;
}

cv::Mat inputFrame(int i) {
  cv::Mat f(kH, kW, CV_8UC3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      f.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar((x + 5 * i) % 256), uchar(y % 256), uchar(30 + 9 * i));
  return f;
}

// Keeps what it is handed.
struct Keeper final : overlay::FrameSink {
  void begin(double f, int w, int h) override {
    ++begins;
    fps = f;
    size = cv::Size(w, h);
  }
  void write(std::size_t index, const cv::Mat& bgr) override {
    indices.push_back(index);
    frames.push_back(bgr.clone());
  }
  int begins = 0;
  double fps = 0.0;
  cv::Size size;
  std::vector<std::size_t> indices;
  std::vector<cv::Mat> frames;
};

class OverlayRecording : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_overlay_recording_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    camera_ = calib::loadCamera(kData + "/demo_camera.yaml");
    const double s = static_cast<double>(kW) / camera_.width;
    camera_.width = kW;
    camera_.height = kH;
    camera_.camera_matrix(0, 0) *= s;
    camera_.camera_matrix(1, 1) *= s;
    camera_.camera_matrix(0, 2) = (camera_.camera_matrix(0, 2) + 0.5) * s - 0.5;
    camera_.camera_matrix(1, 2) = (camera_.camera_matrix(1, 2) + 0.5) * s - 0.5;
    video_ = (dir_ / "in.mkv").string();
    cv::VideoWriter vw(video_, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), kFps, cv::Size(kW, kH),
                       true);
    ASSERT_TRUE(vw.isOpened());
    for (int i = 0; i < kFrames; ++i) vw.write(inputFrame(i));
    std::string csv = "time,shoulder_yaw,shoulder_pitch,elbow\n";
    for (const auto& r : kRows)
      csv += std::to_string(r[0]) + "," + std::to_string(r[1]) + "," + std::to_string(r[2]) + "," +
             std::to_string(r[3]) + "\n";
    log_.emplace(parseStateLog(csv, "log.csv", model_));
  }
  void TearDown() override { fs::remove_all(dir_); }
  overlay::OverlayReport run(overlay::FrameSink* sink, overlay::OverlayOptions o = {}, const std::string& video = "") {
    const overlay::OverlayInputs in{model_, camera_,          *log_,      video.empty() ? video_ : video,
                                    {},     "--video in.mkv", "cam.yaml", ""};
    return overlay::overlayRecording(in, o, sink);
  }
  fs::path dir_;
  Model model_ = loadModel(kData + "/demo_arm.yaml");
  calib::Camera camera_;
  std::optional<StateLog> log_;
  std::string video_;
};

TEST_F(OverlayRecording, EveryFrameCarriesTheQueryAtItsLoggedState) {
  overlay::OverlayOptions o;
  o.frames = overlay::parseFrameRange("1:15:2");
  o.jobs = 2;
  o.contact_frames = 4;
  Keeper keep;
  const overlay::OverlayReport r = run(&keep, o);
  ASSERT_EQ(r.frames.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(keep.begins, 1);
  EXPECT_DOUBLE_EQ(keep.fps, kFps);
  EXPECT_EQ(keep.size, cv::Size(kW, kH));
  EXPECT_EQ(keep.indices, (std::vector<std::size_t>{1, 3, 5, 7, 9, 11, 13}));
  EXPECT_EQ(r.written, keep.indices.size());
  EXPECT_DOUBLE_EQ(r.max_gap, 0.375);
  Checker checker(model_);
  std::size_t colliding = 0, none = 0;
  for (int i = 0; i < kFrames; ++i) {
    const overlay::FrameRecord& f = r.frames[static_cast<std::size_t>(i)];
    EXPECT_DOUBLE_EQ(f.time, i / kFps);
    EXPECT_EQ(f.selected, i % 2 == 1 && i < 15) << i;
    const std::optional<std::vector<double>> q = stateHere(i / kFps, 0.375);
    if (!q) {
      EXPECT_EQ(f.status, SafetyStatus::NoState) << i;
      EXPECT_TRUE(f.values.empty());
      ++none;
      continue;
    }
    ASSERT_EQ(f.values.size(), 3u) << i;
    for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(f.values[k], (*q)[k], 1e-9) << i;
    const QueryResult& res = checker.query(*q, *q, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
    ASSERT_EQ(res.status, Status::Ok);
    EXPECT_EQ(f.status, safetyStatus(res)) << i;
    EXPECT_NEAR(f.min_distance, res.min_distance, 1e-9) << i;
    colliding += f.status == SafetyStatus::Colliding;
  }
  EXPECT_GE(colliding, 1u);  // the arm at the post (t = 0.5 s)
  EXPECT_GE(none, 4u);       // the gap in the log
  EXPECT_EQ(r.no_state, none);
  EXPECT_EQ(r.colliding, colliding);
  EXPECT_EQ(r.clear + r.within_margin + r.colliding + r.no_state, r.frames.size());
  EXPECT_FALSE(r.firstUnsafe().has_value());
  // Drawn frames carry the volumes: they differ from the input frame; the sheet shows 4 of them.
  for (std::size_t k = 0; k < keep.frames.size(); ++k)
    EXPECT_GT(cv::norm(keep.frames[k], inputFrame(static_cast<int>(keep.indices[k])), cv::NORM_L1), 0.0);
  EXPECT_FALSE(r.contact_sheet.empty());
  const nlohmann::json j = overlay::reportJson(r, model_, true);
  EXPECT_EQ(j.at("frames_total"), kFrames);
  EXPECT_EQ(j.at("frames").size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(j.at("frames")[4].at("status"), toString(r.frames[4].status));
  EXPECT_EQ(j.at("frames")[7].at("written"), true);
  EXPECT_FALSE(overlay::reportJson(r, model_, false).contains("frames"));
}

TEST_F(OverlayRecording, TheAnswerDoesNotDependOnTheNumberOfThreads) {
  overlay::OverlayOptions o;
  o.swept = true;
  o.braking.latency = 0.02;
  o.braking.deceleration = 4.0;
  std::vector<overlay::OverlayReport> reports;
  std::vector<Keeper> keeps(2);
  for (int jobs : {1, 3}) {
    o.jobs = jobs;
    reports.push_back(run(&keeps[reports.size()], o));
  }
  ASSERT_EQ(keeps[0].frames.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(keeps[1].frames.size(), keeps[0].frames.size());
  for (std::size_t i = 0; i < keeps[0].frames.size(); ++i) {
    EXPECT_EQ(cv::norm(keeps[0].frames[i], keeps[1].frames[i], cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(reports[0].frames[i].status, reports[1].frames[i].status) << i;
    EXPECT_TRUE(reports[0].frames[i].min_distance == reports[1].frames[i].min_distance ||
                (std::isnan(reports[0].frames[i].min_distance) && std::isnan(reports[1].frames[i].min_distance)));
  }
}

TEST_F(OverlayRecording, ARecordingOfAnotherSizeIsOneLineNamingIt) {
  const std::string small = (dir_ / "small.mkv").string();
  {
    cv::VideoWriter vw(small, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), kFps, cv::Size(64, 36),
                       true);
    for (int i = 0; i < 3; ++i) vw.write(cv::Mat(36, 64, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i)));
  }
  try {
    run(nullptr, {}, small);
    FAIL() << "no error";
  } catch (const overlay::VideoError& e) {
    EXPECT_EQ(std::string(e.what()), "--video in.mkv: frame 0 is 64x36 but cam.yaml is calibrated for 256x144");
  }
  EXPECT_THROW(run(nullptr, {}, (dir_ / "missing.mkv").string()), overlay::VideoError);
}

TEST_F(OverlayRecording, FrameRangesAreSlicesAndMistakesNameTheOption) {
  const overlay::FrameRange r = overlay::parseFrameRange("2:9:3");
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < 12; ++i)
    if (r.contains(i)) in.push_back(i);
  EXPECT_EQ(in, (std::vector<std::size_t>{2, 5, 8}));
  EXPECT_TRUE(overlay::parseFrameRange("").contains(123456));
  EXPECT_TRUE(overlay::parseFrameRange("7").contains(7));
  EXPECT_FALSE(overlay::parseFrameRange("7").contains(8));
  for (const char* bad : {"5:5", "1:2:0", "a", "1:2:3:4", "-1"}) {
    try {
      overlay::parseFrameRange(bad, "--frames");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(std::string("--frames ") + bad + ": expected FIRST", 0), 0u) << e.what();
    }
  }
}

TEST_F(OverlayRecording, TheVideoSinkShowsItsOutputsOnlyWhenCommitted) {
  const std::string video = (dir_ / "out.mkv").string(), pngs = (dir_ / "frames").string();
  {
    overlay::VideoSink sink({.video = video, .png_dir = pngs});
    sink.begin(kFps, kW, kH);
    sink.write(3, inputFrame(3));
    EXPECT_THROW(sink.write(4, cv::Mat(10, 10, CV_8UC3)), std::logic_error);
  }  // not committed: nothing left
  EXPECT_FALSE(fs::exists(video));
  EXPECT_FALSE(fs::exists(pngs));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);  // in.mkv
  overlay::VideoSink sink({.video = video, .png_dir = pngs});
  sink.begin(kFps, kW, kH);
  for (int i : {2, 5}) sink.write(static_cast<std::size_t>(i), inputFrame(i));
  sink.commit();
  EXPECT_EQ(cv::norm(cv::imread(pngs + "/frame_000005.png"), inputFrame(5), cv::NORM_INF), 0.0);
  EXPECT_TRUE(fs::exists(pngs + "/frame_000002.png"));
  overlay::VideoSource back(video);
  cv::Mat f;
  int n = 0;
  while (back.read(f)) EXPECT_EQ(cv::norm(f, inputFrame(n++ == 0 ? 2 : 5), cv::NORM_INF), 0.0);  // FFV1: lossless
  EXPECT_EQ(n, 2);
}

// The timeline of a report made here: each status's span shaded where its frames' times fall, the
// curve at each bound's height against the margin line, the list's length bounded.
TEST(Timeline, SpansCurveAndMarginSitWhereTheReportSays) {
  const Model model = loadModel(kData + "/demo_arm.yaml");
  overlay::OverlayReport report;
  report.margin = 0.02;
  for (int i = 0; i < 40; ++i) {
    overlay::FrameRecord f;
    f.time = 0.1 * i;
    f.status = SafetyStatus::Clear;
    f.min_distance = 0.1;
    if (i >= 10 && i <= 14) f.status = SafetyStatus::WithinMargin, f.min_distance = 0.01, f.pairs = {{0, 1}};
    if (i >= 20 && i <= 22) f.status = SafetyStatus::Colliding, f.min_distance = 0.0, f.pairs = {{0, 1}};
    if (i >= 30 && i <= 31) f.status = SafetyStatus::NoState, f.min_distance = std::nan("");
    report.frames.push_back(f);
  }
  report.contact_sheet_frames = {0, 21, 39};
  const cv::Mat img = overlay::drawTimeline(report, model, "test", 1600);
  ASSERT_EQ(img.cols, 1600);
  ASSERT_EQ(img.type(), CV_8UC3);
  // Columns holding each fill (BGR as drawn), and rows of the curve and the margin line.
  auto columns = [&](cv::Vec3b c) {
    std::vector<int> xs;
    for (int x = 0; x < img.cols; ++x) {
      int n = 0;
      for (int y = 0; y < img.rows; ++y) n += img.at<cv::Vec3b>(y, x) == c;
      if (n > 100) xs.push_back(x);  // a span's full height, not a key swatch
    }
    return xs;
  };
  const std::vector<int> within = columns({150, 220, 255}), colliding = columns({170, 170, 250}),
                         none = columns({215, 215, 215});
  ASSERT_FALSE(within.empty());
  ASSERT_FALSE(colliding.empty());
  ASSERT_FALSE(none.empty());
  EXPECT_EQ(within.back() - within.front() + 1, static_cast<int>(within.size()));  // one run each
  EXPECT_EQ(colliding.back() - colliding.front() + 1, static_cast<int>(colliding.size()));
  // Widths in proportion to the frames (5, 3, 2 frames), centres in proportion to the times.
  const double w5 = within.size(), w3 = colliding.size(), w2 = none.size();
  EXPECT_NEAR(w5 / w3, 5.0 / 3.0, 0.05);
  EXPECT_NEAR(w2 / w3, 2.0 / 3.0, 0.05);
  const double c5 = 0.5 * (within.front() + within.back()), c3 = 0.5 * (colliding.front() + colliding.back()),
               c2 = 0.5 * (none.front() + none.back());
  const double px_per_s = (c3 - c5) / (2.1 - 1.2);
  EXPECT_NEAR(c2 - c3, (3.05 - 2.1) * px_per_s, 2.0);
  EXPECT_NEAR(w3, 0.3 * px_per_s, 2.0);
  // The curve (the darkest blue) in the colliding span sits on the zero line; in the within span at
  // half the margin line's height.
  auto curveRow = [&](int x) {
    for (int y = 0; y < img.rows; ++y)
      if (img.at<cv::Vec3b>(y, x) == cv::Vec3b(150, 70, 20)) return y;
    return -1;
  };
  auto marginRow = [&](int x) {
    for (int y = 0; y < img.rows; ++y)
      if (img.at<cv::Vec3b>(y, x) == cv::Vec3b(0, 110, 230)) return y;
    return -1;
  };
  const int zero = curveRow(static_cast<int>(c3)), half = curveRow(static_cast<int>(c5));
  int margin_row = -1;
  for (int x = within.front(); x <= within.back() && margin_row < 0; ++x)
    margin_row = marginRow(x);  // the line is dashed
  ASSERT_GT(zero, 0);
  ASSERT_GT(half, 0);
  ASSERT_GT(margin_row, 0);
  EXPECT_NEAR(static_cast<double>(zero - half) / (zero - margin_row), 0.5, 0.05);
  EXPECT_LT(curveRow(static_cast<int>(c5 - 0.5 * px_per_s)), margin_row);  // a clear frame's bound above the margin
  // The list: at most 12 spans, then one line for the rest.
  auto withSpans = [&](int n) {
    overlay::OverlayReport r;
    r.margin = 0.02;
    for (int i = 0; i < 2 * n; ++i) {
      overlay::FrameRecord f;
      f.time = i;
      f.status = i % 2 ? SafetyStatus::Colliding : SafetyStatus::Clear;
      f.min_distance = i % 2 ? 0.0 : 0.5;
      r.frames.push_back(f);
    }
    return overlay::drawTimeline(r, model, "spans", 800).rows;
  };
  EXPECT_EQ(withSpans(12) - withSpans(11), 22);
  EXPECT_EQ(withSpans(13) - withSpans(12), 22);  // "... and 1 more"
  EXPECT_EQ(withSpans(30), withSpans(13));
  EXPECT_THROW(overlay::drawTimeline(report, model, "x", 100), InputError);
  EXPECT_THROW(overlay::drawTimeline(overlay::OverlayReport{}, model, "x"), InputError);
}

}  // namespace
