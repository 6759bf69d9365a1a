// The value types of a query: what it asks (QueryOptions) and what it answers (QueryResult).
// Plain data with no behaviour beyond naming; the Checker (kccd/checker.hpp) runs queries.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "kccd/types.hpp"

namespace kccd {

/// Outcome of a query. Anything but Ok must be treated as a collision.
enum class Status : std::uint8_t {
  Ok,
  WrongStateSize,    ///< lower/upper length differs from Model::stateSize()
  NonFiniteState,    ///< NaN or infinite state value
  LowerAboveUpper,   ///< an interval with lower > upper
  ExactNeedsPoint,   ///< a joint with `sweep: exact` was given a non-zero-width interval
  NumericalFailure,  ///< a swept volume became non-finite (e.g. overflow)
};
const char* toString(Status status);

/// The questions a query can answer, cheapest first.
enum class QueryType : std::uint8_t {
  Collision,  ///< is any pair within the margin?
  Closest,    ///< the pair with the smallest distance, when it is within the margin
  NClosest,   ///< the N pairs with the smallest distances, with witness points
  Distances,  ///< every checked pair
};
const char* toString(QueryType type);
/// The query type toString names ("collision", "closest", "nclosest", "distances"); none otherwise.
std::optional<QueryType> queryTypeFromString(std::string_view name);

/// The largest time budget a query honours (about 11.6 days, in microseconds); larger is unlimited.
inline constexpr double kMaxBudgetUs = 1e12;

/// How exactly the exact stage refines a pair already clear of the margin (metres): each support
/// of its search within this (the slack counted in the bound) and its distance to a relative 1e-3,
/// so its bound lies at most 2 kExactDistanceTolerance + 1e-3 of the distance below the search's
/// exact value. A verdict (a pair within the margin) is always searched exactly.
inline constexpr double kExactDistanceTolerance = 1e-3;

/// The most sub-boxes QueryOptions::exact_splits may ask for.
inline constexpr int kMaxExactSplits = 32;

/// What a query asks and how long it may take.
struct QueryOptions {
  QueryType type = QueryType::Collision;
  int n = 1;               ///< for NClosest
  double margin = -1.0;    ///< distances <= margin count as collision; < 0 or NaN: the model's margin
  double budget_us = 0.0;  ///< time budget in microseconds; <= 0, NaN or > kMaxBudgetUs: unlimited
  int max_pairs = -1;      ///< work budget: recompute at most this many pairs; < 0: unlimited
  /// The exact stage (swept volumes without a point budget, searched by branch and bound) refines
  /// a pair whose point-volume bound is at most this and at most what the query still needs to
  /// know. Negative (default): the margin for a Collision query, so every verdict is decided by the
  /// exact stage, and the margin plus exact_band for the distance queries (Closest, NClosest,
  /// Distances), so near pairs get tight distances too; +inf: every pair (tightest, slowest);
  /// -inf or NaN: never (point volumes only).
  double exact_below = -1.0;
  /// With the default exact_below: how far above the margin (metres) a distance query's pairs are
  /// refined. A pair already clear of the margin is refined for its distance only, to within
  /// about a millimetre (kExactDistanceTolerance), which costs a fraction of a verdict's search.
  double exact_band = 0.2;
  /// A distance query's pair refined for its distance (clear of the margin, within the band),
  /// moved by at least one swept (accurate) joint, whose bound lies
  /// more than exact_split_gap below its distance at a configuration of the box has its box split into
  /// up to this many sub-boxes (halving, level by level, the state value that moves the pair's
  /// points farthest), each refined by the exact stage: the bound is the smallest over them, up to
  /// the band's top. The exact stage bounds the convex hull of a swept chain, which for wide arcs
  /// of long chains or wide bodies reaches far inside the sweep; sub-boxes shrink that. Rounded
  /// down to a power of two, at most kMaxExactSplits; 0 or 1: never. Collision queries never split.
  int exact_splits = 8;
  /// How far (metres) a pair's bound may lie below its distance at a configuration of the box (the
  /// centre, or the corner the distance's gradient points to) before its box is split: the most a
  /// split could gain, so the looseness a distance query accepts on a pair before paying for
  /// splitting. Smaller: tighter distances, more splits (a smaller gap never gives a lower bound).
  /// NaN or negative: the default.
  double exact_split_gap = 0.015;
  /// Point volumes for display: where a sweep's budget forces a coarse cover, also try chords for
  /// every point reduced to the budget by hull distance, and keep the tighter. Slower; the
  /// verdicts do not change (the exact stage decides them).
  bool tight_volumes = false;
};

/// QueryOptions::exact_below for the words of `kccd query --exact`: "band" (the default, -1),
/// "margin" (`margin`, the query's margin), "all" (+inf: every pair), "off" (-inf: none); none for
/// any other text (a distance in metres is the caller's to read).
std::optional<double> exactBelowFromWord(std::string_view word, double margin);

/// One pair in a result. `distance` is a lower bound over the whole interval box.
struct PairDistance {
  int pair = -1;  ///< index into Model::pairs
  double distance = 0.0;
  bool fresh = false;             ///< recomputed in this query (else carried over from earlier ones)
  bool has_witness = false;       ///< fresh and computed by GJK: witness points are valid
  Vec3 witness_a = Vec3::Zero();  ///< closest points found, in the pair's LCA frame
  Vec3 witness_b = Vec3::Zero();
};

struct QueryStats {
  double time_us = 0.0;
  int pairs_checked = 0;  ///< pairs whose bound was recomputed
  int gjk_calls = 0;
  int gjk_iterations = 0;  ///< the iterations of those gjk_calls (GJK's work, where warm starts show)
  int exact_calls = 0;     ///< distance computations of the exact stage
  int split_pairs = 0;     ///< pairs whose box was split (QueryOptions::exact_splits)
  int volumes_swept = 0;
  bool budget_exhausted = false;  ///< a time or work budget stopped refinement (answer still conservative)
};

/// The answer to one query; its pair list is a view into the Checker's buffers, valid until
/// the next query.
struct QueryResult {
  Status status = Status::Ok;
  QueryType type = QueryType::Collision;
  bool collision = true;      ///< some pair's bound is <= margin (or status is not Ok)
  double min_distance = 0.0;  ///< smallest lower bound over all pairs (+inf without pairs)
  double margin = 0.0;
  std::span<const PairDistance> pairs;  ///< per type: the colliding pair, the closest, the N closest, or all
  QueryStats stats;
};

}  // namespace kccd
