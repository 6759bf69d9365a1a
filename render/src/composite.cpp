#include "kccd/render/composite.hpp"

#include <stdexcept>

namespace kccd::render {

void compositeOver(cv::Mat& frame_bgr, const cv::Mat& layer_bgra) {
  if (frame_bgr.type() != CV_8UC3 || layer_bgra.type() != CV_8UC4 || frame_bgr.size() != layer_bgra.size())
    throw std::invalid_argument("compositeOver: needs a CV_8UC3 frame and a CV_8UC4 layer of the same size");
  for (int y = 0; y < frame_bgr.rows; ++y) {
    auto* out = frame_bgr.ptr<cv::Vec3b>(y);
    const auto* in = layer_bgra.ptr<cv::Vec4b>(y);
    for (int x = 0; x < frame_bgr.cols; ++x) {
      const int a = in[x][3];
      if (a == 0) continue;
      for (int c = 0; c < 3; ++c)
        out[x][c] = static_cast<unsigned char>((in[x][c] * a + out[x][c] * (255 - a) + 127) / 255);
    }
  }
}

}  // namespace kccd::render
