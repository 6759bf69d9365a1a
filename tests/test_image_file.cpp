// Image files (kccd/calib/image_file.hpp): PNGs decoded with libpng's simplified API give OpenCV's
// pixels for every colour type and bit depth (OpenCV's own decoder is the oracle), and a damaged
// PNG, whatever byte of its header or data is wrong or wherever it is cut, is one ImageError and
// not a byte on stderr (OpenCV's use of libpng prints "libpng error: ..." there).
#include <gtest/gtest.h>
#include <unistd.h>

#include <zlib.h>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_file.hpp"

namespace {

namespace kc = kccd::calib;

std::vector<std::uint8_t> png(const cv::Mat& m) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(".png", m, bytes));
  return bytes;
}

cv::Mat randomImage(int type, std::mt19937& rng) {
  cv::Mat m(37, 53, type);
  cv::randu(m, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  (void)rng;
  return m;
}

// Everything written to file descriptor 2 while `f` runs.
template <class F>
std::string stderrOf(F&& f) {
  std::fflush(stderr);
  char name[] = "/tmp/kccd_stderr_XXXXXX";
  const int fd = ::mkstemp(name);
  EXPECT_GE(fd, 0);
  const int saved = ::dup(2);
  ::dup2(fd, 2);
  f();
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  std::string text(static_cast<std::size_t>(::lseek(fd, 0, SEEK_END)), '\0');
  ::lseek(fd, 0, SEEK_SET);
  if (!text.empty()) {
    EXPECT_EQ(::read(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  }
  ::close(fd);
  ::unlink(name);
  return text;
}

cv::Mat decoded(const std::vector<std::uint8_t>& bytes, kc::ImageColour colour) {
  return kc::decodeImage({bytes.data(), bytes.size()}, "test.png", colour);
}

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return 1e9;
  return cv::norm(a, b, cv::NORM_INF);
}

TEST(ImageFile, PngPixelsAreOpenCvsForEveryColourTypeAndDepth) {
  std::mt19937 rng(7);
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    cv::Mat m = randomImage(type, rng);
    if (m.channels() == 4) {  // some fully transparent and some opaque pixels among the random ones
      std::vector<cv::Mat> ch;
      cv::split(m, ch);
      ch[3].rowRange(0, 5).setTo(0);
      ch[3].rowRange(5, 10).setTo(CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255);
      cv::merge(ch, m);
    }
    const std::vector<std::uint8_t> bytes = png(m);
    const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<std::uint8_t*>(bytes.data()));
    SCOPED_TRACE("type " + std::to_string(type));
    // 16-bit colour with alpha comes premultiplied from libpng and is divided back: exact where
    // opaque (compared there), black where fully transparent.
    const bool premultiplied = m.channels() == 4 && CV_MAT_DEPTH(type) == CV_16U;
    const cv::Range rows = premultiplied ? cv::Range(5, 10) : cv::Range::all();
    const cv::Mat bgr = decoded(bytes, kc::ImageColour::Bgr);
    ASSERT_EQ(bgr.type(), CV_8UC3);
    EXPECT_EQ(maxDifference(bgr.rowRange(rows), cv::imdecode(encoded, cv::IMREAD_COLOR).rowRange(rows)), 0.0);
    const cv::Mat as_stored = decoded(bytes, kc::ImageColour::Unchanged);
    const cv::Mat opencv_stored = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(as_stored.type(), opencv_stored.type());
    EXPECT_EQ(maxDifference(as_stored.rowRange(rows), opencv_stored.rowRange(rows)), 0.0);
    // Grey from colour: OpenCV lets libpng weigh the channels; within one level of cvtColor's.
    const cv::Mat grey = decoded(bytes, kc::ImageColour::Grey);
    ASSERT_EQ(grey.type(), CV_8UC1);
    EXPECT_LE(maxDifference(grey.rowRange(rows), cv::imdecode(encoded, cv::IMREAD_GRAYSCALE).rowRange(rows)),
              m.channels() == 1 ? 0.0 : 1.0);
  }
}

