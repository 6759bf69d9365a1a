// The fuzz targets' one helper: readers take a path, so each input is written to a file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace kccd::fuzz {

/// Writes `size` bytes to `name` in a folder of this process's own (created once, under the
/// system's temporary folder, named after `target`) and returns the file's path.
inline std::string writeInput(const char* target, const std::string& name, const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [target] {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / (std::string("kccd_") + target + "_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::string path = (dir / name).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace kccd::fuzz
