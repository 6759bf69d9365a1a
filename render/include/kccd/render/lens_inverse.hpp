// The inverse of a camera's lens model at every pixel of its image, kept between runs.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"

namespace kccd::render {

/// Every pixel centre of a camera's image through the inverse of its distortion model.
struct LensInverse {
  cv::Mat normal;                    ///< width x height rows of normalised coordinates, CV_64FC2 (row-major pixels)
  std::vector<unsigned char> valid;  ///< per pixel: calib::undistortPixels solved it
  bool from_cache = false;           ///< read from the cache file rather than computed
};

/// The folder of the lens cache: $KCCD_CACHE_DIR, else $XDG_CACHE_HOME/kccd, else
/// $HOME/.cache/kccd; empty (no cache) when KCCD_CACHE_DIR is "off" or no folder can be named.
std::string lensCacheFolder();

/// calib::undistortPixels over the whole image of `camera`, in parallel blocks of rows. The result
/// depends only on the image size, camera matrix and distortion, so it is kept in the lens cache
/// (one file per lens, written to a temporary name and renamed; at most 8 files, the oldest
/// removed; images up to 2.1 megapixels) and a later run with the same lens reads the same values,
/// bit for bit, instead of computing them (0.2 s of CPU at 1280x720). A missing, unreadable or
/// mismatched cache file is computed again; the cache never changes a result.
LensInverse lensInverse(const calib::Camera& camera);

}  // namespace kccd::render
