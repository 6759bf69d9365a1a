// kccd: conservative continuous collision detection for robots, from the command line.
#include <iostream>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/render/gl_context.hpp"

namespace {

using kccd::cli::Exit;

// Says why on one line and gives the exit status.
int fail(Exit status, const std::string& message) {
  std::cerr << "kccd: " << message << "\n";
  return static_cast<int>(status);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "kccd - strictly conservative continuous collision detection for robots.\n"
      "Every distance is a guaranteed lower bound over the whole joint interval box."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "kccd 0.1.0");
  std::vector<std::pair<CLI::App*, kccd::cli::Runner>> commands;
  auto add = [&](kccd::cli::Runner (*adder)(CLI::App&)) {
    const std::size_t before = app.get_subcommands({}).size();
    kccd::cli::Runner run = adder(app);
    commands.emplace_back(app.get_subcommands({})[before], std::move(run));
  };
  add(kccd::cli::addInfo);
  add(kccd::cli::addQuery);
  add(kccd::cli::addFit);
  add(kccd::cli::addPairs);
  add(kccd::cli::addImport);
  add(kccd::cli::addRender);
  add(kccd::cli::addCalib);
  add(kccd::cli::addSynth);
  add(kccd::cli::addOverlay);
  add(kccd::cli::addCheck);
  add(kccd::cli::addGolden);
  add(kccd::cli::addBag);
  add(kccd::cli::addDataset);
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
    return fail(Exit::BadInput, kccd::cli::optionMessage(e.what()) + " (see " + help + ")");
  }
  // A silent change of GL back end changes the renderer string (and may change pixels): said once.
  const auto say_fallback = [] {
    const std::string reason = kccd::render::GlContext::lastFallback();
    if (!reason.empty())
      std::cerr << "kccd: warning: no EGL context (" << kccd::cli::oneLine(reason)
                << "): rendered with OSMesa (KCCD_GL=egl makes this an error, KCCD_GL=osmesa chooses OSMesa)\n";
  };
  try {
    for (auto& [sub, run] : commands)
      if (sub->parsed()) {
        const Exit status = run();
        say_fallback();
        return static_cast<int>(status);
      }
  } catch (const kccd::InputError& e) {  // every reader's error and every option error (UsageError)
    return fail(Exit::BadInput, kccd::cli::oneLine(e.what()));
  } catch (const kccd::render::GlContextError& e) {  // no GL context (KCCD_GL, EGL, OSMesa): not an input error
    return fail(Exit::Internal, kccd::cli::oneLine(e.what()));
  } catch (const std::exception& e) {
    return fail(Exit::Internal, "internal error: " + kccd::cli::oneLine(e.what()));
  }
  return static_cast<int>(Exit::Ok);
}
