// libFuzzer target: labels files. Any input must load or be rejected with kccd::InputError
// (calib::LabelsError); any other exception, a crash, a hang or a sanitizer report is a finding.
// Loaded body labels are also placed by a small model, whose errors keep the same contract.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/calib/labels.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"

namespace {

const kccd::Model& model() {
  static const kccd::Model m = kccd::parseModel(
      "kccd: 1\n"
      "joints:\n"
      "  - {name: base, parent: world, type: revolute, axis: [0, 0, 1]}\n"
      "  - {name: slide, parent: base, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0.3, 0, 0]}}\n"
      "bodies:\n"
      "  - {name: table, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
      "  - {name: forearm, frame: slide, points: [[0, 0, 0]], radius: 0.1}\n",
      "fuzz_model");
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_labels", "labels.yaml", data, size);
  try {
    const kccd::calib::Labels labels = kccd::calib::loadLabels(path);
    for (const kccd::calib::Label& l : labels.labels) {
      if (labels.find(l.name) != &l || l.world.has_value() == !l.body.empty()) std::abort();
      try {
        const cv::Point3d w = kccd::calib::worldPoint(model(), l);
        if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z)) std::abort();
      } catch (const kccd::InputError& e) {
        kccd::fuzz::checkMessage(e.what(), path);
      }
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
