// libFuzzer target: tag layout files. Any input must load or be rejected with kccd::InputError
// (calib::TagLayoutError); any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_tags", "layout.yaml", data, size);
  try {
    const kccd::calib::TagLayout layout = kccd::calib::loadTagLayout(path);
    // A loaded layout keeps its promises: ids in range and unique, finite corners.
    for (const kccd::calib::Tag& t : layout.tags) {
      if (t.id < 0 || t.id > kccd::calib::kMaxTagId || layout.find(t.id) != &t || !(t.size > 0.0)) std::abort();
      for (const cv::Point3d& c : t.corners())
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) std::abort();
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
