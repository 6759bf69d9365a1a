// PNG and JPEG encoding (calib::encodePng / encodeJpeg, libpng and libjpeg-turbo directly) against
// OpenCV's image codecs, a second implementation: every picture type decodes back exactly (PNG) and
// the files are the bytes OpenCV writes with the same settings.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_encode.hpp"
#include "kccd/calib/image_file.hpp"

namespace {

using kccd::calib::encodeJpeg;
using kccd::calib::encodePng;
using kccd::calib::ImageEncodeError;

cv::Mat picture(int type, int w, int h) {
  cv::Mat m(h, w, type);
  cv::RNG rng(static_cast<std::uint64_t>(type) * 977 + static_cast<std::uint64_t>(w));
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  cv::rectangle(m, cv::Rect(w / 4, h / 4, w / 3, h / 3), cv::Scalar::all(CV_MAT_DEPTH(type) == CV_16U ? 40000 : 200),
                cv::FILLED);
  return m;
}

TEST(ImageEncode, PngDecodesBackExactlyAndIsOpenCVsFile) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3}) {
    for (const int level : {0, 1, 6, 9}) {
      SCOPED_TRACE(cv::typeToString(type) + " level " + std::to_string(level));
      const cv::Mat m = picture(type, 67, 41);
      const std::vector<std::uint8_t> png = encodePng(m, level);
      const cv::Mat back = kccd::calib::decodeImage(png, "png", kccd::calib::ImageColour::Unchanged);
      ASSERT_EQ(back.type(), m.type());
      EXPECT_EQ(cv::norm(back, m, cv::NORM_INF), 0.0);
      std::vector<uchar> theirs;
      std::vector<int> params{cv::IMWRITE_PNG_COMPRESSION, level};
      if (level != 1) params.insert(params.end(), {cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_DEFAULT});
      ASSERT_TRUE(cv::imencode(".png", m, theirs, level == 1 ? std::vector<int>{} : params));
      EXPECT_TRUE(std::vector<std::uint8_t>(theirs.begin(), theirs.end()) == png) << "the files differ";
    }
  }
  // A view into a larger picture (rows not contiguous) is encoded as the view.
  const cv::Mat big = picture(CV_8UC3, 90, 60);
  const cv::Mat view = big(cv::Rect(5, 7, 40, 30));
  const cv::Mat back = kccd::calib::decodeImage(encodePng(view), "png", kccd::calib::ImageColour::Unchanged);
  EXPECT_EQ(cv::norm(back, view, cv::NORM_INF), 0.0);
}

TEST(ImageEncode, JpegIsOpenCVsFileAtTheSameQuality) {
  for (const int type : {CV_8UC1, CV_8UC3}) {
    for (const int quality : {1, 50, 90, 100}) {
      SCOPED_TRACE(cv::typeToString(type) + " quality " + std::to_string(quality));
      cv::Mat m = picture(type, 83, 57);
      cv::GaussianBlur(m, m, cv::Size(7, 7), 2.0);
      const std::vector<std::uint8_t> jpeg = encodeJpeg(m, quality);
      std::vector<uchar> theirs;
      ASSERT_TRUE(cv::imencode(".jpg", m, theirs, {cv::IMWRITE_JPEG_QUALITY, quality}));
      EXPECT_TRUE(std::vector<std::uint8_t>(theirs.begin(), theirs.end()) == jpeg) << "the files differ";
      const cv::Mat back = kccd::calib::decodeImage(jpeg, "jpeg", kccd::calib::ImageColour::Unchanged);
      EXPECT_EQ(back.size(), m.size());
    }
  }
}

TEST(ImageEncode, WhatCannotBeEncodedIsRefusedInWords) {
  EXPECT_THROW(encodePng(cv::Mat()), ImageEncodeError);
  EXPECT_THROW(encodePng(cv::Mat(4, 4, CV_32FC1)), ImageEncodeError);
  EXPECT_THROW(encodePng(cv::Mat(4, 4, CV_8UC2)), ImageEncodeError);
  EXPECT_THROW(encodePng(cv::Mat(4, 4, CV_8UC3), 10), ImageEncodeError);
  EXPECT_THROW(encodeJpeg(cv::Mat(4, 4, CV_16UC3)), ImageEncodeError);
  EXPECT_THROW(encodeJpeg(cv::Mat(4, 4, CV_8UC3), 0), ImageEncodeError);
  EXPECT_THROW(encodeJpeg(cv::Mat(4, 4, CV_8UC4)), ImageEncodeError);
}

}  // namespace
