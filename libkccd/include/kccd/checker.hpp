// The mutable side of KCCD: a Checker owns every buffer a query needs. After construction a
// query never allocates and never throws; any status other than Ok means "unsafe, stop".
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "kccd/model.hpp"
#include "kccd/query.hpp"
#include "kccd/ssch.hpp"

namespace kccd::detail {
struct JointMaps;
struct RevoluteTrig;
struct ChainLevel;
struct ChainEntry;
struct ChainView;
struct SupportCells;
struct PointSummary;
}  // namespace kccd::detail

namespace kccd {

struct DistanceResult;
struct GjkOptions;

/// Holds the per-cycle swept volumes and the any-time table of pair bounds. Bounds are reused
/// across queries while they stay valid lower bounds for the new interval box.
class Checker {
 public:
  /// Preallocates everything for `model` (which must outlive the Checker).
  explicit Checker(const Model& model);
  ~Checker();
  Checker(const Checker&) = delete;
  Checker& operator=(const Checker&) = delete;

  /// Answers one query for the interval box [lower, upper] (both of length stateSize()).
  /// Never allocates, never throws.
  const QueryResult& query(std::span<const double> lower, std::span<const double> upper,
                           const QueryOptions& options = {}) noexcept;

  /// Forgets every stored bound and warm start: the next query's answer is exactly a new
  /// Checker's (bit for bit), whatever was asked before.
  void reset() noexcept;

  const Model& model() const { return model_; }

  /// The swept volume of `body` expressed in frame `frame` (an ancestor of the body's frame or
  /// its own) for the box of the last query. For inspection and rendering; valid until the next
  /// query. Returns an empty view when the frame is not on the body's path.
  SschView sweptVolume(int body, int frame) noexcept;

 private:
  struct Volume {
    int offset = 0;  // into points_
    int capacity = 0;
    int count = 0;
    double radius = 0.0;
    Sphere bound;         // around the points (valid with stamp)
    Sphere swept_sphere;  // swept cheaply from the level below (valid with sphere_stamp)
    std::uint64_t stamp = 0;
    std::uint64_t sphere_stamp = 0;
    // The body's points moved rigidly, every one kept, the radius grown by rounding guards only
    // (every joint below at a single value): the exact stage's chains are these points too.
    bool exact = false;
    // Posed: a rigid volume kept as the map x -> lin x + off of the body's points (the levels'
    // rigid maps composed), its points written into the arena only when asked for (written:
    // the cycle they were written in); its radius covers the map's rounding and a support
    // chosen in the body's frame. start and scale are GJK's start point and rounding scale.
    bool posed = false;
    bool own = false;  // level 0: the body's own points in its frame
    int body = 0;
    mutable std::uint64_t written = 0;
    Eigen::Matrix3d lin = Eigen::Matrix3d::Identity();
    Vec3 off = Vec3::Zero();
    double lin_error = 0.0, off_error = 0.0;  // bounds on |lin - exact| (operator norm), |off - exact|
    Vec3 start = Vec3::Zero();
    double scale = 0.0;
  };
  struct Entry {  // the any-time table
    bool valid = false;
    double bound = 0.0;              // lower bound for the box stored in box_
    double current = 0.0;            // bound valid for this query's box
    bool gjk = false;                // the stored bound came from GJK (witness points valid)
    Vec3 direction = Vec3::UnitX();  // GJK's last direction for the pair (its warm start)
    double moved = 0.0;              // how far the pair's points may have moved since the stored bound (carryBounds)
    Vec3 witness_a = Vec3::Zero(), witness_b = Vec3::Zero();
  };

  // The interval box of one query: the lower and upper end of every state value.
  struct Box {
    std::span<const double> lower, upper;
  };
  // When refinement must stop: a deadline (when timed) and a number of recomputed pairs.
  struct Budget {
    bool timed = false;
    std::chrono::steady_clock::time_point deadline;
    int max_pairs = -1;  // < 0: unlimited
  };

  // Construction, in order: where every volume lives, then how far each state value moves a pair.
  void layoutVolumes();
  void computeReach();

  // A query, in order: validate the box, carry stored bounds over to it, order the candidate
  // pairs, refine them per query type, publish the answer.
  bool validate(std::span<const double> lower, std::span<const double> upper) noexcept;
  void carryBounds(Box box) noexcept;
  int orderCandidates(QueryType type, double margin) noexcept;
  int refineCollision(int candidates, double margin, const Budget& budget, Box box) noexcept;
  void refineClosest(int candidates, double margin, const Budget& budget, Box box) noexcept;
  void refineNClosest(int n, const Budget& budget, Box box) noexcept;
  void refineDistances(const Budget& budget, Box box) noexcept;
  void publishAnswer(QueryType type, double margin, int hit, int n_wanted) noexcept;

