// Diagnosis of flagged pairs, off the real-time path: which configuration in an interval box
// brings a pair closest, and whether a flag is a real collision or only a possible one.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "kccd/model.hpp"

namespace kccd {

/// How hard closestConfiguration() searches.
struct SearchOptions {
  int starts = 12;          ///< descents: the box centre, the corner down the gradient, then random points (>= 1)
  int max_steps = 200;      ///< accepted steps per descent (>= 0)
  std::uint64_t seed = 1;   ///< the random starts; the same seed gives the same answer
  double stop_below = 0.0;  ///< stop the whole search once a distance <= this is found
};

/// The closest configuration found for one pair.
struct ClosestConfiguration {
  int pair = -1;  ///< index into Model::pairs
  /// SSCH distance of the pair at `state` (rounded up): an upper bound on the pair's smallest
  /// distance over the box; +inf when no configuration could be evaluated.
  double distance = 0.0;
  std::vector<double> state;    ///< a configuration inside [lower, upper] (every value within its interval)
  Vec3 point_a = Vec3::Zero();  ///< closest point of body a in world coordinates at `state`
  Vec3 point_b = Vec3::Zero();  ///< closest point of body b in world coordinates at `state`
  int evaluations = 0;          ///< distance evaluations spent
};

/// Searches [lower, upper] for the configuration with the smallest distance of `pair`: projected
/// gradient descent with a backtracking line search and the analytic gradient (rotation3d joints:
/// central differences of the exponential map), from several starts. Only the joints between
/// each body and the pair's LCA frame are varied (the others sit at their interval's centre).
/// Joint error bounds are not searched: the configuration uses nominal joint values. A revolute
/// interval wider than a full turn is searched over one full turn inside it, starting at the
/// value nearest zero. A local search: the answer bounds the true minimum from above only.
/// Allocates; throws std::invalid_argument for a bad pair index, box or option.
ClosestConfiguration closestConfiguration(const Model& model, int pair, std::span<const double> lower,
                                          std::span<const double> upper, const SearchOptions& options = {});

/// What a flag means.
enum class PairVerdict : std::uint8_t {
  Clear,     ///< the lower bound is above the margin
  Possible,  ///< the bound is within the margin but no configuration found is
  Real,      ///< a configuration found is within the margin (it proves the collision)
};
const char* toString(PairVerdict verdict);

/// Clear: bound > margin; Real: found <= margin; Possible: bound <= margin < found (or a NaN).
PairVerdict verdict(double bound, double found, double margin) noexcept;

/// One flagged pair explained.
struct PairExplanation {
  int pair = -1;                 ///< index into Model::pairs
  double bound = 0.0;            ///< the Checker's lower bound over the box
  ClosestConfiguration closest;  ///< the closest configuration found
  PairVerdict verdict = PairVerdict::Possible;
};

/// Runs a Distances query on [lower, upper] and explains every pair whose bound is <= margin
/// (margin < 0 or NaN: the model's), in pair order. Throws std::invalid_argument for a box the
/// query rejects (any status but Ok) and for what closestConfiguration() rejects.
std::vector<PairExplanation> explainFlagged(const Model& model, std::span<const double> lower,
                                            std::span<const double> upper, double margin = -1.0,
                                            const SearchOptions& options = {});

}  // namespace kccd
