#include "warp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <opencv2/imgproc.hpp>

namespace kccd::render::detail {
namespace {

// Per row of a warp's y map, the source rows its samples may read: the extremes' floors, widened
// by a row each way for the fixed-point rounding and the bilinear neighbour (empty: first > second).
// Samples above row -1 or below row `source_rows` (e.g. the far-off marks of pixels the lens
// model cannot invert) read nothing (the constant border) and are left out.
std::vector<std::pair<int, int>> sourceRows(const cv::Mat& map_y, int source_rows) {
  std::vector<std::pair<int, int>> rows(static_cast<std::size_t>(map_y.rows), {0, -1});
  for (int y = 0; y < map_y.rows; ++y) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (int x = 0; x < map_y.cols; ++x) {
      const float v = map_y.at<float>(y, x);
      if (v > -2.0f && v < static_cast<float>(source_rows) + 1.0f) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    if (lo <= hi)
      rows[static_cast<std::size_t>(y)] = {static_cast<int>(std::floor(lo)) - 1, static_cast<int>(std::floor(hi)) + 2};
  }
  return rows;
}

// Which rows of an image hold a non-zero byte, as prefix counts (rows + 1 entries), to ask of
// any range of rows whether something is drawn in it.
struct DrawnRows {
  std::vector<int> prefix;
  explicit DrawnRows(const cv::Mat& image) : prefix(static_cast<std::size_t>(image.rows) + 1, 0) {
    const std::size_t bytes = image.cols * image.elemSize();
    cv::parallel_for_(cv::Range(0, image.rows), [&](const cv::Range& r) {
      for (int y = r.start; y < r.end; ++y) {
        const uchar* row = image.ptr<uchar>(y);
        uchar any = 0;
        for (std::size_t x = 0; x < bytes; ++x) any |= row[x];
        prefix[static_cast<std::size_t>(y) + 1] = any != 0;
      }
    });
    for (std::size_t y = 1; y < prefix.size(); ++y) prefix[y] += prefix[y - 1];
  }
  bool any(std::pair<int, int> rows) const {
    const int n = static_cast<int>(prefix.size()) - 1;
    const int lo = std::clamp(rows.first, 0, n), hi = std::clamp(rows.second + 1, 0, n);
    return lo < hi && prefix[static_cast<std::size_t>(hi)] > prefix[static_cast<std::size_t>(lo)];
  }
};

// Warps `src` into `dst` (the maps' size, src's type; fixed-point maps, map_b may be empty) in
// parallel runs of a few rows and calls after(rows, warped) on each run while it is in cache.
// Output rows whose samples (`source`, from sourceRows) read only empty rows of `src` are cleared
// instead of warped: what the warp would give them (zeros, the constant border).
template <class Fn>
void warpByRows(const cv::Mat& src, cv::Mat& dst, const cv::Mat& map_a, const cv::Mat& map_b, int interpolation,
                const std::vector<std::pair<int, int>>& source, Fn&& after) {
  const DrawnRows drawn(src);
  dst.create(map_a.rows, map_a.cols, src.type());
  constexpr int kBlock = 8;
  cv::parallel_for_(cv::Range(0, (dst.rows + kBlock - 1) / kBlock), [&](const cv::Range& blocks) {
    for (int b = blocks.start; b < blocks.end; ++b) {
      const int y1 = std::min(dst.rows, (b + 1) * kBlock);
      for (int y = b * kBlock; y < y1;) {
        const bool any = drawn.any(source[static_cast<std::size_t>(y)]);
        int end = y + 1;
        while (end < y1 && drawn.any(source[static_cast<std::size_t>(end)]) == any) ++end;
        cv::Mat out = dst.rowRange(y, end);
        if (any)
          cv::remap(src, out, map_a.rowRange(y, end), map_b.empty() ? cv::Mat() : map_b.rowRange(y, end), interpolation,
                    cv::BORDER_CONSTANT, cv::Scalar::all(0));
        else
          out.setTo(cv::Scalar::all(0));
        after(out, any);
        y = end;
      }
    }
  });
}

// Straight colour from premultiplied, per alpha a: entries a * 256 + c (alpha 0: none).
const std::vector<uchar>& unpremultiplyTable() {
  static const std::vector<uchar> table = [] {
    std::vector<uchar> t(256 * 256);
    for (int a = 1; a < 256; ++a)
      for (int c = 0; c < 256; ++c) t[a * 256 + c] = static_cast<uchar>(std::min(255, (c * 255 + a / 2) / a));
    return t;
  }();
  return table;
}

// Straight alpha: colour / alpha, through a table, for every pixel of `rows` (CV_8UC4).
void straighten(cv::Mat rows) {
  const std::vector<uchar>& unpremultiply = unpremultiplyTable();
  for (int y = 0; y < rows.rows; ++y) {
    uchar* px = rows.ptr<uchar>(y);
    for (int x = 0; x < rows.cols; ++x, px += 4) {
      const uchar* t = &unpremultiply[px[3] * 256];
      if (px[3] != 255 && px[3] != 0) px[0] = t[px[0]], px[1] = t[px[1]], px[2] = t[px[2]];
    }
  }
}

}  // namespace

TileMask::TileMask(int width, int height)
    : width_(width),
      height_(height),
      tiles_x_((width + kTile - 1) / kTile),
      on_(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>((height + kTile - 1) / kTile), 0) {}

cv::Rect TileMask::tile(int t) const {
  return cv::Rect((t % tiles_x_) * kTile, (t / tiles_x_) * kTile, kTile, kTile) & cv::Rect(0, 0, width_, height_);
}

void TileMask::mark(const cv::Rect& pixels) {
  const cv::Rect r = pixels & cv::Rect(0, 0, width_, height_);
  if (r.empty()) return;
  for (int ty = r.y / kTile; ty <= (r.y + r.height - 1) / kTile; ++ty)
    for (int tx = r.x / kTile; tx <= (r.x + r.width - 1) / kTile; ++tx) mark(ty * tiles_x_ + tx);
}

std::vector<cv::Rect> TileMask::runs() const {
  std::vector<cv::Rect> out;
  const int tiles_y = tiles_x_ > 0 ? tiles() / tiles_x_ : 0;
  for (int ty = 0; ty < tiles_y; ++ty)
    for (int tx = 0; tx < tiles_x_;) {
      if (!marked(ty * tiles_x_ + tx)) {
        ++tx;
        continue;
      }
      const int first = tx;
      while (tx < tiles_x_ && marked(ty * tiles_x_ + tx)) ++tx;
      out.push_back(tile(ty * tiles_x_ + first) | tile(ty * tiles_x_ + tx - 1));
    }
  return out;
}

std::vector<cv::Rect> ColourWarp::markTiles(std::span<const cv::Rect> drawn, TileMask& tiles) {
  if (tile_source_.empty()) {
    tile_source_.resize(static_cast<std::size_t>(tiles.tiles()));
    if (!projection_.warps()) {  // the pinhole image is the camera image
      for (int t = 0; t < tiles.tiles(); ++t) tile_source_[static_cast<std::size_t>(t)] = tiles.tile(t);
    } else {
      cv::convertMaps(projection_.mapX(), projection_.mapY(), map_a_, map_b_, CV_16SC2);  // remap's fast path (1/32 px)
      // Per tile, the pinhole pixels its bilinear samples may read: the extremes' floors widened
      // by a pixel each way (the fixed-point rounding and the neighbour). Samples more than a
      // pixel outside the pinhole image (e.g. the far-off marks of pixels the lens model cannot
      // invert) read only the constant border and are left out.
      const cv::Mat& mx = projection_.mapX();
      const cv::Mat& my = projection_.mapY();
      const float w = static_cast<float>(projection_.pinhole().width),
                  h = static_cast<float>(projection_.pinhole().height);
      for (int t = 0; t < tiles.tiles(); ++t) {
        const cv::Rect px = tiles.tile(t);
        float x0 = std::numeric_limits<float>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
        for (int y = px.y; y < px.y + px.height; ++y)
          for (int x = px.x; x < px.x + px.width; ++x) {
            const float u = mx.at<float>(y, x), v = my.at<float>(y, x);
            if (!(u > -2.0f && u < w + 1.0f && v > -2.0f && v < h + 1.0f)) continue;
            x0 = std::min(x0, u), x1 = std::max(x1, u), y0 = std::min(y0, v), y1 = std::max(y1, v);
          }
        if (x0 <= x1)
          tile_source_[static_cast<std::size_t>(t)] =
              cv::Rect(cv::Point(static_cast<int>(std::floor(x0)) - 1, static_cast<int>(std::floor(y0)) - 1),
                       cv::Point(static_cast<int>(std::floor(x1)) + 3, static_cast<int>(std::floor(y1)) + 3));
      }
    }
  }
  // Every tile whose samples may read a drawn pixel: the drawn rectangles marked on a grid of
  // kTile-pixel pinhole cells, asked of each tile's source rectangle through the grid's sums.
  const int pw = projection_.pinhole().width, ph = projection_.pinhole().height;
  const int gx = (pw + TileMask::kTile - 1) / TileMask::kTile, gy = (ph + TileMask::kTile - 1) / TileMask::kTile;
  const cv::Rect pinhole(0, 0, pw, ph);
  std::vector<int>& sums = grid_sums_;  // (gy + 1) x (gx + 1): cells marked above and left of each corner
  sums.assign(static_cast<std::size_t>(gx + 1) * static_cast<std::size_t>(gy + 1), 0);
  const auto at = [&](int x, int y) -> int& {
    return sums[static_cast<std::size_t>(y) * static_cast<std::size_t>(gx + 1) + static_cast<std::size_t>(x)];
  };
  bool any = false;
  for (const cv::Rect& d : drawn) {
    const cv::Rect r = d & pinhole;
    if (r.empty()) continue;
    any = true;
    for (int y = r.y / TileMask::kTile; y <= (r.y + r.height - 1) / TileMask::kTile; ++y)
      for (int x = r.x / TileMask::kTile; x <= (r.x + r.width - 1) / TileMask::kTile; ++x) at(x + 1, y + 1) = 1;
  }
  if (!any) return tiles.runs();
  for (int y = 1; y <= gy; ++y)
    for (int x = 1; x <= gx; ++x) at(x, y) += at(x - 1, y) + at(x, y - 1) - at(x - 1, y - 1);
  for (int t = 0; t < tiles.tiles(); ++t) {
    const cv::Rect source = tile_source_[static_cast<std::size_t>(t)] & pinhole;
    if (source.empty()) continue;
    const int x0 = source.x / TileMask::kTile, x1 = (source.x + source.width - 1) / TileMask::kTile + 1;
    const int y0 = source.y / TileMask::kTile, y1 = (source.y + source.height - 1) / TileMask::kTile + 1;
    if (at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0) > 0) tiles.mark(t);
  }
  return tiles.runs();
}

