// Frame-times files: each video frame's time, for recordings whose frames are not evenly spaced.
// CSV with the header `frame,time`, one row per frame from frame 0 in order, times in seconds,
// strictly increasing.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "kccd/input_error.hpp"

namespace kccd::overlay {

/// A frame-times file that cannot be used: one line, "file:line:col: problem" for a row and
/// "file: problem" for the file itself.
class FrameTimesError : public InputError {
 public:
  using InputError::InputError;
};

/// Largest frame-times file loadFrameTimes() reads.
inline constexpr std::size_t kMaxFrameTimesBytes = std::size_t{1} << 30;
/// Largest frame number a file may list (the table is sized by the rows, never by a number).
inline constexpr long kMaxFrameNumber = 100000000;

/// Each frame's time, indexed by frame number. Throws FrameTimesError naming the file (`name` in
/// parseFrameTimes) and the line for any mistake: header, missing or repeated rows (a row per
/// frame from 0, in order), non-numbers, non-finite or |time| > 1e300, times not increasing.
std::vector<double> loadFrameTimes(const std::string& path);
std::vector<double> parseFrameTimes(std::string_view text, const std::string& name);

}  // namespace kccd::overlay
