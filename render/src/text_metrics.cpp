#include "kccd/render/text_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace kccd::render {

int TextMetrics::width(const std::string& text) const {
  int baseline = 0;
  return cv::getTextSize(text, font, scale, thickness, &baseline).width;
}

TextMetrics textMetrics(int rows) {
  TextMetrics m;
  m.scale = std::max(kMinTextScale, rows / 900.0);
  m.thickness = std::max(1, static_cast<int>(std::lround(m.scale * 2)));
  m.height = cv::getTextSize("A", m.font, m.scale, m.thickness, &m.descent).height;
  m.pad = std::max(2, m.height / 2);
  m.margin = m.pad;
  return m;
}

}  // namespace kccd::render
