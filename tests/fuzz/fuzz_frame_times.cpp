// libFuzzer target: frame-times files. Any input must load or be rejected with kccd::InputError
// (FrameTimesError) whose message is one printable line naming the file. A loaded table keeps its
// promises: at least one frame, every time finite, bounded and strictly increasing.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/overlay/recording/frame_times.hpp"

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "frame times broke a promise: %s\n", what);
    std::abort();
  }
}

void checkTimes(const std::vector<double>& times, std::size_t bytes) {
  check(!times.empty(), "at least one frame");
  check(times.size() <= bytes / 4 + 1, "no more rows than the text holds");
  for (std::size_t i = 0; i < times.size(); ++i) {
    check(std::isfinite(times[i]) && std::abs(times[i]) <= 1e300, "time bound");
    check(i == 0 || times[i] > times[i - 1], "time order");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_frame_times", "times.csv", data, size);
  try {
    const std::vector<double> times = kccd::overlay::loadFrameTimes(path);
    checkTimes(times, size);
    // The in-memory parser gives the same table.
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    check(kccd::overlay::parseFrameTimes(text, path) == times, "file and text agree");
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
