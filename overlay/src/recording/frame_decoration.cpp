#include "kccd/overlay/recording/frame_decoration.hpp"

#include <algorithm>
#include <climits>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "kccd/overlay/recording/status_line.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/status_legend.hpp"

namespace kccd::overlay {
namespace {

const std::pair<const char*, LegendPlace> kPlaces[] = {{"auto", LegendPlace::Auto},
                                                       {"outside", LegendPlace::Outside},
                                                       {"off", LegendPlace::Off},
                                                       {"top-left", LegendPlace::TopLeft},
                                                       {"top-right", LegendPlace::TopRight},
                                                       {"bottom-left", LegendPlace::BottomLeft},
                                                       {"bottom-right", LegendPlace::BottomRight}};

// `legend` scaled down (by area averaging) to fit `room`; empty when it would be under 8 px.
cv::Mat fitted(const cv::Mat& legend, cv::Size room) {
  if (legend.cols <= room.width && legend.rows <= room.height) return legend;
  const double s =
      std::min(static_cast<double>(room.width) / legend.cols, static_cast<double>(room.height) / legend.rows);
  const cv::Size size(static_cast<int>(legend.cols * s), static_cast<int>(legend.rows * s));
  if (size.width < 8 || size.height < 8) return {};
  cv::Mat small;
  cv::resize(legend, small, size, 0, 0, cv::INTER_AREA);
  return small;
}

// Each byte times 0.35, rounded as convertTo rounds, through a table made by convertTo itself (a
// table look-up per byte is several times faster than convertTo's arithmetic on a strip of the image).
const cv::Mat& darkening() {
  static const cv::Mat table = [] {
    cv::Mat ramp(1, 256, CV_8U), out;
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = static_cast<uchar>(i);
    ramp.convertTo(out, -1, 0.35, 0);
    return out;
  }();
  return table;
}

}  // namespace

std::optional<LegendPlace> legendPlaceOf(const std::string& word) {
  for (const auto& [name, place] : kPlaces)
    if (word == name) return place;
  return std::nullopt;
}

std::string legendPlaceWords() {
  std::string s;
  const std::size_t n = std::size(kPlaces);
  for (std::size_t i = 0; i < n; ++i)
    s += (i == 0 ? "'" : i + 1 == n ? " or '" : ", '") + std::string(kPlaces[i].first) + "'";
  return s;
}

FrameDecoration::FrameDecoration(cv::Size picture, LegendPlace place, bool status_line)
    : picture_(picture),
      frame_(picture),
      text_(render::textMetrics(picture.height)),
      status_line_(status_line),
      outside_(place == LegendPlace::Outside) {
  const int m = text_.margin, line = text_.height + text_.descent + 2 * text_.pad;
  const int status_band = status_line ? line + m : 0;  // the status line and the margin above it
  if (outside_) {
    // The strip: the status line, then the legend in as few rows as the width allows.
    const int room = picture.width - 2 * m;
    int columns = 4;
    cv::Mat legend = render::statusLegend(text_, columns);
    while (columns > 1 && legend.cols > room) legend = render::statusLegend(text_, columns /= 2);
    legend_ = fitted(legend, {room, INT_MAX});
    int strip = m + status_band + (legend_.empty() ? 0 : legend_.rows + m);
    strip += strip % 2;
    frame_.height += strip;
    strip_legend_ = {m, picture.height + m + status_band};
    return;
  }
  if (place == LegendPlace::Off) return;
  legend_ = fitted(render::statusLegend(text_), {picture.width - 2 * m, picture.height - 2 * m - status_band});
  if (legend_.empty()) return;
  const int w = legend_.cols, h = legend_.rows;
  const int right = picture.width - m - w, bottom = picture.height - m - status_band - h;
  const std::vector<cv::Rect> all{{m, m, w, h}, {right, m, w, h}, {m, bottom, w, h}, {right, bottom, w, h}};
  if (place == LegendPlace::Auto)
    corners_ = all;
  else
    corners_ = {all[static_cast<std::size_t>(place) - static_cast<std::size_t>(LegendPlace::TopLeft)]};
}

int FrameDecoration::statusWidth() const { return picture_.width - 2 * text_.margin - 2 * text_.pad; }

cv::Rect FrameDecoration::statusBox(const std::string& status) const {
  if (!status_line_ || status.empty()) return {};
  const int m = text_.margin, line = text_.height + text_.descent + 2 * text_.pad;
  const cv::Rect box(m, outside_ ? picture_.height + m : picture_.height - m - line,
                     text_.width(status) + 2 * text_.pad, line);
  return box & cv::Rect(0, 0, picture_.width - m, frame_.height);
}

void FrameDecoration::draw(cv::Mat& frame, const std::string& status, const cv::Scalar& colour, int corner) const {
  if (frame.type() != CV_8UC3 || frame.size() != frame_)
    throw std::invalid_argument("FrameDecoration::draw: needs a CV_8UC3 frame of frameSize()");
  if (outside_) frame.rowRange(picture_.height, frame_.height).setTo(cv::Scalar(24, 24, 24));
  if (const cv::Rect box = statusBox(status); !box.empty()) {
    if (!outside_) {  // the picture under the text darkened: readable on any frame
      cv::Mat under = frame(box);
      cv::LUT(under, darkening(), under);
    }
    const cv::Point at(box.x + text_.pad, box.y + text_.pad + text_.height);
    cv::putText(frame, status, at, text_.font, text_.scale, colour, text_.thickness, cv::LINE_AA);
  }
  if (legend_.empty()) return;
  cv::Rect where;
  if (outside_)
    where = cv::Rect(strip_legend_, legend_.size());
  else if (!corners_.empty())
    where = corners_[static_cast<std::size_t>(std::clamp<int>(corner, 0, static_cast<int>(corners_.size()) - 1))];
  if (where.empty()) return;
  cv::Mat part = frame(where);
  render::compositeOver(part, legend_);
}

cv::Mat& decorateFrame(cv::Mat& picture, cv::Mat& tall, const FrameDecoration& decoration, const FrameRecord& record,
                       const Model& model, const AnnotatorSettings& settings, int corner) {
  cv::Mat* frame = &picture;
  if (decoration.frameSize() != picture.size()) {
    tall.create(decoration.frameSize(), CV_8UC3);
    picture.copyTo(tall.rowRange(0, picture.rows));
    frame = &tall;
  }
  const std::string status = decoration.statusLine()
                                 ? fitStatus(statusFields(record, model, settings), decoration.statusWidth(),
                                             [&](const std::string& text) { return decoration.text().width(text); })
                                 : std::string();
  decoration.draw(*frame, status, statusTextColour(record.status), corner);
  return *frame;
}

}  // namespace kccd::overlay
