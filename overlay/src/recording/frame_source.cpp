#include "kccd/overlay/recording/frame_source.hpp"

#include <algorithm>

namespace kccd::overlay {

std::vector<SampledFrame> sampleFrames(FrameSource& source, std::size_t count) {
  count = std::max<std::size_t>(count, 1);
  std::vector<SampledFrame> kept;
  // Every stride-th frame kept; at twice the count, every other one dropped and the stride doubled.
  std::size_t stride = 1, seen = 0;
  for (cv::Mat frame;; ++seen) {
    const std::size_t index = source.nextIndex();
    if (!source.read(frame)) break;
    if (seen % stride != 0) continue;
    kept.push_back({index, frame.clone()});
    if (kept.size() == 2 * count) {
      for (std::size_t k = 0; k < count; ++k) kept[k] = std::move(kept[2 * k]);
      kept.resize(count);
      stride *= 2;
    }
  }
  if (kept.size() <= count) return kept;
  std::vector<SampledFrame> out;  // between count and 2 count: evenly
  for (std::size_t k = 0; k < count; ++k) out.push_back(std::move(kept[k * kept.size() / count]));
  return out;
}

}  // namespace kccd::overlay
