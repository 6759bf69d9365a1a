// The mutable side of KCCD: a Checker owns every buffer a query needs. After construction a
// query never allocates and never throws; any status other than Ok means "unsafe, stop".
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "kccd/model.hpp"

namespace kccd {

/// Outcome of a query. Anything but Ok must be treated as a collision.
enum class Status : std::uint8_t {
  Ok,
  WrongStateSize,     ///< lower/upper length differs from Model::stateSize()
  NonFiniteState,     ///< NaN or infinite state value
  LowerAboveUpper,    ///< an interval with lower > upper
  ExactNeedsPoint,    ///< a joint with `sweep: exact` was given a non-zero-width interval
  NumericalFailure,   ///< a swept volume became non-finite (e.g. overflow)
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

/// The largest time budget a query honours (about 11.6 days, in microseconds); larger is unlimited.
inline constexpr double kMaxBudgetUs = 1e12;

/// What a query asks and how long it may take.
struct QueryOptions {
  QueryType type = QueryType::Collision;
  int n = 1;               ///< for NClosest
  double margin = -1.0;    ///< distances <= margin count as collision; < 0 or NaN: the model's margin
  double budget_us = 0.0;  ///< time budget in microseconds; <= 0, NaN or > kMaxBudgetUs: unlimited
  int max_pairs = -1;      ///< work budget: recompute at most this many pairs; < 0: unlimited
};

/// One pair in a result. `distance` is a lower bound over the whole interval box.
struct PairDistance {
  int pair = -1;            ///< index into Model::pairs
  double distance = 0.0;
  bool fresh = false;       ///< recomputed in this query (else carried over from earlier ones)
  bool has_witness = false; ///< fresh and computed by GJK: witness points are valid
  Vec3 witness_a = Vec3::Zero();  ///< closest points found, in the pair's LCA frame
  Vec3 witness_b = Vec3::Zero();
};

struct QueryStats {
  double time_us = 0.0;
  int pairs_checked = 0;    ///< pairs whose bound was recomputed
  int gjk_calls = 0;
  int volumes_swept = 0;
  bool budget_exhausted = false;  ///< a time or work budget stopped refinement (answer still conservative)
};

/// The answer to one query; its pair list is a view into the Checker's buffers, valid until
/// the next query.
struct QueryResult {
  Status status = Status::Ok;
  QueryType type = QueryType::Collision;
  bool collision = true;          ///< some pair's bound is <= margin (or status is not Ok)
  double min_distance = 0.0;      ///< smallest lower bound over all pairs (+inf without pairs)
  double margin = 0.0;
  std::span<const PairDistance> pairs;  ///< per type: the colliding pair, the closest, the N closest, or all
  QueryStats stats;
};

/// Holds the per-cycle swept volumes and the any-time table of pair bounds. Bounds are reused
/// across queries while they stay valid lower bounds for the new interval box.
class Checker {
 public:
  /// Preallocates everything for `model` (which must outlive the Checker).
  explicit Checker(const Model& model);

  /// Answers one query for the interval box [lower, upper] (both of length stateSize()).
  /// Never allocates, never throws.
  const QueryResult& query(std::span<const double> lower, std::span<const double> upper,
                           const QueryOptions& options = {}) noexcept;

  /// Forgets every stored bound (the next query recomputes from scratch).
  void reset() noexcept;

  const Model& model() const { return model_; }

  /// The swept volume of `body` expressed in frame `frame` (an ancestor of the body's frame or
  /// its own) for the box of the last query. For inspection and rendering; valid until the next
  /// query. Returns an empty view when the frame is not on the body's path.
  SschView sweptVolume(int body, int frame) noexcept;

 private:
  struct Volume {
    int offset = 0;       // into points_
    int capacity = 0;
    int count = 0;
    double radius = 0.0;
    Sphere bound;          // around the points (valid with stamp)
    Sphere swept_sphere;   // swept cheaply from the level below (valid with sphere_stamp)
    std::uint64_t stamp = 0;
    std::uint64_t sphere_stamp = 0;
  };
  struct Entry {           // the any-time table
    bool valid = false;
    double bound = 0.0;    // lower bound for the box stored in box_
    double current = 0.0;  // bound valid for this query's box
    bool gjk = false;      // the stored bound came from GJK (witness points valid)
    Vec3 direction = Vec3::UnitX();
    Vec3 witness_a = Vec3::Zero(), witness_b = Vec3::Zero();
  };

  bool validate(std::span<const double> lower, std::span<const double> upper) noexcept;
  const Volume* volume(int body, int level) noexcept;
  SschView view(const Volume& v) const noexcept;
  const Sphere* sphere(int body, int level) noexcept;
  double refresh(int pair, double stop_above) noexcept;
  void publish(int pair, PairDistance& out) const noexcept;

  const Model& model_;
  std::vector<Vec3> points_;                 // arena of every volume's points
  std::vector<int> level_begin_;             // per body: index of its level-0 volume in volumes_
  std::vector<int> levels_;                  // per body: number of levels
  std::vector<Volume> volumes_;
  std::vector<int> path_;                    // per body and level: the joint swept from that level
  std::vector<int> pair_level_;              // per pair: level of a, level of b
  std::vector<int> reach_begin_;             // per pair: its range in reach_state_ / reach_
  std::vector<int> reach_state_;             // state values that move the pair
  std::vector<double> reach_;                // how far they move its core points per unit change
  std::vector<Entry> table_;
  std::vector<double> box_;                  // per reach entry: the stored bound's lower, upper
  std::vector<Vec3> scratch_;
  std::vector<double> scratch_dist_;
  std::vector<double> scratch_rho_;
  std::vector<int> scratch_level_, scratch_order_;
  std::vector<int> order_;
  std::vector<PairDistance> out_;
  std::vector<std::uint8_t> fresh_;          // per pair: recomputed in this query
  std::vector<double> nbest_;
  std::vector<double> lower_, upper_;
  std::uint64_t cycle_ = 1;                  // volumes stamped with it are current (0: never)
  QueryResult result_;
};

}  // namespace kccd
