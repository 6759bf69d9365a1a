// libFuzzer target: state logs, read against a small model (the demo arm's joints, the first
// without limits so it is unwrapped, and a translation3d). Any input must load or be rejected with
// kccd::InputError (StateLogError) whose message is one printable line naming the file. A loaded
// log keeps its promises, and stateAt answers a few times around its samples consistently.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/state_log.hpp"

namespace {

const kccd::Model& model() {
  static const kccd::Model m = kccd::parseModel(
      "kccd: 1\n"
      "joints:\n"
      "  - {name: shoulder_yaw, parent: world, type: revolute, axis: [0, 0, 1], origin: {xyz: [0, 0, 0.35]}}\n"
      "  - {name: shoulder_pitch, parent: shoulder_yaw, type: revolute, axis: [0, 1, 0], limits: [-2, 2]}\n"
      "  - {name: elbow, parent: shoulder_pitch, type: revolute, axis: [0, 1, 0], limits: [-2.5, 2.5]}\n"
      "  - {name: tool, parent: world, type: translation3d, error: 0.01}\n"
      "bodies:\n"
      "  - {name: forearm, frame: elbow, points: [[0, 0, 0], [0.32, 0, 0]], radius: 0.045}\n"
      "  - {name: box, frame: tool, points: [[0, 0, 0]], radius: 0.1}\n",
      "fuzz_model");
  return m;
}

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "state log broke a promise: %s\n", what);
    std::abort();
  }
}

void checkLog(const kccd::StateLog& log) {
  const std::size_t n = log.stateSize();
  check(log.names == model().stateNames(), "names");
  check(log.rows() >= 1 && log.values.size() == log.rows() * n, "shape");
  check(log.velocities.empty() || log.velocities.size() == log.values.size(), "velocity shape");
  for (std::size_t r = 0; r < log.rows(); ++r) {
    check(std::isfinite(log.times[r]) && std::abs(log.times[r]) <= kccd::kMaxStateLogMagnitude, "time bound");
    check(r == 0 || log.times[r] > log.times[r - 1], "time order");
  }
  for (const double v : log.values)
    check(std::isfinite(v) && std::abs(v) <= kccd::kMaxStateLogMagnitude, "value bound");
  for (std::size_t k = 0; k < log.velocities.size(); ++k)
    check(log.logged_velocity[k % n] ? std::abs(log.velocities[k]) <= kccd::kMaxStateLogMagnitude
                                     : std::isnan(log.velocities[k]),
          "velocity bound");

  std::vector<double> state(n), velocity(n);
  const double first = log.times.front(), last = log.times.back();
  const double period = log.medianPeriod();
  check(period >= 0.0, "median period");
  // Samples are exact and give their own values.
  for (const std::size_t r : {std::size_t{0}, log.rows() / 2, log.rows() - 1}) {
    check(kccd::stateAt(log, log.times[r], 0.0, state) == kccd::StateMatch::Exact, "exact sample");
    const std::span<const double> values = log.row(r);
    check(std::equal(values.begin(), values.end(), state.begin()), "exact values");
    const kccd::StateMatch m = kccd::stateAt(log, log.times[r], period, state, velocity);
    check(m != kccd::StateMatch::Interpolated, "a sample time is not interpolated");
    if (m == kccd::StateMatch::Exact)
      for (const double v : velocity) check(!std::isnan(v), "velocity at a sample");
  }
  // Nothing beyond the ends.
  check(kccd::stateAt(log, first - 1.0 - std::abs(first) * 1e-6, 1e308, state) == kccd::StateMatch::None, "before");
  check(kccd::stateAt(log, last + 1.0 + std::abs(last) * 1e-6, 1e308, state) == kccd::StateMatch::None, "after");
  // Between the first two samples, with their gap allowed: a state, each limited value between
  // its two samples, each unwrapped one within half a turn of them.
  if (log.rows() >= 2) {
    const double t0 = log.times[0], t1 = log.times[1];
    for (const double f : {0.25, 0.5, 0.75}) {
      const double t = t0 + f * (t1 - t0);
      const kccd::StateMatch m = kccd::stateAt(log, t, t1 - t0, state, velocity);
      check(m != kccd::StateMatch::None, "inside a gap that is allowed");
      for (std::size_t i = 0; i < n; ++i) {
        check(std::isfinite(state[i]) && !std::isnan(velocity[i]), "finite state");
        if (m != kccd::StateMatch::Interpolated) continue;
        const double a = log.values[i], b = log.values[n + i];
        const double slack = 1e-12 * std::max(std::abs(a), std::abs(b)) + std::numeric_limits<double>::denorm_min();
        if (log.circular[i])
          check(std::min(std::abs(state[i] - a), std::abs(state[i] - b)) <= 3.2 + slack,
                "unwrapped value near its samples");
        else
          check(state[i] >= std::min(a, b) - slack && state[i] <= std::max(a, b) + slack, "value between its samples");
      }
      check(kccd::stateAt(log, t, (t1 - t0) / 4, state) != kccd::StateMatch::Interpolated, "gap too long");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_states", "log.csv", data, size);
  static const std::vector<std::string> ignore{"note", "elbow.vel"};
  try {
    checkLog(kccd::loadStateLog(path, model(), ignore));
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
