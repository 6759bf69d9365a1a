// libFuzzer target: robot logs as `kccd bag info` reads them (kccd::logs::summarizeBag: the MCAP
// reader, chunk decompression, CRCs, the message definitions the log stores and the CDR / ROS 1
// decoders). Any input must be summarised or rejected with kccd::InputError naming the file on
// one line; any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_mcap", "log.mcap", data, size);
  try {
    const kccd::logs::BagSummary b = kccd::logs::summarizeBag(path);
    std::uint64_t n = 0;
    for (const auto& t : b.topics) {
      n += t.count;
      if (t.count == 0 || t.first_log_time > t.last_log_time || t.stamped > t.count || t.zero_stamps > t.stamped) std::abort();
    }
    if (n != b.messages) std::abort();
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}
