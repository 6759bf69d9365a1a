// A 2-D <-> 3-D correspondence: what calibration solves a camera pose from. Tag corners, labelled
// world points and body points placed by the model all become these.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace kccd::calib {

/// One observed point: where it is in the world and where it was seen in the image.
struct Correspondence {
  std::string name;   ///< unique, non-empty; used to report rejected points
  cv::Point2d pixel;  ///< OpenCV convention: pixel centres at integer coordinates
  cv::Point3d world;  ///< metres
};

}  // namespace kccd::calib
