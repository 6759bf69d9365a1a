// A survey of recorded states: how often and how close each pair comes to the margin over a
// state log (MoveIt's "often in collision" survey, reported only: ignoring a pair is a decision
// for the integrator, never taken from a survey).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "kccd/model.hpp"
#include "kccd/state_log.hpp"

namespace kccd::modelling {

/// One pair over the whole log.
struct PairSurvey {
  int a = 0, b = 0;  ///< body indices
  int lca = kWorld;
  bool checked = true;          ///< in Model::pairs (false: an ignored pair, surveyed on request)
  std::size_t within = 0;       ///< samples with the distance <= margin
  std::size_t overlapping = 0;  ///< samples where the volumes overlap (distance 0)
  double min_distance = 0.0;    ///< smallest distance over the samples (the engine's lower bound);
                                ///< NaN when no query ended Ok
  double min_time = 0.0;        ///< time of that sample (log time - time_offset); NaN likewise
  double first_within = 0.0;    ///< first and last time within the margin (when within > 0)
  double last_within = 0.0;
  double max_penetration = 0.0;  ///< deepest overlap, libccd's MPR estimate (reporting only, not a bound)
  int body_pairs = 1;            ///< in Survey::links: the body pairs joined (pieces of concave links); a, b
                                 ///< are then the closest pieces (at min_distance)
};

struct SurveyOptions {
  double margin = -1.0;        ///< < 0: the model's safety margin
  double time_offset = 0.0;    ///< times reported as video times: log time - offset (as kccd overlay)
  bool ignored_pairs = false;  ///< also survey the pairs the model ignores
  std::function<void(double)> progress;
};

struct Survey {
  double margin = 0.0;
  std::size_t samples = 0;         ///< log rows queried
  std::size_t samples_within = 0;  ///< rows where some checked pair is within the margin (a red frame)
  std::size_t unsafe = 0;          ///< rows whose query did not end Ok (counted as within)
  std::vector<PairSurvey> pairs;   ///< checked pairs in Model::pairs order, then ignored ones
  /// The same per pair of links (Body::linkName: the pieces of a concave link are one link), in
  /// order of first appearance in `pairs`: within a sample a link pair is as close as its closest
  /// pieces. Equal to `pairs` for a model without pieces.
  std::vector<PairSurvey> links;
};

/// Queries every row of `log` (recorded for `model`) as a point state, distances of every
/// checked pair (and ignored ones on request), exact within the margin.
Survey surveyStates(const Model& model, const StateLog& log, const SurveyOptions& options = {});

/// `count` states drawn uniformly inside the joint ranges (jointRanges; values without a range at
/// 0) by a generator seeded with `seed`, at times 0, 1, ..., count - 1: MoveIt's "often in
/// collision" sampling. The same seed gives the same states.
StateLog randomStates(const Model& model, int count, std::uint64_t seed);

/// Pairs by concern: most often within the margin first, then the closest (stable).
std::vector<const PairSurvey*> byConcern(const std::vector<PairSurvey>& pairs);

}  // namespace kccd::modelling