cv::Mat ColourWarp::apply(const cv::Mat& premultiplied, std::span<const cv::Rect> drawn, TileMask& tiles) {
  const Camera& camera = projection_.camera();
  cv::Mat out = cv::Mat::zeros(camera.height, camera.width, CV_8UC4);
  const std::vector<cv::Rect> runs = markTiles(drawn, tiles);
  // Warped (or copied) and straightened run by run, in parallel, each run while it is in cache.
  cv::parallel_for_(cv::Range(0, static_cast<int>(runs.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const cv::Rect& run = runs[static_cast<std::size_t>(i)];
      cv::Mat part = out(run);
      if (projection_.warps())
        cv::remap(premultiplied, part, map_a_(run), map_b_(run), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                  cv::Scalar::all(0));
      else
        premultiplied(run).copyTo(part);
      straighten(part);
    }
  });
  return out;
}

void ColourWarp::blendOnto(cv::Mat& bgr, const cv::Mat& premultiplied, std::span<const cv::Rect> drawn, TileMask& tiles,
                           const cv::Rect& keep_out) {
  const std::vector<cv::Rect> runs = markTiles(drawn, tiles);
  const std::vector<uchar>& unpremultiply = unpremultiplyTable();
  // Per run, in parallel: warped into a scratch run (the pinhole pixels themselves without a
  // warp), then each pixel made straight and blended as straighten() and compositeOver() would.
  cv::parallel_for_(cv::Range(0, static_cast<int>(runs.size())), [&](const cv::Range& range) {
    cv::Mat scratch;
    for (int i = range.start; i < range.end; ++i) {
      const cv::Rect& run = runs[static_cast<std::size_t>(i)];
      cv::Mat part;
      if (projection_.warps()) {
        scratch.create(run.height, run.width, CV_8UC4);
        cv::remap(premultiplied, scratch, map_a_(run), map_b_(run), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                  cv::Scalar::all(0));
        part = scratch;
      } else {
        part = premultiplied(run);
      }
      for (int y = 0; y < run.height; ++y) {
        const uchar* px = part.ptr<uchar>(y);
        uchar* o = bgr.ptr<uchar>(run.y + y, run.x);
        const bool row_kept = run.y + y >= keep_out.y && run.y + y < keep_out.y + keep_out.height;
        for (int x = 0; x < run.width; ++x, px += 4, o += 3) {
          const unsigned a = px[3];
          if (a == 0) continue;
          if (row_kept && run.x + x >= keep_out.x && run.x + x < keep_out.x + keep_out.width) continue;
          if (a == 255) {
            o[0] = px[0], o[1] = px[1], o[2] = px[2];
            continue;
          }
          const uchar* t = &unpremultiply[a * 256];
          for (int c = 0; c < 3; ++c) o[c] = static_cast<uchar>((t[px[c]] * a + o[c] * (255 - a) + 127) / 255);
        }
      }
    }
  });
}

