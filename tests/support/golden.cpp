#include "support/golden.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace kccd::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kGoldenDir = KCCD_GOLDEN_DIR;
const fs::path kOutDir = KCCD_GOLDEN_OUT_DIR;

std::string storedRenderer() {
  std::ifstream in(kGoldenDir / "golden.yaml");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("renderer: ", 0) == 0) {
      std::string r = line.substr(10);
      if (r.size() >= 2 && r.front() == '"' && r.back() == '"') r = r.substr(1, r.size() - 2);
      return r;
    }
  return {};
}

void storeRenderer(const std::string& renderer) {
  std::ofstream out(kGoldenDir / "golden.yaml");
  out << "# Golden images for the image tests (tests/support/golden.hpp): the GL renderer they were made with.\n"
      << "# Rewrite them deliberately with UPDATE_GOLDEN=1 ctest -R Golden (then review the diff).\n"
      << "renderer: \"" << renderer << "\"\n";
}

}  // namespace

::testing::AssertionResult compareGolden(const cv::Mat& actual, const std::string& name, const std::string& renderer,
                                         const GoldenTolerance& tolerance) {
  const fs::path golden_path = kGoldenDir / (name + ".png");
  const char* update = std::getenv("UPDATE_GOLDEN");
  if (update != nullptr && std::string(update) == "1") {
    fs::create_directories(kGoldenDir);
    if (!cv::imwrite(golden_path.string(), actual))
      return ::testing::AssertionFailure() << "cannot write golden " << golden_path;
    storeRenderer(renderer);
    std::cerr << "[golden] updated " << golden_path << "\n";
    return ::testing::AssertionSuccess();
  }
  const std::string stored = storedRenderer();
  const std::string renderer_note = stored == renderer ? ""
                                                       : "\n[golden] warning: goldens were made with renderer '" +
                                                             stored + "', this is '" + renderer + "'";
  const cv::Mat golden = cv::imread(golden_path.string(), cv::IMREAD_UNCHANGED);
  fs::create_directories(kOutDir);
  const fs::path actual_path = kOutDir / (name + ".actual.png"), diff_path = kOutDir / (name + ".diff.png");
  if (golden.empty()) {
    cv::imwrite(actual_path.string(), actual);
    return ::testing::AssertionFailure() << "no golden " << golden_path << " (actual written to " << actual_path
                                         << "; create goldens with UPDATE_GOLDEN=1)";
  }
  if (golden.size() != actual.size() || golden.type() != actual.type()) {
    cv::imwrite(actual_path.string(), actual);
    return ::testing::AssertionFailure() << "golden " << golden_path << " is " << golden.cols << "x" << golden.rows
                                         << " with " << golden.channels() << " channels, actual " << actual.cols << "x"
                                         << actual.rows << " with " << actual.channels() << " (written to "
                                         << actual_path << ")" << renderer_note;
  }
  cv::Mat diff;
  cv::absdiff(actual, golden, diff);
  cv::Mat per_pixel = diff.reshape(1, static_cast<int>(diff.total()));
  cv::reduce(per_pixel, per_pixel, 1, cv::REDUCE_MAX);
  const int different = cv::countNonZero(per_pixel > tolerance.threshold);
  const int changed = cv::countNonZero(per_pixel > 0);
  const int allowed = std::max(tolerance.min_pixels, static_cast<int>(tolerance.max_fraction * actual.total()));
  if (different <= allowed) {
    if (changed > 0)
      std::cerr << "[golden] " << name << ": " << changed << " pixels changed, " << different << " beyond "
                << tolerance.threshold << " levels (allowed " << allowed << ")" << renderer_note << "\n";
    return ::testing::AssertionSuccess();
  }
  cv::Mat amplified = diff * 8;
  if (amplified.channels() == 4) {
    std::vector<cv::Mat> ch;
    cv::split(amplified, ch);
    cv::max(ch[0], ch[3], ch[0]);  // an alpha change shows in blue
    ch[3].setTo(255);
    cv::merge(ch, amplified);
  }
  cv::imwrite(actual_path.string(), actual);
  cv::imwrite(diff_path.string(), amplified);
  return ::testing::AssertionFailure() << name << ": " << different << " pixels differ by more than "
                                       << tolerance.threshold << " levels (allowed " << allowed << "); actual "
                                       << actual_path << ", diff " << diff_path << renderer_note;
}

}  // namespace kccd::testing