  // Helpers of the phases.
  bool expired(const Budget& budget) noexcept;
  void refine(int pair, double stop_above, Box box) noexcept;
  bool splitPair(int pair, Box box, double& bound) noexcept;
  double posedDistance(int pair, const double* q, double* grad) noexcept;
  const Joint& levelJoint(int body, int level) const noexcept;
  double refresh(int pair, double stop_above, Box box) noexcept;
  bool exactStage(int pair, double stop_above, Box box, double& bound) noexcept;
  const detail::JointMaps* jointMaps(int joint, Box box) noexcept;
  const detail::RevoluteTrig& revoluteTrig(int joint, Box box) noexcept;
  bool chain(int body, int level, int variant, Box box, detail::ChainView& out) noexcept;
  void report(int pair, PairDistance& out) const noexcept;
  const Volume* volume(int body, int level, Box box) noexcept;
  bool pose(Volume& v, const Volume& below, bool first, const Joint& joint, const double* value,
            const detail::RevoluteTrig& trig) noexcept;
  SschView written(const Volume& v) noexcept;
  DistanceResult pairDistance(const Volume& a, const Volume& b, const GjkOptions& options) noexcept;
  SschView view(const Volume& v) const noexcept;
  const Sphere* sphere(int body, int level, Box box) noexcept;

  const Model& model_;
  std::vector<Vec3> points_;      // arena of every volume's points
  std::vector<int> level_begin_;  // per body: index of its level-0 volume in volumes_
  std::vector<int> levels_;       // per body: number of levels
  std::vector<Volume> volumes_;
  std::vector<int> path_;         // per body and level: the joint swept from that level
  std::vector<int> pair_level_;   // per pair: level of a, level of b
  std::vector<int> reach_begin_;  // per pair: its range in reach_state_ / reach_
  std::vector<int> reach_state_;  // state values that move the pair
  std::vector<double> reach_;     // how far they move its core points per unit change
  std::vector<Entry> table_;
  std::vector<double> box_;  // per reach entry: the stored bound's lower, upper
  std::vector<Vec3> scratch_;
  std::vector<double> scratch_dist_;
  std::vector<Vec3> scratch_alt_;  // the other cover of a sweep
  std::vector<int> scratch_order_;
  std::vector<detail::RevoluteTrig> trig_;  // per joint: its last interval's trigonometry
  // The exact stage: per joint its vertex maps for this query, per body and level the chain
  // level (variant 0: chords only; 1: each joint's own mode), and the search's scratch.
  std::vector<detail::JointMaps> joint_maps_;
  std::vector<std::uint64_t> joint_maps_stamp_;
  std::vector<detail::ChainLevel> chain_[2];
  std::vector<std::uint64_t> chain_stamp_[2];
  std::vector<double> chain_radius_[2];             // per body and level: radius of the chain up to it
  std::vector<std::uint8_t> chain_tangent_[2];      // per body and level: some level uses apexes
  std::vector<Sphere> base_sphere_;                 // per body: sphere around its core points
  std::vector<double> base_norm_;                   // per body: the largest |core point|
  std::vector<detail::PointSummary> base_summary_;  // per body: its core points' scale, centroid
  std::vector<detail::SupportCells> base_cells_;    // per body: its support candidates by direction
  std::vector<Vec3> base_box_;                      // per body: centre and half-sizes of their box
  std::vector<detail::ChainEntry> chain_stack_;
  std::vector<int> chain_choice_, chain_best_;
  double exact_below_ = 0.0;
  bool tight_volumes_ = false;
  std::vector<int> order_;
  std::vector<PairDistance> out_;
  std::vector<std::uint8_t> fresh_;  // per pair: recomputed in this query
  std::vector<double> nbest_;
  std::vector<double> lower_, upper_;  // the box of the last query (for sweptVolume())
  // Splitting a pair's box (splitPair): per sub-box its lower and upper ends; per side and level
  // the extent of the volume below the level's joint.
  int splits_ = 0;           // sub-boxes per split pair this query (0: none)
  double split_gap_ = 0.0;   // QueryOptions::exact_split_gap, resolved
  bool in_sub_box_ = false;  // the exact stage is refining a sub-box of a split
  std::vector<double> split_box_;
  std::vector<double> split_extent_;
  std::vector<double> centre_;
  std::vector<Vec3> centre_points_;  // the pair's two bodies posed at one configuration
  std::vector<int> split_order_;     // sub-boxes in the order they are refined
  std::vector<double> split_key_;    // per sub-box: the posed distance at its centre
  std::vector<double> split_grad_;   // per state value: the posed distance's derivative
  std::vector<Pose> split_frames_;   // per side and level: the joint frame, posed
  std::uint64_t stamps_ = 1;         // the last stamp handed out
  std::uint64_t cycle_ = 1;          // volumes stamped with it are current (0: never)
  // Swept spheres, joint maps and chains stamped with it are current: the query's box, or a
  // sub-box of splitPair (which takes a stamp of its own and leaves a fresh one for the box).
  std::uint64_t geo_cycle_ = 1;
  QueryResult result_;
};

}  // namespace kccd
