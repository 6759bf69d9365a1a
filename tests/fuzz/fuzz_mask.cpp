// libFuzzer target: robot masks as `kccd calib --masks` reads them (calib::readMask: any image file,
// non-zero = robot, the camera's size), then the silhouette's IoU with a drawn box. Any input must
// load as a 0/255 mask of that size with robot and background, or be rejected with
// kccd::InputError (calib::MaskError) on one line naming the file; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_support.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  // The first byte picks the camera size the mask must have: 1..64 x 1..64 (most inputs then
  // fail the size check; the decoders run either way).
  const int side = 1 + (data[0] & 63);
  const std::string path = kccd::fuzz::writeInput("fuzz_mask", "mask.png", data + 1, size - 1);
  try {
    const cv::Mat m = kccd::calib::readMask(path, side, side);
    if (m.rows != side || m.cols != side || m.type() != CV_8UC1) std::abort();
    const int robot = cv::countNonZero(m);
    if (robot == 0 || robot == side * side || cv::countNonZero(m == 255) != robot) std::abort();
    cv::Mat box = cv::Mat::zeros(side, side, CV_8UC1);
    box(cv::Rect(0, 0, (side + 1) / 2, side)).setTo(255);
    const double iou = kccd::calib::maskIou(m, box);
    if (!(iou >= 0.0 && iou <= 1.0)) std::abort();
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
