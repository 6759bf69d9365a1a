#include "kccd/calib/image_file.hpp"

#include <png.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <type_traits>

#include <dlfcn.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "jpeg_decode.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/file_reader.hpp"

namespace kccd::calib {

namespace {

// OpenCV's imdecode, for the formats other than PNG and JPEG, from its library loaded the first
// time one is met: linked, that library loads GDAL's tree of libraries (~0.1 s) into every
// process of the suite, for pictures it rarely meets. Null (with `why` set) when it cannot be
// loaded. The declaration in the header is the one this pointer's type must match.
using Imdecode = cv::Mat (*)(cv::InputArray, int);
static_assert(std::is_same_v<decltype(static_cast<Imdecode>(&cv::imdecode)), Imdecode>, "cv::imdecode's signature");

Imdecode otherFormats(std::string& why) {
  static std::string problem;
  static const Imdecode decode = []() -> Imdecode {
    void* library = dlopen(KCCD_OPENCV_IMGCODECS_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      problem = "formats other than PNG and JPEG need " KCCD_OPENCV_IMGCODECS_SONAME ", which cannot be loaded";
      return nullptr;
    }
    // cv::imdecode(cv::InputArray, int), by its (Itanium C++ ABI) name.
    void* symbol = dlsym(library, "_ZN2cv8imdecodeERKNS_11_InputArrayEi");
    if (symbol == nullptr) {
      problem = KCCD_OPENCV_IMGCODECS_SONAME " has no cv::imdecode";
      return nullptr;
    }
    return reinterpret_cast<Imdecode>(symbol);
  }();
  why = problem;
  return decode;
}

// A picture no camera file can describe (kMaxImageSide a side, kMaxImagePixels in all): the
// problem in words, else empty.
std::string tooLarge(long width, long height) {
  if (width <= kMaxImageSide && height <= kMaxImageSide && width * height <= kMaxImagePixels) return {};
  return std::to_string(width) + "x" + std::to_string(height) + " is larger than a camera file allows (" +
         std::to_string(kMaxImageSide) + " a side, " + std::to_string(kMaxImagePixels) + " pixels)";
}

// PNG files are decoded here with libpng's simplified API, never by OpenCV: OpenCV's use of libpng
// prints libpng's own messages ("libpng error: ...", "libpng warning: ...") on stderr, where a
// damaged file must give one line that says what is wrong with it. The simplified API keeps its
// messages to itself. The pixels are OpenCV's: 16-bit samples keep their high byte in 8-bit
// output, alpha is dropped (not composited) in BGR and grey output, grey with alpha reads as
// BGRA when unchanged.
cv::Mat decodePng(std::span<const std::uint8_t> bytes, ImageColour colour,
                  const std::function<void(const std::string&)>& fail) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size()))
    fail("a damaged PNG (" + printable(image.message) + ")");
  struct Release {
    png_image* image;
    ~Release() { png_image_free(image); }
  } release{&image};
  if (const std::string problem = tooLarge(static_cast<long>(image.width), static_cast<long>(image.height));
      !problem.empty())
    fail(problem);
  const bool sixteen = (image.format & PNG_FORMAT_FLAG_LINEAR) != 0;  // 16-bit samples, read as stored
  const bool alpha = (image.format & PNG_FORMAT_FLAG_ALPHA) != 0;
  const bool col = (image.format & PNG_FORMAT_FLAG_COLOR) != 0;  // a palette expands to its colours
  image.format = (col ? PNG_FORMAT_FLAG_COLOR | PNG_FORMAT_FLAG_BGR : 0u) | (alpha ? PNG_FORMAT_FLAG_ALPHA : 0u) |
                 (sixteen ? PNG_FORMAT_FLAG_LINEAR : 0u);
  const int channels = static_cast<int>(PNG_IMAGE_SAMPLE_CHANNELS(image.format));
  cv::Mat stored(static_cast<int>(image.height), static_cast<int>(image.width),
                 CV_MAKETYPE(sixteen ? CV_16U : CV_8U, channels));
  if (!png_image_finish_read(&image, nullptr, stored.data, static_cast<png_int_32>(stored.step[0] / stored.elemSize1()),
                             nullptr))
    fail("a damaged PNG (" + printable(image.message) + ")");
  if (sixteen && alpha) {  // the simplified API gives 16-bit colour premultiplied by alpha: undone
    const int colours = channels - 1;
    for (int r = 0; r < stored.rows; ++r) {
      auto* px = stored.ptr<std::uint16_t>(r);
      for (int c = 0; c < stored.cols; ++c, px += channels) {
        const std::uint32_t a = px[colours];
        for (int k = 0; k < colours; ++k)
          px[k] =
              a == 0 ? 0 : static_cast<std::uint16_t>(std::min<std::uint32_t>(65535u, (px[k] * 65535u + a / 2) / a));
      }
    }
  }
  if (channels == 2) cv::cvtColor(stored, stored, cv::COLOR_GRAY2BGRA);  // grey + alpha: as OpenCV reads it
  if (colour == ImageColour::Unchanged) return stored;
  cv::Mat eight = stored;
  if (sixteen) {  // the high byte, as OpenCV's 8-bit reading keeps it
    eight.create(stored.size(), CV_MAKETYPE(CV_8U, stored.channels()));
    for (int r = 0; r < stored.rows; ++r) {
      const auto* in = stored.ptr<std::uint16_t>(r);
      auto* out = eight.ptr<std::uint8_t>(r);
      for (std::size_t k = 0; k < static_cast<std::size_t>(stored.cols) * stored.channels(); ++k)
        out[k] = static_cast<std::uint8_t>(in[k] >> 8);
    }
  }
  const int n = eight.channels();
  if (colour == ImageColour::Grey) {
    if (n == 1) return eight;
    cv::Mat grey;
    cv::cvtColor(eight, grey, n == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    return grey;
  }
  if (n == 3) return eight;
  cv::Mat bgr;
  cv::cvtColor(eight, bgr, n == 4 ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
  return bgr;
}

}  // namespace

