// Reading a whole file, and writing files into a scratch folder, in tests.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace kccd::testing {

/// The bytes of the file at `path` (empty when it cannot be read).
inline std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A folder of this process's own under the temporary directory, `tag` naming the test file.
inline std::filesystem::path scratchFolder(const std::string& tag) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / (tag + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

/// Writes `bytes` to `name` in the scratch folder `tag` and returns its path.
inline std::string writeScratch(const std::string& tag, const std::string& name, const std::string& bytes) {
  const std::filesystem::path p = scratchFolder(tag) / name;
  std::ofstream(p, std::ios::binary) << bytes;
  return p.string();
}

}  // namespace kccd::testing
