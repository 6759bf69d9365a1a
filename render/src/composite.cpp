#include "kccd/render/composite.hpp"

#include <stdexcept>

namespace kccd::render {
namespace {

// One row: `n` BGRA layer pixels over BGR frame pixels; runs of four transparent pixels are
// skipped with one test of their alpha bytes.
void blendRow(unsigned char* out, const unsigned char* in, int n) {
  int x = 0;
  while (x < n) {
    if (x + 4 <= n) {
      const unsigned char* q = in + 4 * x;
      if ((q[3] | q[7] | q[11] | q[15]) == 0) {
        x += 4;
        continue;
      }
    }
    const unsigned char* p = in + 4 * x;
    const unsigned a = p[3];
    if (a != 0) {
      unsigned char* o = out + 3 * x;
      for (int c = 0; c < 3; ++c) o[c] = static_cast<unsigned char>((p[c] * a + o[c] * (255 - a) + 127) / 255);
    }
    ++x;
  }
}

}  // namespace

void compositeOver(cv::Mat& frame_bgr, const cv::Mat& layer_bgra) {
  const cv::Rect whole(0, 0, frame_bgr.cols, frame_bgr.rows);
  compositeOver(frame_bgr, layer_bgra, std::span<const cv::Rect>(&whole, 1));
}

void compositeOver(cv::Mat& frame_bgr, const cv::Mat& layer_bgra, std::span<const cv::Rect> drawn) {
  if (frame_bgr.type() != CV_8UC3 || layer_bgra.type() != CV_8UC4 || frame_bgr.size() != layer_bgra.size())
    throw std::invalid_argument("compositeOver: needs a CV_8UC3 frame and a CV_8UC4 layer of the same size");
  for (const cv::Rect& d : drawn) {
    const cv::Rect r = d & cv::Rect(0, 0, frame_bgr.cols, frame_bgr.rows);
    for (int y = r.y; y < r.y + r.height; ++y)
      blendRow(frame_bgr.ptr<unsigned char>(y, r.x), layer_bgra.ptr<unsigned char>(y, r.x), r.width);
  }
}

}  // namespace kccd::render