std::mutex& stderrLock() {
  static std::mutex lock;
  return lock;
}

cv::Mat decodeImage(std::span<const std::uint8_t> bytes, const std::string& source, ImageColour colour) {
  const auto fail = [&](const std::string& problem) {
    throw ImageError(InputLocation{source, 0, 0, "image"}, problem);
  };
  if (bytes.empty()) fail("empty file");
  static constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPngSignature, 8) == 0) {
    try {
      return decodePng(bytes, colour, fail);
    } catch (const std::bad_alloc&) {
      fail("a PNG too large to decode in the memory available");
    }
  }
  const auto checkSize = [&](int width, int height) {
    if (const std::string problem = tooLarge(width, height); !problem.empty()) fail(problem);
  };
  if (detail::looksLikeJpeg(bytes)) {
    cv::Mat jpeg;
    try {
      jpeg = detail::decodeJpeg(bytes, colour, checkSize, fail);
    } catch (const std::bad_alloc&) {
      fail("a JPEG too large to decode in the memory available");
    }
    if (!jpeg.empty()) return jpeg;
  }
  // Other formats (BMP, TIFF, WebP, PNM, ...) through OpenCV, whose imdecode prints a decoder's
  // exception on std::cerr: that text is caught (under a lock: the stream is the process's) and
  // becomes part of the one-line error.
  cv::Mat img;
  std::string said;
  {
    const std::lock_guard<std::mutex> lock(stderrLock());
    std::ostringstream caught;
    struct Swap {  // std::cerr's buffer swapped, and restored however the decode ends
      std::streambuf* was;
      explicit Swap(std::streambuf* to) : was(std::cerr.rdbuf(to)) {}
      ~Swap() { std::cerr.rdbuf(was); }
      Swap(const Swap&) = delete;
      Swap& operator=(const Swap&) = delete;
    };
    {
      const Swap swap(caught.rdbuf());
      try {
        const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<std::uint8_t*>(bytes.data()));
        std::string unavailable;
        const Imdecode imdecode = otherFormats(unavailable);
        if (imdecode == nullptr) fail(unavailable);
        img = imdecode(encoded, colour == ImageColour::Grey  ? cv::IMREAD_GRAYSCALE
                                : colour == ImageColour::Bgr ? cv::IMREAD_COLOR
                                                             : cv::IMREAD_UNCHANGED);
      } catch (const cv::Exception&) {
        img.release();
      } catch (const std::bad_alloc&) {
        img.release();
      }
    }
    said = caught.str();
  }
  if (img.empty()) {
    // OpenCV's words after its "imdecode_(''): can't read data: " prefix, first line only.
    std::string why = said.substr(0, said.find('\n'));
    if (const std::size_t colon = why.find("): "); colon != std::string::npos) why = why.substr(colon + 3);
    // "error: (-2:Unspecified error) Unexpected end of input stream in function 'readBlock'": the words only.
    if (const std::size_t err = why.find("error: ("); err != std::string::npos)
      if (const std::size_t close = why.find(") ", err); close != std::string::npos) why = why.substr(close + 2);
    if (const std::size_t in = why.rfind(" in function "); in != std::string::npos) why = why.substr(0, in);
    fail(why.empty() ? "not an image OpenCV can decode (PNG, JPEG, TIFF, BMP, ...)"
                     : "a damaged image (" + printable(why, 120) + ")");
  }
  if (const std::string problem = tooLarge(img.cols, img.rows); !problem.empty()) fail(problem);
  return img;
}

cv::Mat readImageFile(const std::string& path, ImageColour colour) {
  std::string bytes;
  try {
    bytes = readRegularFile(path, kMaxImageFileBytes, "image");
  } catch (const FileError& e) {  // said as "path: image: problem", as every image error is
    throw ImageError(InputLocation{e.location().source, 0, 0, "image"}, e.problem());
  }
  return decodeImage({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, path, colour);
}

}  // namespace kccd::calib
