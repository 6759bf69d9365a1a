#include "cli_fit_args.hpp"

#include <charconv>

#include "cli_args.hpp"
#include "kccd/modelling/fit.hpp"

namespace kccd::cli {

void checkFitOptions(const modelling::FitRequest& request) {
  try {
    modelling::checkFitRequest(request);
  } catch (const modelling::FitRequestError& e) {
    rethrowAsOption(e, {{"max_evaluations", "--evaluations"}});
  }
}

void addPieceOptions(CLI::App& sub, std::string& pieces, double& concavity_mm, const std::string& what) {
  sub.add_option("--pieces", pieces,
                 what +
                     " in convex pieces: auto (up to 8) or N (1: never split); it splits while its concavity exceeds "
                     "--concavity")
      ->capture_default_str();
  sub.add_option("--concavity", concavity_mm,
                 "Millimetres of empty space inside the hull (the hull's surface to the mesh's solid) above which it "
                 "splits")
      ->capture_default_str()
      ->check(finiteIn(1e-3, 1e6));
}

int piecesOption(const std::string& text) {
  if (text == "auto") return modelling::kAutoPieces;
  int n = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc() || end != text.data() + text.size() || n < 1 || n > 64)
    throw UsageError("--pieces: expected auto or a number of pieces 1 ... 64, got '" + text + "'");
  return n;
}

}  // namespace kccd::cli
