// kccd: the command a user runs. `kccd --version`, `kccd info` and `kccd query` run here, in a
// program that loads only the checker's few libraries (a few milliseconds to start); every other
// subcommand replaces this process by the whole program, kccd-all (rendering, video, calibration:
// some 270 shared libraries, a fifth of a second to load), with the same arguments.
#include <limits.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <string>
#include <string_view>

#include "cli_app.hpp"

namespace {

// This program's own folder, from /proc/self/exe (symbolic links resolved).
std::string ownFolder() {
  char path[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) return {};
  const std::string self(path, static_cast<std::size_t>(n));
  return self.substr(0, self.rfind('/'));
}

// Runs kccd-all with this command line: installed, it is KCCD_ALL_FROM_BIN from this program's
// folder; in the build tree, beside it. Returns only when neither could be run.
int runWholeProgram(char** argv) {
  const std::string folder = ownFolder();
  const std::array<std::string, 2> candidates = {folder + "/" KCCD_ALL_FROM_BIN, folder + "/kccd-all"};
  int error = ENOENT;
  std::string failed = candidates[0];  // the installed place, unless the other exists but failed
  for (const std::string& path : candidates) {
    ::execv(path.c_str(), argv);
    if (errno != ENOENT) error = errno, failed = path;
  }
  std::cerr << "kccd: cannot run " << failed << " (" << std::strerror(error) << "): "
            << (error == ENOENT ? "the rest of kccd is missing; reinstall it" : "the rest of kccd cannot be run")
            << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace kccd::cli;
  const std::string_view first = argc > 1 ? argv[1] : "";
  if (argc == 2 && first == "--version") {
    std::cout << "kccd " KCCD_VERSION_STRING "\n";
    return 0;
  }
  static constexpr std::array<Adder, 2> kLight = {addInfo, addQuery};
  if (first == "info" || first == "query") return runApp(argc, argv, kLight);
  return runWholeProgram(argv);
}
