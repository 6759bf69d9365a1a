#include "kccd/overlay/recording/timeline.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "kccd/format_number.hpp"
#include "kccd/input_error.hpp"

namespace kccd::overlay {
namespace {

// Colours (BGR) on a white page.
const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kCurve(150, 70, 20), kMarginLine(0, 110, 230);
const cv::Scalar kCollidingFill(170, 170, 250), kWithinFill(150, 220, 255), kNoStateFill(215, 215, 215),
    kUnsafeFill(200, 140, 200);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr std::size_t kListed = 12;

// A frame's shade: 0 none (clear), else 1 within margin, 2 colliding, 3 no state, 4 unsafe.
int shadeOf(const FrameRecord& f) {
  if (f.unsafe()) return 4;
  switch (f.status) {
    case SafetyStatus::WithinMargin:
      return 1;
    case SafetyStatus::Colliding:
      return 2;
    case SafetyStatus::NoState:
      return 3;
    default:
      return 0;
  }
}
const char* shadeWord(int s) {
  static const char* const w[] = {"clear", "within margin", "colliding", "no state", "unsafe"};
  return w[s];
}
cv::Scalar shadeFill(int s) {
  return s == 1 ? kWithinFill : s == 2 ? kCollidingFill : s == 3 ? kNoStateFill : kUnsafeFill;
}
// Severity for the list's order: unsafe, colliding, within margin, no state.
int severity(int s) { return s == 4 ? 0 : s == 2 ? 1 : s == 1 ? 2 : 3; }

// A round step (1, 2 or 5 x 10^k) giving about `n` ticks over `range`.
double tickStep(double range, int n) {
  const double raw = range / n, p = std::pow(10.0, std::floor(std::log10(raw))), m = raw / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale, const cv::Scalar& c, int thickness = 1) {
  cv::putText(img, s, at, kFont, scale, c, thickness, cv::LINE_AA);
}
int textWidth(const std::string& s, double scale, int thickness = 1) {
  int base = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &base).width;
}

// The agreement row under the spans' list: each frame's mask IoU over time (0 to 1), the low frames
// (below 0.8 x the median) marked. Draws into rows [y, y + kAgreementHeight) of `img`.
constexpr int kAgreementHeight = 150;
const cv::Scalar kAgreement(60, 140, 40), kLow(40, 40, 220);
template <typename ToX>
void drawAgreement(cv::Mat& img, const std::vector<FrameRecord>& frames, const AgreementSummary& a, ToX X, int x0,
                   int x1, int y) {
  const int p0 = y + 34, p1 = y + kAgreementHeight - 16;
  auto Y = [&](double v) { return p1 - static_cast<int>(std::lround(std::clamp(v, 0.0, 1.0) * (p1 - p0))); };
  text(img,
       "Robot masks: IoU with the drawn robot over " + std::to_string(a.frames) + " frames, mean " +
           formatNumber(a.mean, 3) + ", smallest " + formatNumber(a.min, 3) + "; " + std::to_string(a.low.size()) +
           " frames below " + formatNumber(a.low_below, 3) +
           " (0.8 x the median: the state and the video disagree there)",
       {x0, y + 18}, 0.45, kInk);
  for (double v : {0.0, 0.5, 1.0}) {
    cv::line(img, {x0, Y(v)}, {x1, Y(v)}, kGrid, 1);
    const std::string label = formatNumber(v, 2);
    text(img, label, {x0 - 8 - textWidth(label, 0.42), Y(v) + 5}, 0.42, kInk);
  }
  text(img, "IoU", {8, p0 + 10}, 0.42, kInk);
  for (const std::size_t i : a.low) cv::line(img, {X(frames[i].time), p0}, {X(frames[i].time), p1}, kLow, 1);
  std::vector<cv::Point> run;
  auto flush = [&] {
    if (run.size() == 1) cv::circle(img, run[0], 2, kAgreement, cv::FILLED, cv::LINE_AA);
    if (run.size() > 1) cv::polylines(img, run, false, kAgreement, 2, cv::LINE_AA);
    run.clear();
  };
  for (const FrameRecord& f : frames) {
    if (!f.mask_iou) {
      flush();
      continue;
    }
    run.emplace_back(X(f.time), Y(*f.mask_iou));
  }
  flush();
  cv::rectangle(img, {x0, p0}, {x1, p1}, kInk, 1);
}

struct Span {
  std::size_t first = 0, last = 0;  // frame positions in the report
  int shade = 0;
  double min_distance = HUGE_VAL;
  std::string pair;  // the link pair within the margin in most of its frames
};

}  // namespace

