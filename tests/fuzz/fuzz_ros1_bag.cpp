// libFuzzer target: ROS 1 bags as `kccd bag info` reads them (kccd::logs::summarizeBag through
// Ros1Reader: records, bz2 and lz4 chunks, connection headers, the definitions they carry and
// ROS 1 decoding). Any input must be summarised or rejected with kccd::InputError naming the file
// on one line; any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_logs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Every input is read as a ROS 1 bag: the magic first, so the fuzzer need not find it.
  std::string bytes = "#ROSBAG V2.0\n";
  bytes.append(reinterpret_cast<const char*>(data), size);
  if (size >= 13 && std::string(reinterpret_cast<const char*>(data), 13) == "#ROSBAG V2.0\n")
    bytes.assign(reinterpret_cast<const char*>(data), size);
  const std::string path = kccd::fuzz::writeInput("fuzz_ros1_bag", "log.bag",
                                                  reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  kccd::fuzz::summarizeOrExplain(path);
  return 0;
}
