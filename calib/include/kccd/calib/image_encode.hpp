// Encoding pictures to PNG and JPEG in memory, with libpng and libjpeg-turbo directly: the
// suite's frames, masks, golden images and robot-log images. (OpenCV's image codecs are not
// linked: they load GDAL's tree of libraries, ~0.1 s, into every process that links them.)
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace kccd::calib {

/// A picture that cannot be encoded: the library's words.
class ImageEncodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `image` (8-bit grey, BGR or BGRA, or 16-bit grey or BGR) as a PNG file's bytes. Level 1 (the
/// default) is OpenCV's default PNG: zlib level 1, run-length strategy, the sub filter; any other
/// `compression` (0 none .. 9 smallest) is that zlib level with the default strategy and libpng's
/// adaptive filters, as OpenCV with IMWRITE_PNG_COMPRESSION. The pixels decode back exactly.
/// Throws ImageEncodeError.
std::vector<std::uint8_t> encodePng(const cv::Mat& image, int compression = 1);

/// `image` (8-bit grey or BGR) as a baseline JFIF file's bytes at `quality` (1..100; 4:2:0 chroma
/// for colour, as libjpeg's defaults). Throws ImageEncodeError.
std::vector<std::uint8_t> encodeJpeg(const cv::Mat& image, int quality = 95);

}  // namespace kccd::calib
