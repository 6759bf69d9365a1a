// What every fuzz target shares: writing the input to a file (readers take a path) and the
// contract every input error must keep.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace kccd::fuzz {

/// This process's id in ten digits: the input's path, which error messages quote, then has the
/// same length in every run (a pid of another length changed the messages' lengths, so the
/// coverage libFuzzer steers by, and runs with the same seed and count did not repeat).
inline std::string fixedWidthPid() {
  const std::string pid = std::to_string(getpid());
  return std::string(pid.size() < 10 ? 10 - pid.size() : 0, '0') + pid;
}

/// Writes `size` bytes to `name` in a folder of this process's own (created once, under the
/// system's temporary folder, named after `target`) and returns the file's path.
inline std::string writeInput(const char* target, const std::string& name, const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [target] {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / (std::string("kccd_") + target + "_" + fixedWidthPid());
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::string path = (dir / name).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

/// The error contract: one printable line that starts with the file's name. Anything else aborts
/// (a finding).
inline void checkMessage(const std::string& message, const std::string& file) {
  bool ok = message.rfind(file, 0) == 0;
  for (const char c : message) ok = ok && static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
  if (!ok) {
    std::fprintf(stderr, "input error breaks the one-line contract: %s\n", message.c_str());
    std::abort();
  }
}

}  // namespace kccd::fuzz
