// libFuzzer target: robot logs as `kccd bag info` reads them (kccd::logs::summarizeBag: the MCAP
// reader, chunk decompression, CRCs, the message definitions the log stores and the CDR / ROS 1
// decoders). Any input must be summarised or rejected with kccd::InputError naming the file on
// one line; any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_logs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_mcap", "log.mcap", data, size);
  kccd::fuzz::summarizeOrExplain(path);
  return 0;
}
