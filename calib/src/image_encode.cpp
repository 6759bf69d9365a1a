#include "kccd/calib/image_encode.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <string>

#include <jpeglib.h>
#include <png.h>
#include <zlib.h>

namespace kccd::calib {

namespace {

// ---- PNG: libpng's write API into a vector; its errors come back by longjmp, with their text.

struct PngSink {
  std::vector<std::uint8_t>* out;
  char message[200];
};

void pngWrite(png_structp png, png_bytep data, png_size_t size) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  sink->out->insert(sink->out->end(), data, data + size);
}
void pngFlush(png_structp) {}
void pngError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", message);
  png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

// The rows are written from `image`, which outlives the call; nothing with a destructor lives in
// this frame after setjmp. Returns false with sink->message set on an error.
bool writePng(const cv::Mat& image, int compression, PngSink* sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, pngError, pngWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, sink, pngWrite, pngFlush);
  const int channels = image.channels();
  const int depth = image.depth() == CV_16U ? 16 : 8;
  const int type = channels == 1 ? PNG_COLOR_TYPE_GRAY : channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA;
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows), depth, type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (compression == 1) {
    // Fast: the sub filter and run-length strategy (OpenCV's default for PNG).
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_strategy(png, Z_RLE);
  } else {
    png_set_compression_strategy(png, Z_DEFAULT_STRATEGY);  // libpng's own default would be Z_FILTERED
  }
  png_set_compression_level(png, compression);
  png_write_info(png, info);
  if (channels >= 3) png_set_bgr(png);
  if (depth == 16) png_set_swap(png);  // the machine's little-endian samples, PNG's big-endian
  for (int y = 0; y < image.rows; ++y) png_write_row(png, image.ptr<png_byte>(y));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// ---- JPEG: libjpeg's compressor into its own memory buffer; errors by longjmp.

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpegExit(j_common_ptr info) {
  auto* err = reinterpret_cast<JpegError*>(info->err);
  info->err->format_message(info, err->message);
  std::longjmp(err->jump, 1);
}
void jpegOutput(j_common_ptr) {}

bool writeJpeg(const cv::Mat& image, int quality, unsigned char** buffer, unsigned long* size, JpegError* err) {
  jpeg_compress_struct c;
  c.err = jpeg_std_error(&err->manager);
  err->manager.error_exit = jpegExit;
  err->manager.output_message = jpegOutput;
  if (setjmp(err->jump)) {
    jpeg_destroy_compress(&c);
    return false;
  }
  jpeg_create_compress(&c);
  jpeg_mem_dest(&c, buffer, size);
  c.image_width = static_cast<JDIMENSION>(image.cols);
  c.image_height = static_cast<JDIMENSION>(image.rows);
  c.input_components = image.channels();
  c.in_color_space = image.channels() == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, quality, TRUE);
  jpeg_start_compress(&c, TRUE);
  while (c.next_scanline < c.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(image.ptr<JSAMPLE>(static_cast<int>(c.next_scanline)));
    jpeg_write_scanlines(&c, &row, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  return true;
}

}  // namespace

std::vector<std::uint8_t> encodePng(const cv::Mat& image, int compression) {
  const int channels = image.channels();
  const bool depth_ok = image.depth() == CV_8U || (image.depth() == CV_16U && channels != 4);
  if (image.empty() || !depth_ok || (channels != 1 && channels != 3 && channels != 4) || image.dims != 2)
    throw ImageEncodeError("PNG: not an 8-bit grey, BGR or BGRA picture, or a 16-bit grey or BGR one");
  if (compression < 0 || compression > 9) throw ImageEncodeError("PNG: a compression level not in 0..9");
  std::vector<std::uint8_t> out;
  out.reserve(image.total() * image.elemSize() / 4 + 1024);
  PngSink sink{&out, {}};
  if (!writePng(image, compression, &sink)) throw ImageEncodeError(std::string("PNG: ") + sink.message);
  return out;
}

std::vector<std::uint8_t> encodeJpeg(const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3) || image.dims != 2)
    throw ImageEncodeError("JPEG: not an 8-bit grey or BGR picture");
  if (quality < 1 || quality > 100) throw ImageEncodeError("JPEG: a quality not in 1..100");
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  JpegError err{};
  const bool ok = writeJpeg(image, quality, &buffer, &size, &err);
  std::vector<std::uint8_t> out;
  if (ok) out.assign(buffer, buffer + size);
  std::free(buffer);
  if (!ok) throw ImageEncodeError(std::string("JPEG: ") + err.message);
  return out;
}

}  // namespace kccd::calib
