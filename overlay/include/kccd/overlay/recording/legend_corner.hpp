// Which corner of the picture the legend takes, frame after frame: where it hides the fewest pixels
// of the drawn volumes, without jumping about.
#pragma once

#include <span>

namespace kccd::overlay {

/// Chooses among candidate boxes (the legend's corners) from the volume pixels each would hide.
class LegendCorner {
 public:
  /// Boxes of `area` pixels each. The first frame takes the least covered box (the first of
  /// equals); the legend then moves only when another box has hidden fewer pixels, by more than
  /// 2 % of the area, for `hold` frames in a row, and goes to the least covered box of that frame.
  explicit LegendCorner(int area, int hold = 8);
  /// The box for the next frame, given the volume pixels under each box on it.
  int next(std::span<const int> cover);

 private:
  int slack_, hold_, current_ = -1, better_for_ = 0;
};

}  // namespace kccd::overlay
