// libFuzzer target: rosbag2 sqlite3 files as `kccd bag info` reads them (kccd::logs::summarizeBag
// through Db3Reader: the topics and messages tables, the stored or built-in definitions, CDR
// decoding). sqlite3 parses the file; what is fuzzed is everything the reader makes of what it
// returns: column types, sizes, NULLs, unknown ids, rows out of order, definitions. Any input must be
// summarised or rejected with kccd::InputError naming the file on one line.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_logs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Every input is read as a database: the magic first, so the fuzzer need not find it.
  static const std::string magic("SQLite format 3\0", 16);
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.compare(0, magic.size(), magic) != 0) bytes = magic + bytes;
  const std::string path =
      kccd::fuzz::writeInput("fuzz_db3", "log.db3", reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  kccd::fuzz::summarizeOrExplain(path);
  std::remove(path.c_str());
  return 0;
}
