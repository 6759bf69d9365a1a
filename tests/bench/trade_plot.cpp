#include "trade_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace kccd::bench {
namespace {

const cv::Scalar kBlack(0, 0, 0), kGrid(225, 225, 225), kWhite(255, 255, 255);
const cv::Scalar kSeriesColours[] = {{200, 110, 20}, {30, 40, 200}, {40, 150, 40}, {150, 40, 150}};
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// A plotting area: x on a log10 scale, y linear.
struct Axes {
  cv::Rect area;
  double lx0 = 0.0, lx1 = 1.0;  // log10 of the x range
  double y0 = 0.0, y1 = 1.0;

  cv::Point at(double x, double y) const {
    const double fx = (std::log10(x) - lx0) / (lx1 - lx0);
    const double fy = (y - y0) / (y1 - y0);
    return {area.x + static_cast<int>(std::lround(fx * area.width)),
            area.y + area.height - static_cast<int>(std::lround(fy * area.height))};
  }
};

void text(cv::Mat& img, const std::string& s, cv::Point p, double scale, const cv::Scalar& colour, bool centred = false,
          bool right = false) {
  int base = 0;
  const cv::Size size = cv::getTextSize(s, kFont, scale, 1, &base);
  if (centred) p.x -= size.width / 2;
  if (right) p.x -= size.width;
  cv::putText(img, s, p, kFont, scale, colour, 1, cv::LINE_AA);
}

// Text turned 90 degrees counter-clockwise, centred on `centre` (a y axis label).
void verticalText(cv::Mat& img, const std::string& s, cv::Point centre, double scale) {
  int base = 0;
  const cv::Size size = cv::getTextSize(s, kFont, scale, 1, &base);
  cv::Mat strip(size.height + base + 4, size.width + 4, CV_8UC3, kWhite);
  cv::putText(strip, s, {2, size.height + 2}, kFont, scale, kBlack, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect dst(centre.x - turned.cols / 2, centre.y - turned.rows / 2, turned.cols, turned.rows);
  if ((dst & cv::Rect(0, 0, img.cols, img.rows)) == dst) turned.copyTo(img(dst));
}

// A tick spacing of 1, 2 or 5 times a power of ten giving about `count` ticks over `range`.
double niceStep(double range, int count) {
  const double raw = range / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

void drawFrame(cv::Mat& img, const Axes& ax, const std::string& ylabel, bool xlabels) {
  for (int k = static_cast<int>(std::floor(ax.lx0)); k <= static_cast<int>(std::ceil(ax.lx1)); ++k)
    for (double m : {1.0, 1.5, 2.0, 3.0, 5.0, 7.0}) {
      const double x = m * std::pow(10.0, k);
      if (std::log10(x) < ax.lx0 - 1e-9 || std::log10(x) > ax.lx1 + 1e-9) continue;
      const cv::Point p = ax.at(x, ax.y0);
      cv::line(img, {p.x, ax.area.y}, {p.x, ax.area.y + ax.area.height}, kGrid, 1);
      if (xlabels) text(img, format("%g", x), {p.x, p.y + 16}, 0.4, kBlack, true);
    }
  const double step = niceStep(ax.y1 - ax.y0, 4);
  for (double y = std::ceil(ax.y0 / step) * step; y <= ax.y1 + 1e-9 * step; y += step) {
    const cv::Point p = ax.at(std::pow(10.0, ax.lx0), y);
    cv::line(img, {ax.area.x, p.y}, {ax.area.x + ax.area.width, p.y}, kGrid, 1);
    text(img, format("%g", std::abs(y) < 1e-12 ? 0.0 : y), {p.x - 6, p.y + 4}, 0.4, kBlack, false, true);
  }
  cv::rectangle(img, ax.area, kBlack, 1);
  verticalText(img, ylabel, {ax.area.x - 52, ax.area.y + ax.area.height / 2}, 0.45);
}

void drawSeries(cv::Mat& img, const Axes& ax, const TradeSeries& s, const cv::Scalar& colour, bool y_is_looseness,
                bool label_budgets) {
  std::vector<cv::Point> pts;
  for (const TradePoint& p : s.points) {
    const double y = y_is_looseness ? p.looseness_p90_mm : p.false_alarm_pct;
    if (!std::isfinite(y) || !(p.distances_us > 0.0)) continue;
    pts.push_back(ax.at(p.distances_us, y));
    if (label_budgets) text(img, std::to_string(p.budget), pts.back() + cv::Point(5, -6), 0.38, colour);
  }
  if (pts.size() > 1) cv::polylines(img, pts, false, colour, 2, cv::LINE_AA);
  for (const cv::Point& p : pts) cv::circle(img, p, 4, colour, cv::FILLED, cv::LINE_AA);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
};

void drawCell(cv::Mat& img, cv::Rect cell, const TradeCell& c) {
  Range x, loose, alarms;
  for (const TradeSeries& s : c.series)
    for (const TradePoint& p : s.points) {
      if (p.distances_us > 0.0) x.add(p.distances_us);
      loose.add(p.looseness_p90_mm);
      alarms.add(p.false_alarm_pct);
    }
  if (!(x.lo <= x.hi)) x = {1.0, 10.0};
  const double lx0 = std::log10(x.lo) - 0.08, lx1 = std::max(std::log10(x.hi) + 0.08, std::log10(x.lo) + 0.3);
  const double ytop = loose.hi > 0.0 ? loose.hi * 1.12 : 1.0;
  const double atop = std::max(10.0, std::isfinite(alarms.hi) ? std::min(100.0, alarms.hi * 1.15) : 10.0);

  const int left = cell.x + 80, width = cell.width - 110;
  const Axes top{{left, cell.y + 40, width, (cell.height - 120) * 2 / 3}, lx0, lx1, 0.0, ytop};
  const int ybottom = top.area.y + top.area.height + 14;
  const Axes bottom{{left, ybottom, width, cell.y + cell.height - 62 - ybottom}, lx0, lx1, 0.0, atop};

  text(img, c.title, {cell.x + cell.width / 2, cell.y + 24}, 0.55, kBlack, true);
  drawFrame(img, top, "looseness p90 in band (mm)", false);
  drawFrame(img, bottom, "false alarms (% boxes)", true);
  text(img, "distances query time, cold median (us, log scale)",
       {left + width / 2, bottom.area.y + bottom.area.height + 38}, 0.45, kBlack, true);
  for (std::size_t i = 0; i < c.series.size(); ++i) {
    const cv::Scalar& colour = kSeriesColours[i % std::size(kSeriesColours)];
    drawSeries(img, top, c.series[i], colour, true, true);
    drawSeries(img, bottom, c.series[i], colour, false, false);
    // Legend, top right inside the upper panel.
    const cv::Point l(top.area.x + top.area.width - 110, top.area.y + 20 + 20 * static_cast<int>(i));
    cv::line(img, l, l + cv::Point(24, 0), colour, 2, cv::LINE_AA);
    cv::circle(img, l + cv::Point(12, 0), 4, colour, cv::FILLED, cv::LINE_AA);
    text(img, c.series[i].label, l + cv::Point(30, 4), 0.4, kBlack);
  }
  text(img, "numbers at the points: point budget", {top.area.x + 8, top.area.y + 18}, 0.4, kBlack);
}

}  // namespace

bool writeTradePlot(const std::string& path, const std::string& title, const std::vector<TradeCell>& cells, int columns,
                    std::string& error) {
  const int cw = 760, ch = 560, header = 44;
  const int rows = (static_cast<int>(cells.size()) + columns - 1) / columns;
  cv::Mat img(header + rows * ch, columns * cw, CV_8UC3, kWhite);
  text(img, title, {img.cols / 2, 30}, 0.7, kBlack, true);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const int r = static_cast<int>(i) / columns, c = static_cast<int>(i) % columns;
    drawCell(img, {c * cw, header + r * ch, cw, ch}, cells[i]);
  }
  try {
    if (cv::imwrite(path, img)) return true;
    error = "could not write " + path;
  } catch (const cv::Exception& e) {
    error = path + ": " + e.what();
  }
  return false;
}

}  // namespace kccd::bench