cv::Mat drawTimeline(const OverlayReport& report, const Model& model, const std::string& title, int width) {
  if (width < 480 || width > 8192)
    throw InputError("timeline: width " + std::to_string(width) + " is not within 480 ... 8192 pixels");
  const std::vector<FrameRecord>& frames = report.frames;
  if (frames.empty()) throw InputError("timeline: the run has no frame");
  const double margin = report.margin;

  // Spans of equal shade; each named by its most frequent link pair.
  std::vector<Span> spans;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const int s = shadeOf(frames[i]);
    if (s == 0) continue;
    if (spans.empty() || spans.back().shade != s || spans.back().last + 1 != i) spans.push_back({i, i, s});
    Span& sp = spans.back();
    sp.last = i;
    if (std::isfinite(frames[i].min_distance)) sp.min_distance = std::min(sp.min_distance, frames[i].min_distance);
  }
  for (Span& sp : spans) {
    std::map<std::string, std::size_t> votes;
    for (std::size_t i = sp.first; i <= sp.last; ++i)
      for (const auto& p : linkPairs(model, frames[i].pairs)) ++votes[p[0] + " x " + p[1]];
    std::size_t best = 0;
    for (const auto& [name, n] : votes)
      if (n > best) best = n, sp.pair = name;
  }

  // The axes: time over the frames; distance from 0 to a round value above the margin and most bounds.
  const double t0 = frames.front().time, t1 = std::max(frames.back().time, t0 + 1e-6);
  std::vector<double> d;
  for (const FrameRecord& f : frames)
    if (std::isfinite(f.min_distance)) d.push_back(std::max(f.min_distance, 0.0));
  std::sort(d.begin(), d.end());
  double top = d.empty() ? 1.0 : d[std::min(d.size() - 1, d.size() * 9 / 10)];
  top = std::max({top, 3.0 * margin, 1e-3});
  const double ystep = tickStep(top, 5);
  top = std::ceil(top / ystep - 1e-9) * ystep;

  std::vector<const Span*> listed;
  for (const Span& sp : spans) listed.push_back(&sp);
  std::stable_sort(listed.begin(), listed.end(), [](const Span* a, const Span* b) {
    return severity(a->shade) != severity(b->shade) ? severity(a->shade) < severity(b->shade)
                                                    : a->min_distance < b->min_distance;
  });
  const std::size_t shown = std::min(listed.size(), kListed);

  const int left = 86, right = 24, head = 74, plot_h = 300, axis_h = 62;
  const int list_h = 30 + static_cast<int>(shown) * 22 + (listed.size() > shown ? 22 : 0) + (spans.empty() ? 0 : 8);
  const AgreementSummary agreement = summariseAgreement(frames);
  const int height = head + plot_h + axis_h + list_h + (agreement.frames > 0 ? kAgreementHeight : 0);
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int x0 = left, x1 = width - right, y0 = head, y1 = head + plot_h;
  auto X = [&](double t) { return x0 + static_cast<int>(std::lround((t - t0) / (t1 - t0) * (x1 - x0))); };
  auto Y = [&](double v) { return y1 - static_cast<int>(std::lround(std::clamp(v, 0.0, top) / top * (y1 - y0))); };
  // Each frame covers from the midpoint with its predecessor to the one with its successor.
  auto edgeBefore = [&](std::size_t i) { return i == 0 ? x0 : X(0.5 * (frames[i - 1].time + frames[i].time)); };
  auto edgeAfter = [&](std::size_t i) {
    return i + 1 == frames.size() ? x1 : X(0.5 * (frames[i].time + frames[i + 1].time));
  };

  // Title and counts.
  text(img, title, {left, 26}, 0.62, kInk, 1);
  std::string counts = std::to_string(frames.size()) + " frames over " + formatNumber(t1 - t0, 4) +
                       " s:  " + std::to_string(report.clear) + " clear, " + std::to_string(report.within_margin) +
                       " within margin (" + formatNumber(margin, 4) + " m), " + std::to_string(report.colliding) +
                       " colliding, " + std::to_string(report.no_state) + " no state";
  if (report.unsafe > 0) counts += ", " + std::to_string(report.unsafe) + " unsafe";
  if (report.swept) counts += ";  swept volumes";
  text(img, counts, {left, 50}, 0.45, kInk);

  // Shaded spans, grid, margin line, the curve.
  for (const Span& sp : spans)
    cv::rectangle(img, cv::Point(edgeBefore(sp.first), y0),
                  cv::Point(std::max(edgeAfter(sp.last), edgeBefore(sp.first) + 1), y1), shadeFill(sp.shade),
                  cv::FILLED);
  for (double v = 0; v <= top + 1e-12; v += ystep) {
    cv::line(img, {x0, Y(v)}, {x1, Y(v)}, kGrid, 1);
    const std::string label = formatNumber(v, 4);
    text(img, label, {x0 - 8 - textWidth(label, 0.42), Y(v) + 5}, 0.42, kInk);
  }
  const double xstep = tickStep(t1 - t0, std::max(2, (x1 - x0) / 110));
  for (double t = std::ceil(t0 / xstep - 1e-9) * xstep + 0.0; t <= t1 + 1e-9; t += xstep) {
    cv::line(img, {X(t), y1}, {X(t), y1 + 5}, kInk, 1);
    const std::string label = formatNumber(std::abs(t) < 1e-9 * xstep ? 0.0 : t, 6);
    text(img, label, {X(t) - textWidth(label, 0.42) / 2, y1 + 20}, 0.42, kInk);
  }
  text(img, "time (s)", {8, y1 + 20}, 0.42, kInk);
  text(img, "bound (m)", {8, y0 - 10}, 0.42, kInk);
  if (margin > 0.0) {
    for (int x = x0; x < x1; x += 12) cv::line(img, {x, Y(margin)}, {std::min(x + 7, x1), Y(margin)}, kMarginLine, 2);
    const std::string label = "margin " + formatNumber(margin, 4) + " m";
    text(img, label, {x1 - textWidth(label, 0.42) - 4, Y(margin) - 6}, 0.42, kMarginLine);
  }
  std::vector<cv::Point> run;
  auto flush = [&] {
    if (run.size() == 1) cv::circle(img, run[0], 2, kCurve, cv::FILLED, cv::LINE_AA);
    if (run.size() > 1) cv::polylines(img, run, false, kCurve, 2, cv::LINE_AA);
    run.clear();
  };
  for (const FrameRecord& f : frames) {
    if (!std::isfinite(f.min_distance)) {
      flush();
      continue;
    }
    run.emplace_back(X(f.time), Y(f.min_distance));
  }
  flush();
  cv::rectangle(img, {x0, y0}, {x1, y1}, kInk, 1);

  // Span numbers above the plot (the listed ones), contact-sheet frames below the axis.
  for (std::size_t k = 0; k < shown; ++k) {
    const Span& sp = *listed[k];
    const int xc = (edgeBefore(sp.first) + edgeAfter(sp.last)) / 2;
    const std::string n = std::to_string(k + 1);
    text(img, n, {xc - textWidth(n, 0.4) / 2, y0 - 4}, 0.4, kInk);
  }
  for (const std::size_t i : report.contact_sheet_frames) {
    if (i >= frames.size()) continue;
    const int x = X(frames[i].time);
    const std::vector<cv::Point> tri{{x, y1 + 24}, {x - 5, y1 + 33}, {x + 5, y1 + 33}};
    cv::fillConvexPoly(img, tri, kInk, cv::LINE_AA);
  }

  // The key and the list of spans.
  int ky = y1 + axis_h - 8, kx = x0;
  auto key = [&](const cv::Scalar& c, const std::string& s, bool line) {
    if (line)
      cv::line(img, {kx, ky - 5}, {kx + 18, ky - 5}, c, 2, cv::LINE_AA);
    else
      cv::rectangle(img, {kx, ky - 11}, {kx + 18, ky + 1}, c, cv::FILLED);
    text(img, s, {kx + 24, ky}, 0.42, kInk);
    kx += 24 + textWidth(s, 0.42) + 22;
  };
  key(kCurve, "smallest distance bound", true);
  if (margin > 0.0) key(kMarginLine, "safety margin", true);
  key(kWithinFill, "within margin", false);
  key(kCollidingFill, "colliding", false);
  key(kNoStateFill, "no state", false);
  if (report.unsafe > 0) key(kUnsafeFill, "unsafe (stop)", false);
  if (!report.contact_sheet_frames.empty()) {
    const std::vector<cv::Point> tri{{kx + 9, ky - 11}, {kx + 4, ky - 2}, {kx + 14, ky - 2}};
    cv::fillConvexPoly(img, tri, kInk, cv::LINE_AA);
    text(img, "on the contact sheet", {kx + 24, ky}, 0.42, kInk);
  }
  int ly = y1 + axis_h + 24;
  if (spans.empty()) {
    text(img, "No frame within the margin, colliding or without a state.", {x0, ly}, 0.45, kInk);
  } else {
    text(img,
         "Spans, the most severe first (number above the plot; time of the first and last frame; smallest bound; pair "
         "in most frames):",
         {x0, ly}, 0.42, kInk);
    for (std::size_t k = 0; k < shown; ++k) {
      const Span& sp = *listed[k];
      ly += 22;
      cv::rectangle(img, {x0, ly - 12}, {x0 + 14, ly + 2}, shadeFill(sp.shade), cv::FILLED);
      std::string line =
          std::to_string(k + 1) + "   " + formatNumber(frames[sp.first].time, 6) + " - " +
          formatNumber(frames[sp.last].time, 6) +
          (sp.first == sp.last ? " s (frame " + std::to_string(sp.first)
                               : " s (frames " + std::to_string(sp.first) + "-" + std::to_string(sp.last)) +
          ")   " + shadeWord(sp.shade);
      if (std::isfinite(sp.min_distance)) line += "   " + formatNumber(sp.min_distance * 1000.0, 4) + " mm";
      if (!sp.pair.empty()) line += "   " + sp.pair;
      text(img, line, {x0 + 22, ly}, 0.45, kInk);
    }
    if (listed.size() > shown) {
      ly += 22;
      text(img, "... and " + std::to_string(listed.size() - shown) + " more spans (see the report)", {x0 + 22, ly},
           0.45, kInk);
    }
  }
  if (agreement.frames > 0) drawAgreement(img, frames, agreement, X, x0, x1, head + plot_h + axis_h + list_h);
  return img;
}

}  // namespace kccd::overlay
