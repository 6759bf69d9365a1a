#include "jpeg_decode.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

// jpeglib.h needs size_t and FILE declared first.
#include <jerror.h>
#include <jpeglib.h>

namespace kccd::calib::detail {
namespace {

// libjpeg's error manager with its messages kept: an error jumps back to the decoder, a warning
// about lost data is remembered, nothing is printed.
struct ErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  std::string error;
  std::string damage;  // the first warning that says pixels were lost
};

void onError(j_common_ptr info) {
  auto* self = reinterpret_cast<ErrorManager*>(info->err);
  char text[JMSG_LENGTH_MAX] = {};
  (*info->err->format_message)(info, text);
  self->error = text;
  std::longjmp(self->jump, 1);
}

void onMessage(j_common_ptr info, int level) {
  if (level >= 0) return;  // trace messages
  auto* self = reinterpret_cast<ErrorManager*>(info->err);
  const int code = info->err->msg_code;
  // A cut file, a marker inside the entropy-coded data, a bad code: pixels were filled in.
  if (self->damage.empty() && (code == JWRN_JPEG_EOF || code == JWRN_HIT_MARKER || code == JWRN_HUFF_BAD_CODE)) {
    char text[JMSG_LENGTH_MAX] = {};
    (*info->err->format_message)(info, text);
    self->damage = text;
  }
  ++info->err->num_warnings;
}

void onOutput(j_common_ptr) {}

// A progressive JPEG may hold any number of scans, each a pass over the whole image: thousands
// of tiny scans make a small file decode for minutes. Real encoders write about ten.
constexpr int kMaxScans = 256;

void onProgress(j_common_ptr info) {
  if (!info->is_decompressor) return;
  const auto* d = reinterpret_cast<j_decompress_ptr>(info);
  if (d->input_scan_number > kMaxScans) {
    auto* self = reinterpret_cast<ErrorManager*>(info->err);
    self->error = "more than " + std::to_string(kMaxScans) + " progressive scans";
    std::longjmp(self->jump, 1);
  }
}

// The Exif orientation (1..8) of an APP1 marker's data, 1 when it has none.
int exifOrientation(const jpeg_saved_marker_ptr markers) {
  for (jpeg_saved_marker_ptr m = markers; m; m = m->next) {
    if (m->marker != JPEG_APP0 + 1 || m->data_length < 14 || std::memcmp(m->data, "Exif\0\0", 6) != 0) continue;
    const std::uint8_t* tiff = m->data + 6;
    const std::size_t size = m->data_length - 6;
    const bool little = tiff[0] == 'I' && tiff[1] == 'I';
    if (!little && !(tiff[0] == 'M' && tiff[1] == 'M')) continue;
    const auto u16 = [&](std::size_t at) -> unsigned {
      return little ? tiff[at] | (tiff[at + 1] << 8) : (tiff[at] << 8) | tiff[at + 1];
    };
    const auto u32 = [&](std::size_t at) -> std::size_t {
      return little ? std::size_t{u16(at)} | (std::size_t{u16(at + 2)} << 16)
                    : (std::size_t{u16(at)} << 16) | u16(at + 2);
    };
    const std::size_t ifd = u32(4);
    if (ifd + 2 > size) continue;
    const unsigned entries = u16(ifd);
    for (unsigned i = 0; i < entries; ++i) {
      const std::size_t e = ifd + 2 + 12 * std::size_t{i};
      if (e + 12 > size) break;
      if (u16(e) == 0x0112 && u16(e + 2) == 3) {  // Orientation, SHORT
        const unsigned v = u16(e + 8);
        return v >= 1 && v <= 8 ? static_cast<int>(v) : 1;
      }
    }
  }
  return 1;
}

// Turns `img` as Exif orientation `o` says, as OpenCV's imdecode does.
void orientImage(cv::Mat& img, int o) {
  switch (o) {
    case 2:
      cv::flip(img, img, 1);
      break;
    case 3:
      cv::flip(img, img, -1);
      break;
    case 4:
      cv::flip(img, img, 0);
      break;
    case 5:
      cv::transpose(img, img);
      break;
    case 6:
      cv::transpose(img, img), cv::flip(img, img, 1);
      break;
    case 7:
      cv::transpose(img, img), cv::flip(img, img, -1);
      break;
    case 8:
      cv::transpose(img, img), cv::flip(img, img, 0);
      break;
    default:
      break;
  }
}

// One decompression with its error manager, released however it ends.
struct Decompressor {
  jpeg_decompress_struct info{};
  ErrorManager errors{};
  jpeg_progress_mgr progress{};
  Decompressor() {
    info.err = jpeg_std_error(&errors.pub);
    errors.pub.error_exit = onError;
    errors.pub.emit_message = onMessage;
    errors.pub.output_message = onOutput;
    jpeg_create_decompress(&info);
    progress.progress_monitor = onProgress;
    info.progress = &progress;
  }
  ~Decompressor() { jpeg_destroy_decompress(&info); }
  Decompressor(const Decompressor&) = delete;
  Decompressor& operator=(const Decompressor&) = delete;
};

}  // namespace

