// The overlay's text at any frame size: the status line and the legend sized by the frame
// (render::textMetrics), inside it at 160x120, 320x240, 1280x720 and 3840x2160, a long status
// shortened at word boundaries (fitStatus), the legend in the corner that hides the fewest volume
// pixels (LegendCorner, FrameDecoration) or in a strip under the picture that leaves it untouched.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/overlay/recording/frame_decoration.hpp"
#include "kccd/overlay/recording/legend_corner.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/recording/status_line.hpp"
#include "kccd/render/text_metrics.hpp"

// A namespace of its own: the test program is a unity build with its neighbours.
namespace overlay_text_test {

namespace fs = std::filesystem;
using namespace kccd;
using overlay::LegendPlace;

const std::string kData = KCCD_DATA_DIR;
const cv::Scalar kGrey(110, 120, 100);

// Keeps the frames it is handed, and their size.
struct Keeper final : overlay::FrameSink {
  void begin(double, int w, int h) override { size = cv::Size(w, h); }
  void write(std::size_t, const cv::Mat& bgr) override { frames.push_back(bgr.clone()); }
  cv::Size size;
  std::vector<cv::Mat> frames;
};

// The pixels where `a` and `b` differ (CV_8U, 255 there).
cv::Mat differing(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d, same;
  cv::absdiff(a, b, d);
  cv::inRange(d, cv::Scalar::all(0), cv::Scalar::all(0), same);
  return 255 - same;
}

// Strictly inside the image: not touching any of its edges.
bool inside(const cv::Rect& r, cv::Size image) {
  return !r.empty() && r.x > 0 && r.y > 0 && r.br().x < image.width && r.br().y < image.height;
}

std::vector<std::string> wordsOf(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The demo arm at (0, 0, 0): its forearm in the post (colliding, a pair within the margin), seen by
// the demo camera without distortion at `size` (square pixels, the same vertical field of view),
// its principal point at `centre` (fractions of the size).
class OverlayText : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_overlay_text_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    log_.emplace(parseStateLog("time,shoulder_yaw,shoulder_pitch,elbow\n0,0,0,0\n0.5,0,0,0\n", "log.csv", model_));
  }
  void TearDown() override { fs::remove_all(dir_); }

  calib::Camera camera(cv::Size size, cv::Point2d centre = {0.501, 0.498}) const {
    calib::Camera c = calib::loadCamera(kData + "/demo_camera.yaml");
    const double s = size.height / 720.0;
    c.width = size.width;
    c.height = size.height;
    c.camera_matrix(0, 0) *= s;
    c.camera_matrix(1, 1) *= s;
    c.camera_matrix(0, 2) = centre.x * size.width;
    c.camera_matrix(1, 2) = centre.y * size.height;
    c.distortion.assign(5, 0.0);
    return c;
  }

  // One uniform frame at time 0 drawn with `o` (plain, legend) at `cam`'s size: the frame handed
  // on; its record into `record` when given.
  cv::Mat draw(const calib::Camera& cam, overlay::OverlayOptions o, overlay::FrameRecord* record = nullptr) {
    const fs::path folder = dir_ / (std::to_string(cam.width) + "x" + std::to_string(cam.height));
    if (!fs::exists(folder)) {
      fs::create_directories(folder);
      cv::imwrite((folder / "frame_000000.png").string(), cv::Mat(cam.height, cam.width, CV_8UC3, kGrey));
    }
    const overlay::OverlayInputs in{model_, cam, *log_, (folder / "frame_%06d.png").string(), {}, "", "", ""};
    o.fps = 10.0;
    o.jobs = 1;
    Keeper keep;
    const overlay::OverlayReport report = overlay::overlayRecording(in, o, &keep);
    if (record && !report.frames.empty()) *record = report.frames[0];
    settings_.max_gap = report.max_gap;
    EXPECT_EQ(keep.frames.size(), 1u);
    EXPECT_EQ(keep.size, keep.frames.empty() ? cv::Size() : keep.frames[0].size());
    return keep.frames.empty() ? cv::Mat() : keep.frames[0];
  }
  cv::Mat draw(const calib::Camera& cam, bool plain, LegendPlace legend = LegendPlace::Auto,
               overlay::FrameRecord* record = nullptr) {
    overlay::OverlayOptions o;
    o.plain = plain;
    o.legend = legend;
    return draw(cam, o, record);
  }