// The PNG with its chunk's CRC recomputed after a change (so that the change itself is read).
void fixCrc(std::vector<std::uint8_t>& b, std::size_t chunk_start) {
  const std::uint32_t length = (std::uint32_t{b[chunk_start]} << 24) | (std::uint32_t{b[chunk_start + 1]} << 16) |
                               (std::uint32_t{b[chunk_start + 2]} << 8) | b[chunk_start + 3];
  const std::size_t end = chunk_start + 8 + length;
  if (end + 4 > b.size()) return;
  const uLong crc = crc32(0, b.data() + chunk_start + 4, static_cast<uInt>(length + 4));
  for (int k = 0; k < 4; ++k) b[end + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(crc >> (24 - 8 * k));
}

TEST(ImageFile, DamagedPngsAreOneErrorAndNothingOnStderr) {
  std::mt19937 rng(11);
  cv::Mat m(24, 32, CV_8UC3);
  cv::randu(m, 0, 256);
  const std::vector<std::uint8_t> good = png(m);
  std::vector<std::vector<std::uint8_t>> damaged;
  // Every byte of IHDR's data (width, height, depth, colour type, methods) set to values that
  // matter, with the CRC wrong and with it recomputed.
  for (std::size_t at = 16; at < 29; ++at)
    for (const int v : {0, 1, 2, 3, 4, 6, 7, 8, 16, 0x7f, 0x80, 0xff}) {
      std::vector<std::uint8_t> b = good;
      if (b[at] == v) continue;
      b[at] = static_cast<std::uint8_t>(v);
      damaged.push_back(b);
      fixCrc(b, 8);
      damaged.push_back(b);
    }
  // Cut anywhere, and bytes of the compressed data changed (CRC recomputed).
  for (std::size_t cut = 1; cut < good.size(); cut += 7)
    damaged.emplace_back(good.begin(), good.begin() + static_cast<long>(cut));
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> b = good;
    b[41 + rng() % (good.size() - 41 - 16)] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    fixCrc(b, 33);
    damaged.push_back(b);
  }
  int refused = 0;
  for (std::size_t i = 0; i < damaged.size(); ++i) {
    std::string problem;
    const std::string printed = stderrOf([&] {
      for (const kc::ImageColour c : {kc::ImageColour::Bgr, kc::ImageColour::Grey, kc::ImageColour::Unchanged}) {
        try {
          const cv::Mat img = decoded(damaged[i], c);
          EXPECT_FALSE(img.empty());
        } catch (const kc::ImageError& e) {
          problem = e.what();
        }
      }
    });
    EXPECT_EQ(printed, "") << "input " << i;
    if (!problem.empty()) {
      ++refused;
      EXPECT_EQ(problem.rfind("test.png: image: ", 0), 0u) << problem;
      EXPECT_EQ(problem.find('\n'), std::string::npos) << problem;
    }
  }
  // Most of them cannot be read (a changed byte of pixel data can still decode).
  EXPECT_GT(refused, static_cast<int>(damaged.size() / 2)) << refused << " of " << damaged.size();
}

}  // namespace

