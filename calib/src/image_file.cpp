#include "kccd/calib/image_file.hpp"

#include <png.h>

#include <cstring>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/file_reader.hpp"

namespace kccd::calib {

namespace {

// A PNG that libpng cannot decode: its message (empty when it decodes). libpng's simplified API
// keeps its messages to itself, where OpenCV's use of libpng prints them on stderr: a damaged PNG
// is caught here first so that the user sees one line, and sees what is wrong with it.
std::string pngProblem(std::span<const std::uint8_t> bytes) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return image.message;
  if (image.width > static_cast<png_uint_32>(kMaxImageSide) || image.height > static_cast<png_uint_32>(kMaxImageSide) ||
      static_cast<long>(image.width) * image.height > kMaxImagePixels) {
    png_image_free(&image);
    return "";  // too large: decodeImage says so
  }
  image.format = PNG_FORMAT_GRAY;  // the smallest buffer: only the decoding is checked
  std::unique_ptr<std::uint8_t[]> scratch(new std::uint8_t[PNG_IMAGE_SIZE(image)]);
  if (!png_image_finish_read(&image, nullptr, scratch.get(), 0, nullptr)) return image.message;
  return "";
}

}  // namespace

cv::Mat decodeImage(std::span<const std::uint8_t> bytes, const std::string& source, ImageColour colour) {
  const auto fail = [&](const std::string& problem) {
    throw ImageError(InputLocation{source, 0, 0, "image"}, problem);
  };
  if (bytes.empty()) fail("empty file");
  static constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPngSignature, 8) == 0) {
    const std::string problem = pngProblem(bytes);
    if (!problem.empty()) fail("a damaged PNG (" + printable(problem) + ")");
  }
  cv::Mat img;
  try {
    const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<std::uint8_t*>(bytes.data()));
    img = cv::imdecode(encoded, colour == ImageColour::Grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    img.release();
  } catch (const std::bad_alloc&) {
    img.release();
  }
  if (img.empty()) fail("not an image OpenCV can decode (PNG, JPEG, TIFF, BMP, ...)");
  if (img.cols > kMaxImageSide || img.rows > kMaxImageSide || static_cast<long>(img.cols) * img.rows > kMaxImagePixels)
    fail(std::to_string(img.cols) + "x" + std::to_string(img.rows) + " is larger than a camera file allows (" +
         std::to_string(kMaxImageSide) + " a side, " + std::to_string(kMaxImagePixels) + " pixels)");
  return img;
}

cv::Mat readImageFile(const std::string& path, ImageColour colour) {
  std::string bytes;
  try {
    bytes = readRegularFile(path, kMaxImageFileBytes, "image");
  } catch (const FileError& e) {  // said as "path: image: problem"
    const InputLocation where{path, 0, 0, "image"};
    switch (e.kind()) {
      case FileProblem::Missing:
        throw ImageError(where, "no such file");
      case FileProblem::Directory:
      case FileProblem::NotRegular:
        throw ImageError(where, "not a regular file");
      default:
        throw ImageError(where, e.problem());
    }
  }
  return decodeImage({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, path, colour);
}

}  // namespace kccd::calib
