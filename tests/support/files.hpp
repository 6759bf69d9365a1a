// Reading a whole file in tests.
#pragma once

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

}  // namespace kccd::testing