namespace {

// `jpeg` with an Exif APP1 segment holding only Orientation = `o` inserted after SOI (as a
// camera writes it; OpenCV's encoder writes none).
std::vector<std::uint8_t> withOrientation(const std::vector<std::uint8_t>& jpeg, int o, bool big_endian) {
  std::vector<std::uint8_t> tiff = big_endian ? std::vector<std::uint8_t>{'M', 'M', 0, 42, 0, 0, 0, 8}
                                              : std::vector<std::uint8_t>{'I', 'I', 42, 0, 8, 0, 0, 0};
  const auto u16 = [&](unsigned v) {
    if (big_endian)
      tiff.push_back(static_cast<std::uint8_t>(v >> 8)), tiff.push_back(static_cast<std::uint8_t>(v & 0xFF));
    else
      tiff.push_back(static_cast<std::uint8_t>(v & 0xFF)), tiff.push_back(static_cast<std::uint8_t>(v >> 8));
  };
  u16(1);                                 // one entry
  u16(0x0112), u16(3), u16(1), u16(0);    // Orientation, SHORT, count 1 (the count's high half)
  u16(static_cast<unsigned>(o)), u16(0);  // the value, padding
  u16(0), u16(0);                         // no next IFD
  std::vector<std::uint8_t> app1 = {'E', 'x', 'i', 'f', 0, 0};
  app1.insert(app1.end(), tiff.begin(), tiff.end());
  const std::size_t length = app1.size() + 2;
  std::vector<std::uint8_t> out(jpeg.begin(), jpeg.begin() + 2);
  out.insert(out.end(), {0xFF, 0xE1, static_cast<std::uint8_t>(length >> 8), static_cast<std::uint8_t>(length & 0xFF)});
  out.insert(out.end(), app1.begin(), app1.end());
  out.insert(out.end(), jpeg.begin() + 2, jpeg.end());
  return out;
}

// JPEGs are decoded by the suite (libjpeg-turbo, its messages kept); OpenCV's imdecode is the
// oracle: the same pixels for colour and grey files, baseline and progressive,
// optimised tables, restart markers, every Exif orientation in both byte orders, in every colour mode.
TEST(ImageFile, JpegPixelsAreOpenCvsInEveryMode) {
  std::mt19937 rng(5);
  int compared = 0;
  for (const int type : {CV_8UC3, CV_8UC1}) {
    cv::Mat m(45, 61, type);
    cv::randu(m, 0, 256);
    cv::GaussianBlur(m, m, cv::Size(5, 5), 1.5);  // photo-like, so quantisation keeps structure
    const std::vector<std::vector<int>> settings = {
        {cv::IMWRITE_JPEG_QUALITY, 90},
        {cv::IMWRITE_JPEG_QUALITY, 75, cv::IMWRITE_JPEG_PROGRESSIVE, 1},
        {cv::IMWRITE_JPEG_QUALITY, 95, cv::IMWRITE_JPEG_OPTIMIZE, 1, cv::IMWRITE_JPEG_CHROMA_QUALITY, 60},
        {cv::IMWRITE_JPEG_QUALITY, 80, cv::IMWRITE_JPEG_RST_INTERVAL, 2},
    };
    for (const auto& params : settings) {
      std::vector<std::uint8_t> jpeg;
      ASSERT_TRUE(cv::imencode(".jpg", m, jpeg, params));
      for (int o = 1; o <= 8; ++o) {
        for (const bool big : {false, true}) {
          const std::vector<std::uint8_t> bytes = o == 1 && !big ? jpeg : withOrientation(jpeg, o, big);
          const cv::Mat buf(1, static_cast<int>(bytes.size()), CV_8U, const_cast<std::uint8_t*>(bytes.data()));
          for (const auto& [mode, flag] : {std::pair{kc::ImageColour::Bgr, cv::IMREAD_COLOR},
                                           std::pair{kc::ImageColour::Grey, cv::IMREAD_GRAYSCALE},
                                           std::pair{kc::ImageColour::Unchanged, cv::IMREAD_UNCHANGED}}) {
            SCOPED_TRACE(std::to_string(type) + " orientation " + std::to_string(o) + (big ? " MM" : " II") + " mode " +
                         std::to_string(static_cast<int>(mode)));
            const cv::Mat ours = decoded(bytes, mode), theirs = cv::imdecode(buf, flag);
            ASSERT_EQ(ours.size(), theirs.size());
            ASSERT_EQ(ours.type(), theirs.type());
            EXPECT_EQ(cv::norm(ours, theirs, cv::NORM_INF), 0.0);
            ++compared;
          }
        }
      }
    }
  }
  EXPECT_EQ(compared, 2 * 4 * 16 * 3);
}

// A cut JPEG and one whose entropy-coded data is damaged: one line naming the damage, nothing on
// stderr (OpenCV decoded both to a grey-filled picture, with libjpeg's warning on stderr).
TEST(ImageFile, DamagedJpegsAreOneErrorAndNothingOnStderr) {
  cv::Mat m(64, 64, CV_8UC3);
  cv::randu(m, 0, 256);
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", m, jpeg));
  std::vector<std::vector<std::uint8_t>> damaged;
  for (std::size_t cut = 3; cut + 2 < jpeg.size(); cut += 97)
    damaged.emplace_back(jpeg.begin(), jpeg.begin() + static_cast<long>(cut));
  int refused = 0;
  for (const auto& b : damaged) {
    std::string problem;
    const std::string printed = stderrOf([&] {
      try {
        (void)decoded(b, kc::ImageColour::Bgr);
      } catch (const kc::ImageError& e) {
        problem = e.what();
      }
    });
    EXPECT_EQ(printed, "");
    EXPECT_FALSE(problem.empty()) << "a cut JPEG of " << b.size() << " of " << jpeg.size() << " bytes decoded";
    if (!problem.empty()) {
      ++refused;
      EXPECT_EQ(problem.rfind("test.png: image: a damaged JPEG (", 0), 0u) << problem;
      EXPECT_EQ(problem.find('\n'), std::string::npos) << problem;
    }
  }
  EXPECT_EQ(refused, static_cast<int>(damaged.size()));
}

}  // namespace
