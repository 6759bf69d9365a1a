// The options of the commands that fit bodies to meshes (kccd fit, kccd import).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "kccd/modelling/fit_request.hpp"

namespace kccd::cli {

/// Checks a fit request built from the options; a field out of range is a UsageError naming its
/// option (--points, --tolerance, --pieces, --concavity, --evaluations, --seed).
void checkFitOptions(const modelling::FitRequest& request);

/// `--pieces auto|N`: the most convex pieces a concave link may split into (auto: 8); N in 1 ... 64.
int piecesOption(const std::string& text);

/// Adds `--pieces auto|N` and `--concavity MM` (kccd fit and kccd import); `what` opens --pieces' help.
void addPieceOptions(CLI::App& sub, std::string& pieces, double& concavity_mm, const std::string& what);

}  // namespace kccd::cli