  fs::path dir_;
  overlay::AnnotatorSettings settings_;  // as the last run's (for its status line)
  Model model_ = loadModel(kData + "/demo_arm.yaml");
  std::optional<StateLog> log_;
};

const cv::Size kSizes[] = {{160, 120}, {320, 240}, {1280, 720}, {3840, 2160}};

// The status line (legend off: what differs from the plain frame) lies inside the frame, not
// cut at an edge, at every size; its letters are 3 to 9 % of the frame's height (at least 7 px:
// kMinTextScale), and from 720 rows up exactly in proportion (within 10 % of the ratio at 720).
// The line (colliding, a pair within the margin) is shortened on the small frames only.
TEST_F(OverlayText, StatusLineFitsAndScalesWithTheFrame) {
  double ratio_720 = 0.0;
  for (const cv::Size size : kSizes) {
    const calib::Camera cam = camera(size);
    overlay::FrameRecord record;
    const cv::Mat plain = draw(cam, true), status = draw(cam, false, LegendPlace::Off, &record);
    ASSERT_EQ(record.status, SafetyStatus::Colliding);
    ASSERT_EQ(plain.size(), size);
    ASSERT_EQ(status.size(), size);
    const cv::Rect box = cv::boundingRect(differing(plain, status));
    EXPECT_TRUE(inside(box, size)) << size << ": status box " << box;
    const overlay::FrameDecoration deco(size, LegendPlace::Off, true);
    EXPECT_LE(box.br().x, size.width - deco.text().margin) << size;
    // The letters: pixels far from the darkened picture behind them.
    cv::Mat darkened;
    plain(box).convertTo(darkened, -1, 0.35, 0);
    cv::Mat d, background;
    cv::absdiff(status(box), darkened, d);
    cv::inRange(d, cv::Scalar::all(0), cv::Scalar::all(59), background);
    const cv::Mat letters = 255 - background;
    const cv::Rect text = cv::boundingRect(letters);
    ASSERT_FALSE(text.empty()) << size;
    const double ratio = static_cast<double>(text.height) / size.height;
    EXPECT_GE(text.height, 7) << size;
    EXPECT_GE(ratio, 0.03) << size << ": letters " << text.height << " px high";
    EXPECT_LE(ratio, 0.09) << size << ": letters " << text.height << " px high";
    if (size.height == 720) ratio_720 = ratio;
    if (size.height > 720) {
      EXPECT_NEAR(ratio, ratio_720, 0.1 * ratio_720) << size;
    }
    // The whole line's width against the box's: shortened where it would not fit.
    const auto width = [&](const std::string& s) { return deco.text().width(s); };
    const std::string line = overlay::fitStatus(overlay::statusFields(record, model_, settings_), 1 << 20, width);
    EXPECT_NE(line.find("within margin: "), std::string::npos) << line;
    const int drawn = box.width - 2 * deco.text().pad;
    if (width(line) > deco.statusWidth()) {
      EXPECT_LT(drawn, width(line)) << size << ": shortened";
    } else {
      EXPECT_EQ(drawn, width(line)) << size << ": the whole line";
    }
    if (size.width <= 320) {
      EXPECT_GT(width(line), deco.statusWidth()) << "the test's line is too long at " << size;
    }
  }
}

TEST(OverlayTextMetrics, TodaysSizeAt720RowsAndReadableBelow) {
  const render::TextMetrics m = render::textMetrics(720);
  EXPECT_DOUBLE_EQ(m.scale, 0.8);
  EXPECT_EQ(m.thickness, 2);
  EXPECT_DOUBLE_EQ(render::textMetrics(120).scale, render::kMinTextScale);
  EXPECT_DOUBLE_EQ(render::textMetrics(2160).scale, 2.4);
  int last = 0;
  for (const int rows : {60, 120, 240, 480, 720, 1080, 2160, 4320}) {
    const render::TextMetrics t = render::textMetrics(rows);
    EXPECT_GE(t.height, last) << rows;  // never smaller on a larger frame
    EXPECT_GE(t.pad, 2);
    last = t.height;
  }
}

