#include "kccd/render/status_legend.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "kccd/render/render_types.hpp"

namespace kccd::render {

cv::Mat statusLegend(const TextMetrics& text, int columns) {
  if (columns != 1 && columns != 2 && columns != 4) throw std::invalid_argument("statusLegend: 1, 2 or 4 columns");
  const SafetyStatus all[] = {SafetyStatus::Clear, SafetyStatus::WithinMargin, SafetyStatus::Colliding,
                              SafetyStatus::NoState};
  const char* names[] = {"clear", "within margin", "colliding", "no state"};
  // Per cell a swatch a line high, then the name; each column as wide as its widest name.
  const int pad = text.pad, row = text.height + 2 * pad, rows = (4 + columns - 1) / columns;
  std::vector<int> left(static_cast<std::size_t>(columns) + 1, 0);
  for (int c = 0; c < columns; ++c) {
    int widest = 0;
    for (int i = c; i < 4; i += columns) widest = std::max(widest, text.width(names[i]));
    left[static_cast<std::size_t>(c) + 1] = left[static_cast<std::size_t>(c)] + row + widest + 2 * pad;
  }
  cv::Mat bgra(rows * row + pad, left.back() + pad, CV_8UC4, cv::Scalar(30, 30, 30, 170));
  for (int i = 0; i < 4; ++i) {
    const int x = left[static_cast<std::size_t>(i % columns)], y = pad + (i / columns) * row;
    const cv::Scalar c = statusColour(all[i]);
    cv::rectangle(bgra, cv::Rect(x + pad, y + pad / 2, row - pad, row - pad), cv::Scalar(c[0], c[1], c[2], 255),
                  cv::FILLED);
    const cv::Point at(x + row + pad, y + text.height + pad / 2);
    cv::putText(bgra, names[i], at, text.font, text.scale, cv::Scalar(0, 0, 0, 255), text.thickness + 2, cv::LINE_AA);
    cv::putText(bgra, names[i], at, text.font, text.scale, cv::Scalar(255, 255, 255, 255), text.thickness, cv::LINE_AA);
  }
  return bgra;
}

}  // namespace kccd::render