cv::Mat LabelWarp::apply(const cv::Mat& pinhole_labels, std::array<int, 256>& counts) {
  if (projection_.warps() && map_.empty()) {  // nearest pinhole pixel per output pixel, as integers
    cv::Mat unused;
    cv::convertMaps(projection_.mapX(), projection_.mapY(), map_, unused, CV_16SC2, true);
    source_rows_ = sourceRows(projection_.mapY(), projection_.pinhole().height);
  }
  // The labels at the nearest pinhole pixel of each output pixel (0 outside the pinhole image)
  // and the pixels per label, in runs of rows (rows reading only unlabelled pinhole rows are
  // cleared and counted as background).
  counts.fill(0);
  std::mutex counts_mutex;
  auto count = [&](const cv::Mat& rows) {
    std::array<std::array<int, 256>, 4> local{};  // four histograms: fewer store-to-load stalls
    for (int v = 0; v < rows.rows; ++v) {
      const uchar* row = rows.ptr<uchar>(v);
      for (int u = 0; u < rows.cols; ++u) ++local[static_cast<std::size_t>(u & 3)][row[u]];
    }
    const std::lock_guard lock(counts_mutex);
    for (const auto& h : local)
      for (std::size_t k = 0; k < h.size(); ++k) counts[k] += h[k];
  };
  cv::Mat out;
  if (projection_.warps()) {
    warpByRows(pinhole_labels, out, map_, cv::Mat(), cv::INTER_NEAREST, source_rows_,
               [&](const cv::Mat& rows, bool warped) {
                 if (warped) {
                   count(rows);
                 } else {  // cleared: background
                   const std::lock_guard lock(counts_mutex);
                   counts[0] += rows.rows * rows.cols;
                 }
               });
  } else {
    out = pinhole_labels;
    cv::parallel_for_(cv::Range(0, out.rows), [&](const cv::Range& r) { count(out.rowRange(r.start, r.end)); });
  }
  return out;
}

}  // namespace kccd::render::detail
