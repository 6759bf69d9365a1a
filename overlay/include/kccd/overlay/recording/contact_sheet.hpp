// A contact sheet: selected frames of a long run side by side in one picture, each captioned.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace kccd::overlay {

/// Collects small copies of frames as they stream past in order, keeping memory bounded: every
/// stride-th frame (the stride doubles when 2 x `count` are held) plus the one with the lowest
/// `priority` seen so far; compose() picks `count` of them spread over the run, that one included.
class ContactSheet {
 public:
  ContactSheet(std::size_t count, int tile_width);
  /// Offers frame `index` (BGR) with its caption; a lower priority (e.g. the distance) is kept first.
  void add(std::size_t index, const cv::Mat& frame, const std::string& caption, double priority);
  /// The tiles in index order on a grid (4 columns at most), or an empty Mat when none was added.
  cv::Mat compose() const;
  /// The indices of the frames compose() shows, in order.
  std::vector<std::size_t> frames() const;

 private:
  struct Tile {
    std::size_t index = 0;
    cv::Mat image;
    std::string caption;
  };
  cv::Mat thumbnail(const cv::Mat& frame) const;
  std::vector<const Tile*> pick() const;
  std::size_t count_;
  int tile_width_;
  std::size_t stride_ = 1;
  std::vector<Tile> kept_;
  Tile critical_;
  double critical_priority_ = 0.0;
  bool has_critical_ = false;
};

}  // namespace kccd::overlay