// A status with many pairs, too long for a small frame, is shortened at word boundaries: each
// result fits, is made of the full line's words in order (the last one possibly followed by
// "..."), and keeps the verdict (the distance) as long as it fits at all.
TEST(OverlayStatusLine, ALongStatusIsShortenedAtWordBoundaries) {
  const Model model = loadModel(kData + "/demo_arm.yaml");
  overlay::FrameRecord rec;
  rec.time = 12.3456;
  rec.match = StateMatch::Interpolated;
  rec.status = SafetyStatus::WithinMargin;
  rec.min_distance = 0.0179;
  for (std::size_t p = 0; p < model.pairs.size(); ++p) rec.pairs.push_back({model.pairs[p].a, model.pairs[p].b});
  ASSERT_GE(rec.pairs.size(), 2u);
  overlay::AnnotatorSettings set;
  set.swept = true;
  const std::vector<overlay::StatusField> fields = overlay::statusFields(rec, model, set);
  const render::TextMetrics m = render::textMetrics(120);
  const auto width = [&](const std::string& s) { return m.width(s); };
  const std::string full = overlay::fitStatus(fields, 1 << 20, width);
  EXPECT_EQ(full.rfind("t 12.346 s (interpolated)  swept  min distance 0.0179 m  within margin: ", 0), 0u) << full;
  const std::vector<std::string> all = wordsOf(full);
  bool cut_seen = false, dropped_seen = false;
  for (int max_width = width(full) - 1; max_width > 0; max_width -= 3) {
    const std::string s = overlay::fitStatus(fields, max_width, width);
    if (s.empty()) {
      EXPECT_LT(max_width, width("min")) << "something fits down to the first word";
      continue;
    }
    EXPECT_LE(width(s), max_width) << s;
    std::vector<std::string> got = wordsOf(s);
    if (got.back() == "...") {
      cut_seen = true;
      got.pop_back();
    }
    // Whole words of the line, in its order (a trailing ',' or ':' dropped before "...").
    std::size_t at = 0;
    for (const std::string& w : got) {
      while (at < all.size() && all[at] != w && all[at] != w + "," && all[at] != w + ":") ++at;
      EXPECT_LT(at, all.size()) << "'" << w << "' is not a word of the line, or out of order: " << s;
      ++at;
    }
    dropped_seen |= s.find("(interpolated)") == std::string::npos;
    if (max_width >= width("min distance 0.0179 m")) {
      EXPECT_NE(s.find("min distance 0.0179 m"), std::string::npos) << s;
    }
  }
  EXPECT_TRUE(cut_seen && dropped_seen);
  // The least important goes first: without room for the match, the time stays.
  const std::string no_match = overlay::fitStatus(fields, width(full) - 1, width);
  EXPECT_EQ(no_match.find("(interpolated)"), std::string::npos) << no_match;
  EXPECT_EQ(no_match.rfind("t 12.346 s  swept  min distance", 0), 0u) << no_match;
  // A sole field cut at a word: "UNSAFE ..." (never a part of a word).
  overlay::FrameRecord unsafe;
  unsafe.match = StateMatch::Exact;
  unsafe.query = Status::ExactNeedsPoint;
  const std::string u = overlay::fitStatus(overlay::statusFields(unsafe, model, {}), width("UNSAFE: exact"), width);
  EXPECT_EQ(u, "UNSAFE ...");
}

// The legend stays put for a frame or two in which another corner is clearer, and moves when one
// has been clearer for `hold` frames; equal corners keep it where it is.
TEST(OverlayLegendCorner, MovesOnlyAfterAnotherCornerStaysClearer) {
  overlay::LegendCorner corner(1000, 3);
  EXPECT_EQ(corner.next(std::vector<int>{50, 0, 0, 0}), 1);  // the least covered, the first of equals
  EXPECT_EQ(corner.next(std::vector<int>{0, 500, 0, 0}), 1);
  EXPECT_EQ(corner.next(std::vector<int>{0, 500, 0, 0}), 1);
  EXPECT_EQ(corner.next(std::vector<int>{0, 15, 0, 0}), 1);  // within 2 % of the area: no better
  EXPECT_EQ(corner.next(std::vector<int>{0, 500, 0, 0}), 1);
  EXPECT_EQ(corner.next(std::vector<int>{0, 500, 0, 0}), 1);
  EXPECT_EQ(corner.next(std::vector<int>{900, 500, 900, 0}), 3);  // the third frame in a row: the clearest of it
  EXPECT_EQ(corner.next(std::vector<int>{0, 0, 0, 0}), 3);
}

