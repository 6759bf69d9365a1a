// The distortion warp (internal): the pinhole images GL draws carried into the camera image,
// the colour layer bilinearly (and made straight-alpha on the way), the labels at the nearest
// pinhole pixel (and counted on the way). The remap tables are made on first use.
#pragma once

#include <array>
#include <span>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/render/projection.hpp"

namespace kccd::render::detail {

/// Which square tiles of an image hold drawn pixels.
class TileMask {
 public:
  static constexpr int kTile = 16;  ///< pixels per side of a tile
  TileMask(int width, int height);
  int tiles() const { return static_cast<int>(on_.size()); }
  int tilesX() const { return tiles_x_; }
  /// Tile t's pixels (row-major tiles, clipped to the image).
  cv::Rect tile(int t) const;
  void mark(int t) { on_[static_cast<std::size_t>(t)] = 1; }
  /// Marks every tile that meets `pixels`.
  void mark(const cv::Rect& pixels);
  bool marked(int t) const { return on_[static_cast<std::size_t>(t)] != 0; }
  /// The marked tiles as disjoint rectangles: the runs of marked tiles along each row of tiles.
  std::vector<cv::Rect> runs() const;

 private:
  int width_ = 0, height_ = 0, tiles_x_ = 0;
  std::vector<unsigned char> on_;
};

/// The colour layer's way into the camera image through one projection (which must outlive it).
class ColourWarp {
 public:
  explicit ColourWarp(const Projection& projection) : projection_(projection) {}
  /// The camera image (CV_8UC4, straight alpha) of a premultiplied pinhole image that is zero
  /// outside the rectangles `drawn` (pinhole pixels); `tiles` (the camera image's) gets the tiles
  /// whose samples may read them marked, and the result is zero outside those: only they are
  /// warped. The pixels are those of warping the whole image.
  cv::Mat apply(const cv::Mat& premultiplied, std::span<const cv::Rect> drawn, TileMask& tiles);
  /// The same layer composited straight onto `bgr` (CV_8UC3, the camera image's size) as
  /// compositeOver would, without making it; pixels inside `keep_out` are left alone. `tiles`
  /// gets the same tiles marked as apply() marks.
  void blendOnto(cv::Mat& bgr, const cv::Mat& premultiplied, std::span<const cv::Rect> drawn, TileMask& tiles,
                 const cv::Rect& keep_out);

 private:
  /// Marks the camera tiles whose samples may read a drawn pinhole pixel; returns their runs.
  std::vector<cv::Rect> markTiles(std::span<const cv::Rect> drawn, TileMask& tiles);

  const Projection& projection_;
  cv::Mat map_a_, map_b_;              // remap tables in fixed point
  std::vector<cv::Rect> tile_source_;  // per camera tile (TileMask order), the pinhole pixels its warp may read
  std::vector<int> grid_sums_;         // markTiles' scratch: drawn pinhole cells, summed
};

/// The labels' way into the camera image through the mask pass's projection (which must outlive it).
class LabelWarp {
 public:
  explicit LabelWarp(const Projection& projection) : projection_(projection) {}
  /// The camera image's labels (CV_8UC1: each pixel the label of its nearest pinhole pixel, 0
  /// outside the pinhole image; without a warp the pinhole labels themselves), and in `counts`
  /// the pixels of each label.
  cv::Mat apply(const cv::Mat& pinhole_labels, std::array<int, 256>& counts);

 private:
  const Projection& projection_;
  cv::Mat map_;  // nearest pinhole pixel per output pixel, as integers
  std::vector<std::pair<int, int>> source_rows_;
};

}  // namespace kccd::render::detail
