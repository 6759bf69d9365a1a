#include "support/run_program.hpp"

#include <array>
#include <cstdio>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace kccd::testing {

Outcome runProgram(const std::string& command, bool merge_stderr) {
  static int calls = 0;
  const std::string err_file =
      ::testing::TempDir() + "/kccd_stderr_" + std::to_string(getpid()) + "_" + std::to_string(++calls) + ".txt";
  const std::string cmd = command + (merge_stderr ? " 2>&1" : " 2>" + err_file);
  Outcome r;
  FILE* pipe = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (pipe != nullptr && fgets(buf.data(), buf.size(), pipe) != nullptr) r.out += buf.data();
  const int status = pipe != nullptr ? pclose(pipe) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (!merge_stderr) {
    if (FILE* f = fopen(err_file.c_str(), "r")) {
      while (fgets(buf.data(), buf.size(), f) != nullptr) r.err += buf.data();
      fclose(f);
    }
    std::remove(err_file.c_str());
  }
  return r;
}

}  // namespace kccd::testing