// The legend lies inside the frame at every size; with the volumes filling the top-left corner
// it goes to another, hiding fewer volume pixels there than it would in the top-left; asked for
// the top-left, it goes there.
TEST_F(OverlayText, TheLegendIsInsideAndAvoidsTheVolumes) {
  for (const cv::Size size : kSizes) {
    const calib::Camera cam = camera(size);
    const cv::Mat off = draw(cam, false, LegendPlace::Off), with = draw(cam, false, LegendPlace::Auto);
    const cv::Rect legend = cv::boundingRect(differing(off, with));
    EXPECT_TRUE(inside(legend, size)) << size << ": legend " << legend;
  }
  const cv::Size size(320, 240);
  const calib::Camera corner = camera(size, {0.12, 0.1});  // the arm near the top-left corner
  const cv::Mat input(size, CV_8UC3, kGrey), plain = draw(corner, true);
  const cv::Mat volumes = differing(plain, input);
  const cv::Mat off = draw(corner, false, LegendPlace::Off);
  const cv::Rect chosen = cv::boundingRect(differing(off, draw(corner, false, LegendPlace::Auto)));
  const cv::Rect top_left = cv::boundingRect(differing(off, draw(corner, false, LegendPlace::TopLeft)));
  const overlay::FrameDecoration deco(size, LegendPlace::Auto, true);
  ASSERT_EQ(deco.corners().size(), 4u);
  EXPECT_EQ(top_left, deco.corners()[0]);
  EXPECT_NE(chosen, top_left);
  const int hidden_top_left = cv::countNonZero(volumes(top_left)), hidden = cv::countNonZero(volumes(chosen));
  EXPECT_GT(hidden_top_left, top_left.area() / 4) << "the test's camera puts the volumes in the top-left corner";
  EXPECT_LT(hidden, hidden_top_left / 4) << chosen;
}

// With the legend outside, the frame is taller by a strip that holds the status line and the
// legend, and the picture above it is the plain one (the volumes only): not a pixel of it changed.
TEST_F(OverlayText, OutsideMakesTheFrameTallerAndLeavesThePicture) {
  for (const cv::Size size : {cv::Size(160, 120), cv::Size(1280, 720)}) {
    const calib::Camera cam = camera(size);
    const cv::Mat plain = draw(cam, true), outside = draw(cam, false, LegendPlace::Outside);
    ASSERT_EQ(outside.cols, size.width);
    EXPECT_GT(outside.rows, size.height + 2 * render::textMetrics(size.height).height) << size;
    EXPECT_EQ(outside.rows % 2, size.height % 2);
    EXPECT_EQ(cv::countNonZero(differing(outside.rowRange(0, size.height), plain)), 0) << size;
    const cv::Mat strip = outside.rowRange(size.height, outside.rows);
    cv::Mat grey;
    cv::cvtColor(strip, grey, cv::COLOR_BGR2GRAY);
    double lo = 0, hi = 0;
    cv::minMaxLoc(grey, &lo, &hi);
    EXPECT_GT(hi - lo, 150) << size << ": the strip holds text";
  }
}

TEST(OverlayLegendPlace, WordsAndTheirPlaces) {
  EXPECT_EQ(overlay::legendPlaceOf("auto"), LegendPlace::Auto);
  EXPECT_EQ(overlay::legendPlaceOf("outside"), LegendPlace::Outside);
  EXPECT_EQ(overlay::legendPlaceOf("off"), LegendPlace::Off);
  EXPECT_EQ(overlay::legendPlaceOf("bottom-right"), LegendPlace::BottomRight);
  EXPECT_FALSE(overlay::legendPlaceOf("left").has_value());
  EXPECT_FALSE(overlay::legendPlaceOf("Auto").has_value());
  EXPECT_EQ(overlay::legendPlaceWords(),
            "'auto', 'outside', 'off', 'top-left', 'top-right', 'bottom-left' or 'bottom-right'");
  // Each corner asked for is the one box; a picture too small for any legend has none.
  const overlay::FrameDecoration br(cv::Size(320, 240), LegendPlace::BottomRight, true);
  ASSERT_EQ(br.corners().size(), 1u);
  EXPECT_EQ(br.corners()[0].br().x, 320 - br.text().margin);
  EXPECT_TRUE(overlay::FrameDecoration(cv::Size(12, 10), LegendPlace::Auto, true).corners().empty());
}

}  // namespace overlay_text_test
