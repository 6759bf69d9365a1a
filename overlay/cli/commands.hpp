// The kccd subcommands: each registers its options on the app and runs when selected.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace kccd::cli {

/// The exit status of every subcommand (docs/architecture.md section 6): turned into a number only in
/// main, which also maps the exceptions (an InputError or UsageError is BadInput).
enum class Exit : int {
  Ok = 0,           ///< done (also --help and --version)
  Internal = 1,     ///< a bug: an exception that is not about the input
  CheckFailed = 1,  ///< `kccd golden run`: a case failed or its golden is missing (as pytest and JUnit runners say it)
  BadInput = 2,     ///< bad input or option: one line naming the file and place
  Unsafe = 3,       ///< an unsafe query status (query, render, overlay)
  NotSolvable = 4,  ///< calibration could not solve (degenerate, too few inliers)
};

using Runner = std::function<Exit()>;

Runner addInfo(CLI::App& app);
Runner addQuery(CLI::App& app);
Runner addFit(CLI::App& app);
Runner addPairs(CLI::App& app);
Runner addImport(CLI::App& app);
Runner addRender(CLI::App& app);
Runner addCalib(CLI::App& app);
Runner addSynth(CLI::App& app);
Runner addOverlay(CLI::App& app);
/// `kccd golden run | update | approve | list` (cmd_golden.cpp).
Runner addGolden(CLI::App& app);
/// `kccd bag info` (cmd_bag.cpp).
Runner addBag(CLI::App& app);
/// `kccd check` (cmd_check.cpp).
Runner addCheck(CLI::App& app);
/// `kccd dataset info` (cmd_dataset.cpp).
Runner addDataset(CLI::App& app);
/// `sheet`, registered on the `calib` subcommand app.
Runner addCalibSheet(CLI::App& calib);
/// `kccd calib label`: the labelling page (cmd_calib_label.cpp).
Runner addCalibLabel(CLI::App& calib);
/// `intrinsics`, registered on the `calib` subcommand app.
Runner addCalibIntrinsics(CLI::App& calib);

}  // namespace kccd::cli