bool looksLikeJpeg(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF;
}

namespace {

// The two libjpeg phases, each in a function of its own around its setjmp: no local of the caller
// lives across a longjmp. Each returns false when libjpeg gave up (the error is in d.errors).
bool readHeader(Decompressor& d, std::span<const std::uint8_t> bytes, bool keep_exif) {
  if (setjmp(d.errors.jump) != 0) return false;
  jpeg_mem_src(&d.info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  if (keep_exif) jpeg_save_markers(&d.info, JPEG_APP0 + 1, 0xFFFF);
  jpeg_read_header(&d.info, TRUE);
  return true;
}

bool readPixels(Decompressor& d, JSAMPROW* rows, bool grey) {
  if (setjmp(d.errors.jump) != 0) return false;
  d.info.out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  d.info.out_color_components = grey ? 1 : 3;
  jpeg_start_decompress(&d.info);
  while (d.info.output_scanline < d.info.output_height)
    jpeg_read_scanlines(&d.info, rows + d.info.output_scanline, d.info.output_height - d.info.output_scanline);
  jpeg_finish_decompress(&d.info);
  return true;
}

}  // namespace

cv::Mat decodeJpeg(std::span<const std::uint8_t> bytes, ImageColour colour,
                   const std::function<void(int width, int height)>& check_size,
                   const std::function<void(const std::string&)>& fail) {
  Decompressor d;
  const bool orient = colour != ImageColour::Unchanged;
  if (!readHeader(d, bytes, orient)) fail("a damaged JPEG (" + d.errors.error + ")");
  check_size(static_cast<int>(d.info.image_width), static_cast<int>(d.info.image_height));
  // Read now: the saved markers are freed with the image's memory by jpeg_finish_decompress.
  const int orientation = orient ? exifOrientation(d.info.marker_list) : 1;
  if (d.info.num_components == 4) return {};  // CMYK: left to OpenCV
  const bool grey = colour == ImageColour::Grey || (colour == ImageColour::Unchanged && d.info.num_components == 1);
  cv::Mat img(static_cast<int>(d.info.image_height), static_cast<int>(d.info.image_width), CV_8UC(grey ? 1 : 3));
  std::vector<JSAMPROW> rows(static_cast<std::size_t>(img.rows));
  for (int r = 0; r < img.rows; ++r) rows[static_cast<std::size_t>(r)] = img.ptr<JSAMPLE>(r);
  if (!readPixels(d, rows.data(), grey)) fail("a damaged JPEG (" + d.errors.error + ")");
  if (!d.errors.damage.empty()) fail("a damaged JPEG (" + d.errors.damage + ")");
  orientImage(img, orientation);
  return img;
}

}  // namespace kccd::calib::detail
