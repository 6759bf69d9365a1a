// Which body pairs can never come within the safety margin over the joint limits, proven with
// the engine's own conservative sweeps (branch and bound on the joint box), and which adjacent
// pairs always touch.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "kccd/model.hpp"

namespace kccd::modelling {

enum class Verdict {
  Never,           ///< proven: over the whole joint range the lower bound stays above the margin
  AlwaysTouching,  ///< proven: adjacent bodies within the margin at every configuration
  Meets,           ///< a configuration was found where they come within the margin
  Undecided,       ///< the box budget ran out before a proof or a witness
  Unbounded,       ///< a joint between them has no limits (prismatic, translation3d)
};
const char* toString(Verdict verdict);

struct PairReport {
  int a = 0, b = 0;                 ///< body indices, a < b
  int lca = kWorld;
  Verdict verdict = Verdict::Undecided;
  bool adjacent = false;            ///< one body's frame is the parent joint of the other's
  bool checked = false;             ///< currently in Model::pairs
  double bound = 0.0;               ///< Never: smallest lower bound over the covering boxes
  int boxes = 0;                    ///< boxes queried
  std::vector<double> witness;      ///< Meets: a state within the limits where they meet
  double witness_distance = 0.0;    ///< Meets: distance bound at the witness state
};

struct ProofOptions {
  double margin = -1.0;             ///< < 0: the model's safety margin
  int max_boxes = 2000;             ///< per pair
  std::function<void(double)> progress;
};

/// The range every state value is proven over: limits, a full turn for revolute joints without
/// limits, [-pi, pi]^3 for rotation3d (all orientations); prismatic without limits and
/// translation3d are unbounded (NaN).
std::vector<std::array<double, 2>> jointRanges(const Model& model);

/// Analyses every pair of bodies in different frames (checked or not).
std::vector<PairReport> provePairs(const Model& model, const ProofOptions& options = {});

/// The `pairs: ignore` list the proofs justify, as body-name pairs: first the pairs proven never
/// within the margin or always touching, then those the model already ignores, each in report order.
std::vector<std::array<std::string, 2>> ignoreList(const Model& model, const std::vector<PairReport>& reports);

}  // namespace kccd::modelling
