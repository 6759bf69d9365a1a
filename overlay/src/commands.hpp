// The kccd subcommands: each registers its options on the app and runs when selected.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace kccd::cli {

using Runner = std::function<int()>;

Runner addInfo(CLI::App& app);
Runner addQuery(CLI::App& app);
Runner addFit(CLI::App& app);
Runner addPairs(CLI::App& app);
Runner addImport(CLI::App& app);
Runner addRender(CLI::App& app);

}  // namespace kccd::cli
