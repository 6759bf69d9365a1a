// JPEG decoding with libjpeg-turbo under the suite's own error handling: libjpeg's warnings and
// errors come back as text (OpenCV's use of libjpeg prints them on stderr, and decodes a cut file
// to a grey-filled picture without a word). The pixels are those OpenCV's imdecode gives.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "kccd/calib/image_file.hpp"

namespace kccd::calib::detail {

/// True when `bytes` start like a JPEG (the SOI marker and the next marker's 0xFF).
bool looksLikeJpeg(std::span<const std::uint8_t> bytes);

/// Decodes a JPEG as cv::imdecode does: BGR, grey, or as stored (grey or BGR), turned as its
/// Exif orientation says except as stored (as OpenCV does). `check_size` is called with the size
/// before any pixel is decoded; it and `fail` throw. A file cut short or whose entropy-coded data
/// is corrupt (pixels lost) fails with libjpeg's words. A CMYK JPEG gives an empty matrix (left
/// to OpenCV).
cv::Mat decodeJpeg(std::span<const std::uint8_t> bytes, ImageColour colour,
                   const std::function<void(int width, int height)>& check_size,
                   const std::function<void(const std::string&)>& fail);

}  // namespace kccd::calib::detail
