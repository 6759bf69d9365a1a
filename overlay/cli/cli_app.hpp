// One kccd command line run: parse, dispatch to the selected subcommand, map its outcome to the
// exit status. Shared by the `kccd` launcher (its light subcommands) and the whole program.
#pragma once

#include <exception>
#include <functional>
#include <span>

#include "commands.hpp"

namespace kccd::cli {

/// A subcommand's registration: adds it to the app and returns what runs it (commands.hpp).
using Adder = Runner (*)(CLI::App&);

/// What a program adds to a run: `after_run` is called after a subcommand returned (the whole
/// program says there whether rendering fell back to OSMesa); an exception for which
/// `environment_error` is true is printed as it is, exit 1, without "internal error:" (no GL).
struct AppHooks {
  std::function<void()> after_run;
  std::function<bool(const std::exception&)> environment_error;
};

/// The kccd application with `commands` as its subcommands, run on argv: --help and --version
/// print and exit 0, a bad option or input is one line "kccd: ..." and exit 2, else the
/// subcommand's own exit status (Exit). Never throws.
int runApp(int argc, char** argv, std::span<const Adder> commands, const AppHooks& hooks = {});

}  // namespace kccd::cli
