// kccd: conservative continuous collision detection for robots, from the command line.
#include <iostream>

#include "cli_util.hpp"
#include "commands.hpp"

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
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    for (auto& [sub, run] : commands)
      if (sub->parsed()) return run();
  } catch (const kccd::cli::UsageError& e) {
    std::cerr << "kccd: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "kccd: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
