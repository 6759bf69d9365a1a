// libFuzzer target: camera frames as the calibration commands read them (an image file decoded by
// OpenCV) and the AprilTag detection on what they decode to. Any input must decode and detect, or
// be rejected with kccd::InputError (calib::ImageError, calib::TagDetectionError for a tag seen
// twice); any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/input_error.hpp"

namespace {

const kccd::calib::TagLayout& layout() {
  static const kccd::calib::TagLayout l = kccd::calib::parseTagLayout(
      "tags:\n  - {id: 0, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n  - {id: 3, size: 0.1, xyz: [1, 0, 0], rpy: [0, "
      "0, 0]}\n"
      "  - {id: 17, size: 0.2, xyz: [0, 1, 0], rpy: [1.57, 0, 0]}\n",
      "fuzz_frame layout");
  return l;
}

bool finite(const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_frame", "frame.png", data, size);
  try {
    const cv::Mat grey = kccd::calib::readImageFile(path, kccd::calib::ImageColour::Grey);
    if (grey.empty() || grey.type() != CV_8UC1) std::abort();
    // Keep each input cheap: detection runs on images up to 256 x 256 (larger ones were decoded
    // and bounded above; detection time grows with the pixels, not with new code paths).
    if (static_cast<long>(grey.cols) * grey.rows <= 256L * 256L) {
      const std::vector<kccd::calib::TagDetection> found = kccd::calib::detectTags(grey);
      for (const kccd::calib::TagDetection& d : found) {
        if (d.id < 0 || d.id > kccd::calib::kMaxTagId || d.hamming < 0 || d.hamming > 2) std::abort();
        for (const cv::Point2d& c : d.corners)
          if (!finite(c)) std::abort();
      }
      const kccd::calib::TagCorrespondences tc = kccd::calib::tagCorrespondences(found, layout(), path);
      if (tc.points.size() % 4 != 0 || tc.points.size() / 4 + tc.unknown_ids.size() != found.size()) std::abort();
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
