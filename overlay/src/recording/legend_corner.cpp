#include "kccd/overlay/recording/legend_corner.hpp"

#include <algorithm>
#include <cstddef>
#include <stdexcept>

namespace kccd::overlay {

LegendCorner::LegendCorner(int area, int hold) : slack_(std::max(1, area / 50)), hold_(std::max(1, hold)) {}

int LegendCorner::next(std::span<const int> cover) {
  if (cover.empty()) throw std::invalid_argument("LegendCorner::next: no box");
  const int best = static_cast<int>(std::min_element(cover.begin(), cover.end()) - cover.begin());
  if (current_ < 0 || static_cast<std::size_t>(current_) >= cover.size()) {
    current_ = best;
    better_for_ = 0;
    return current_;
  }
  better_for_ =
      cover[static_cast<std::size_t>(best)] + slack_ < cover[static_cast<std::size_t>(current_)] ? better_for_ + 1 : 0;
  if (better_for_ >= hold_) {
    current_ = best;
    better_for_ = 0;
  }
  return current_;
}

}  // namespace kccd::overlay
