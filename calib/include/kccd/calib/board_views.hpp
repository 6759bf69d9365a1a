// The views of a calibration board in image files: each image read as grey, all of one size, the
// board's tags detected and their corners paired with the board's points. What an intrinsics solve
// (calibrateIntrinsics) takes.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/intrinsics.hpp"

namespace kccd::calib {

/// The board as a set of images shows it.
struct BoardViews {
  std::vector<IntrinsicsView> views;          ///< per image, in order: its path and its board corners
  std::vector<int> tags;                      ///< per image: board tags seen
  std::vector<std::vector<int>> unknown_ids;  ///< per image: detected ids not on the board, ascending
  cv::Size image_size;                        ///< the images' common size
};

/// Reads every image (readImageFile, grey), detects its tags and pairs the board's ones with their
/// points (Board::correspondences); `progress` is told the fraction done after each image. Throws
/// ImageError (also for an image whose size differs from the first one's) or TagDetectionError.
BoardViews detectBoardViews(const std::vector<std::string>& images, const Board& board,
                            const std::function<void(double)>& progress = {});

}  // namespace kccd::calib
