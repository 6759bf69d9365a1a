#include "cli_app.hpp"

#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_args.hpp"
#include "cli_output.hpp"

namespace kccd::cli {

namespace {

// Says why on one line and gives the exit status.
int fail(Exit status, const std::string& message) {
  std::cerr << "kccd: " << message << "\n";
  return static_cast<int>(status);
}

}  // namespace

int runApp(int argc, char** argv, std::span<const Adder> adders, const AppHooks& hooks) {
  try {
    CLI::App app{
        "kccd - strictly conservative continuous collision detection for robots.\n"
        "Every distance is a guaranteed lower bound over the whole joint interval box."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "kccd " KCCD_VERSION_STRING);
    std::vector<std::pair<CLI::App*, Runner>> commands;
    for (const Adder adder : adders) {
      const std::size_t before = app.get_subcommands({}).size();
      Runner run = adder(app);
      commands.emplace_back(app.get_subcommands({})[before], std::move(run));
    }
    if (argc > 1 && argv[1][0] != '-') {  // CLI11 would only say that a subcommand is required
      std::string names;
      bool known = false;
      for (const auto& [sub, run] : commands) {
        known = known || sub->get_name() == argv[1];
        names += (names.empty() ? "" : ", ") + sub->get_name();
      }
      if (!known)
        return fail(Exit::BadInput, "unknown subcommand '" + kccd::printable(argv[1], 40) + "' (" + names + ")");
    }
    try {
      app.parse(argc, argv);
    } catch (const CLI::Success& e) {  // --help, --version: printed, exit 0
      return app.exit(e);
    } catch (const CLI::ParseError& e) {
      // The help of the (nested) subcommand the line was for.
      std::string help = "kccd";
      const CLI::App* at = &app;
      for (int i = 1; i < argc && argv[i][0] != '-'; ++i) {
        const auto subs = at->get_subcommands([&](const CLI::App* s) { return s->get_name() == argv[i]; });
        if (subs.empty()) break;
        at = subs.front();
        help += std::string(" ") + argv[i];
      }
      help += " --help";
      return fail(Exit::BadInput, optionMessage(e.what()) + " (see " + help + ")");
    }
    for (auto& [sub, run] : commands)
      if (sub->parsed()) {
        const Exit status = run();
        if (hooks.after_run) hooks.after_run();
        return static_cast<int>(status);
      }
  } catch (const InputError& e) {  // every reader's error and every option error (UsageError)
    return fail(Exit::BadInput, oneLine(e.what()));
  } catch (const std::exception& e) {
    if (hooks.environment_error && hooks.environment_error(e)) return fail(Exit::Internal, oneLine(e.what()));
    return fail(Exit::Internal, "internal error: " + oneLine(e.what()));
  }
  return static_cast<int>(Exit::Ok);
}

}  // namespace kccd::cli
