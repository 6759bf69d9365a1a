// Reading an image file: camera frames (PNG, JPEG, TIFF, BMP, ...) for the calibration commands
// and image-sequence recordings, golden images. PNGs are decoded with libpng's simplified API
// (whose messages never reach stderr), the other formats by OpenCV.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"

namespace kccd::calib {

/// An image file that cannot be used: one line "path: image: problem".
class ImageError : public InputError {
 public:
  using InputError::InputError;
};

inline constexpr std::size_t kMaxImageFileBytes = std::size_t{256} << 20;  ///< encoded size

/// The pixels an image decodes to: 8-bit BGR, 8-bit grey, or as stored (8 or 16 bits; grey, BGR
/// or BGRA, as OpenCV's IMREAD_UNCHANGED gives them).
enum class ImageColour : std::uint8_t { Bgr, Grey, Unchanged };

/// Decodes an encoded image held in memory; `source` names it in messages. The image must decode
/// and fit a camera (Camera::validate's bounds: kMaxImageSide a side, kMaxImagePixels). Throws
/// ImageError, never anything else for any bytes.
cv::Mat decodeImage(std::span<const std::uint8_t> bytes, const std::string& source, ImageColour colour);

/// The lock decodeImage holds while one of OpenCV's decoders (formats other than PNG and JPEG) may
/// write to std::cerr, whose buffer it swaps for that time to keep the text for its message: a
/// thread that writes to std::cerr while images may be decoded on others takes it too.
std::mutex& stderrLock();

/// Reads a regular file of at most kMaxImageFileBytes (a FIFO or device is refused without
/// blocking) and decodes it with decodeImage. Throws ImageError.
cv::Mat readImageFile(const std::string& path, ImageColour colour);

}  // namespace kccd::calib
