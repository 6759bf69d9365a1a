#include "kccd/overlay/recording/contact_sheet.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace kccd::overlay {

ContactSheet::ContactSheet(std::size_t count, int tile_width)
    : count_(std::max<std::size_t>(1, count)), tile_width_(tile_width) {}

cv::Mat ContactSheet::thumbnail(const cv::Mat& frame) const {
  const double scale = static_cast<double>(tile_width_) / frame.cols;
  cv::Mat small;
  cv::resize(frame, small, cv::Size(tile_width_, std::max(1, static_cast<int>(std::lround(frame.rows * scale)))), 0, 0,
             cv::INTER_AREA);
  return small;
}

void ContactSheet::add(std::size_t index, const cv::Mat& frame, const std::string& caption, double priority) {
  if (frame.empty()) return;
  if (!has_critical_ || priority < critical_priority_) {
    critical_ = {index, thumbnail(frame), caption};
    critical_priority_ = priority;
    has_critical_ = true;
  }
  if (index % stride_ != 0) return;
  kept_.push_back({index, thumbnail(frame), caption});
  if (kept_.size() >= 2 * count_) {  // keep every other one and take every other frame from now on
    std::vector<Tile> half;
    for (std::size_t i = 0; i < kept_.size(); i += 2) half.push_back(std::move(kept_[i]));
    kept_ = std::move(half);
    stride_ *= 2;
  }
}

std::vector<const ContactSheet::Tile*> ContactSheet::pick() const {
  std::vector<const Tile*> pick;
  const std::size_t even = has_critical_ ? count_ - 1 : count_;
  for (std::size_t k = 0; k < even && !kept_.empty(); ++k) {
    const std::size_t at = even == 1 ? 0 : k * (kept_.size() - 1) / (even - 1);
    if (pick.empty() || pick.back() != &kept_[at]) pick.push_back(&kept_[at]);
  }
  if (has_critical_ &&
      std::none_of(pick.begin(), pick.end(), [&](const Tile* t) { return t->index == critical_.index; }))
    pick.push_back(&critical_);
  std::sort(pick.begin(), pick.end(), [](const Tile* a, const Tile* b) { return a->index < b->index; });
  return pick;
}

std::vector<std::size_t> ContactSheet::frames() const {
  std::vector<std::size_t> out;
  for (const Tile* t : pick()) out.push_back(t->index);
  return out;
}

cv::Mat ContactSheet::compose() const {
  const std::vector<const Tile*> pick = this->pick();
  if (pick.empty()) return {};
  const int cols = static_cast<int>(std::min<std::size_t>(4, pick.size()));
  const int rows = static_cast<int>((pick.size() + cols - 1) / cols);
  const int caption_h = 22, gap = 4;
  int tile_h = 0;  // the tallest tile: frames of several cameras may differ in aspect
  for (const Tile* t : pick) tile_h = std::max(tile_h, t->image.rows);
  cv::Mat sheet(rows * (tile_h + caption_h + gap) + gap, cols * (tile_width_ + gap) + gap, CV_8UC3,
                cv::Scalar(40, 40, 40));
  for (std::size_t i = 0; i < pick.size(); ++i) {
    const int r = static_cast<int>(i) / cols, c = static_cast<int>(i) % cols;
    const int x = gap + c * (tile_width_ + gap), y = gap + r * (tile_h + caption_h + gap);
    const cv::Mat& img = pick[i]->image;
    img.copyTo(sheet(cv::Rect(x, y, img.cols, img.rows)));
    cv::putText(sheet, pick[i]->caption, {x + 2, y + tile_h + 16}, cv::FONT_HERSHEY_SIMPLEX, 0.42,
                cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
  }
  return sheet;
}

}  // namespace kccd::overlay
