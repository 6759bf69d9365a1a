// Runs a command line as scripts do and captures what it printed and its exit code.
#pragma once

#include <string>

namespace kccd::testing {

struct Outcome {
  int code = -1;    ///< exit status (-1 when the program did not exit normally)
  std::string out;  ///< standard output (and standard error with merge_stderr)
  std::string err;  ///< standard error
};

/// Runs `command` through the shell. Standard error goes to a file of its own per call and
/// process (ctest runs tests in parallel), unless merged into `out`.
Outcome runProgram(const std::string& command, bool merge_stderr = false);

}  // namespace kccd::testing
