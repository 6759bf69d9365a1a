// libFuzzer target: joint maps (`kccd overlay --bag ... --joint-map`), read against a small model.
// Any input must load or be rejected with kccd::InputError on one line naming the file. A loaded
// map keeps its promises: one source per state value, in the model's order, finite and bounded
// scales and offsets (a scale never 0), a constant or a logged name for each.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/bags/joint_map.hpp"

namespace {

const kccd::Model& model() {
  static const kccd::Model m = kccd::parseModel(
      "kccd: 1\n"
      "joints:\n"
      "  - {name: shoulder, parent: world, type: revolute, axis: [0, 0, 1], origin: {xyz: [0, 0, 0.35]}}\n"
      "  - {name: elbow, parent: shoulder, type: revolute, axis: [0, 1, 0], limits: [-2.5, 2.5]}\n"
      "  - {name: finger, parent: elbow, type: prismatic, axis: [1, 0, 0], limits: [0, 0.04]}\n"
      "bodies:\n"
      "  - {name: forearm, frame: elbow, points: [[0, 0, 0], [0.32, 0, 0]], radius: 0.045}\n",
      "fuzz_joint_map");
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_joint_map", "map.yaml", data, size);
  try {
    const kccd::overlay::JointMap map = kccd::overlay::loadJointMap(path, model());
    const auto& names = model().stateNames();
    if (map.states.size() != names.size()) std::abort();
    for (std::size_t k = 0; k < names.size(); ++k) {
      const kccd::overlay::JointSource& s = map.states[k];
      if (s.state != names[k]) std::abort();
      if (s.constant ? !std::isfinite(*s.constant) || !s.from.empty() : s.from.empty()) std::abort();
      if (!std::isfinite(s.scale) || s.scale == 0.0 || std::abs(s.scale) > 1e6 || !std::isfinite(s.offset) ||
          std::abs(s.offset) > 1e6)
        std::abort();
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
