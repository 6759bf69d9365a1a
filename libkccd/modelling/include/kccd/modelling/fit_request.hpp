// How a rigid part becomes bodies, asked for once by every front end (kccd fit, kccd import,
// Python's kccd.fit and kccd.import_urdf): the request, the part's pieces fitted as requested, and
// each body as a model file writes it.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "kccd/input_error.hpp"
#include "kccd/modelling/fit.hpp"

namespace kccd::modelling {

inline constexpr double kDefaultToleranceMm = 2.0;   ///< kccd import's default tolerance
inline constexpr double kDefaultConcavityMm = 40.0;  ///< the concavity above which a part splits
inline constexpr int kAutoPieces = 8;                ///< the most pieces of `pieces: auto`

/// How a body's core points are chosen.
enum class FitMethod {
  Points,     ///< exactly `points` core points (fit)
  Tolerance,  ///< the fewest points within `tolerance` of the part's hull (fitToTolerance)
  Hull,       ///< every hull vertex, no fit (exactHull)
};

/// What a front end asks of a fit. The comments name each field as the checks' messages do.
struct FitRequest {
  FitMethod method = FitMethod::Points;
  int points = 8;                                 ///< `points`: K, 1 ... 16 (Points; Tolerance tries it first)
  double tolerance = kDefaultToleranceMm * 1e-3;  ///< `tolerance`: metres, 1e-9 ... 1e3 (Tolerance)
  int max_pieces = 1;  ///< `pieces`: a concave part splits into at most this many (1 ... 64; 1: whole)
  double concavity = kDefaultConcavityMm * 1e-3;  ///< `concavity`: metres, 1e-6 ... 1e3, above which it splits
  int max_evaluations = 4000;                     ///< `max_evaluations`: the optimiser's budget per start (>= 1)
  std::uint64_t seed = 1;                         ///< `seed`: of the optimiser's search directions
};

/// A request out of range: the message is "FIELD: problem", the field in location().field (no
/// source), so a front end can say it in its own spelling (`--points`, `points=`).
class FitRequestError : public InputError {
 public:
  FitRequestError(const std::string& field, const std::string& problem)
      : InputError(InputLocation{{}, 0, 0, field}, problem) {}
};

/// Checks every field that the request's method uses; throws FitRequestError for the first out of
/// range.
void checkFitRequest(const FitRequest& request);

/// One body of a fitted part: a convex piece (or the whole part) and its fit.
struct FittedPiece {
  FitResult fit;
  double concavity = 0.0;  ///< the piece's (metres; 0 when the part was not split)
};

/// A part fitted as requested.
struct FittedPart {
  std::vector<FittedPiece> pieces;  ///< one when the part is not split
  double whole_concavity = 0.0;     ///< of the part before splitting (metres)
  bool measured = false;            ///< whether the concavity was measured (max_pieces > 1, a triangle mesh)
};

/// Checks the request (FitRequestError), splits the part into convex pieces when max_pieces > 1
/// (splitConcave), and fits each as requested; `progress` gets the fraction done. Throws as fit()
/// does.
FittedPart fitPart(const Part& part, const FitRequest& request, const std::function<void(double)>& progress = {});

/// The body name of piece `k` (from 0) of `count`: `name`, or NAME/k+1 when there are several.
std::string pieceName(const std::string& name, int k, int count);

/// The bound a fit's body records (`tolerance:`): FitResult::outside rounded up to a micrometre,
/// as the model file writes it.
std::string toleranceYaml(const FitResult& fit);

/// The fitted part as JSON text, the record `kccd fit --json` prints and Python's kccd.fit returns
/// (docs/formats.md §11): per body `points`, `radius` (rounded up, as the model file writes it),
/// `volume`, `hull_volume`, `volume_ratio` (null for a flat hull), `baselines` (not for Hull),
/// `k`, `hull_vertices`, `evaluations`, `outside`, `tolerance`, `method` and `yaml` (the body's
/// geometry, {points: [...], radius: ...}); several pieces under `pieces`, each with its `name`
/// (pieceName of `name`) and `concavity`; then `concavity` when measured, `exact_hull`,
/// `triangles` and `primitives`.
std::string fitJson(const Part& part, const FitRequest& request, const FittedPart& fitted, const std::string& name);

/// A body entry of a model file's `bodies:` list.
struct BodyEntry {
  std::string name, link, frame;  ///< `link` empty: no link line (a whole link)
  const FitResult* fit = nullptr;
  std::string link_comment, radius_comment, tolerance_comment;  ///< after their lines ("   # ..."), when given
};

/// The entry's lines (name, link, frame, points, radius, tolerance), each after `indent`.
std::string bodyYaml(const BodyEntry& body, const std::string& indent = "");

}  // namespace kccd::modelling
