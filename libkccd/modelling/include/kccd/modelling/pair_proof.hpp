// Which body pairs can never come within the safety margin over the joint limits, proven with
// the engine's own conservative sweeps (branch and bound on the joint box), which adjacent
// pairs always touch, which are rigidly attached, and the ignore list that follows.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "kccd/model.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::modelling {

enum class Verdict {
  Never,           ///< proven: over the whole joint range the lower bound stays above the margin
  AlwaysTouching,  ///< proven: adjacent bodies within the margin at every configuration
  Meets,           ///< a configuration was found where they come within the margin
  Undecided,       ///< the box budget ran out before a proof or a witness
  Unbounded,       ///< a joint between them has no limits (prismatic, translation3d)
};
const char* toString(Verdict verdict);

/// How two bodies in different frames are joined, along the path of joints between them (a
/// frame stands for the link it carries).
enum class Connection {
  Rigid,     ///< only fixed joints between them: one constant distance
  Adjacent,  ///< one moving joint, and no body on a link between them (links without geometry
             ///< merged, as MoveIt's adjacency rule does)
  Distant,   ///< more than one moving joint, or a body in between
};
Connection connection(const Model& model, int body_a, int body_b);

struct PairReport {
  int a = 0, b = 0;  ///< body indices, a < b
  int lca = kWorld;
  Verdict verdict = Verdict::Undecided;
  bool adjacent = false;          ///< Connection::Adjacent
  bool rigid = false;             ///< Connection::Rigid: decided exactly (Never or AlwaysTouching)
  bool checked = false;           ///< currently in Model::pairs
  double bound = 0.0;             ///< Never: smallest lower bound over the covering boxes; rigid: the
                                  ///< constant distance (a lower bound, within 1e-9 relative)
  int boxes = 0;                  ///< boxes queried
  std::vector<double> witness;    ///< Meets: a state within the limits where they meet
  double witness_distance = 0.0;  ///< Meets: distance bound at the witness state
};

struct ProofOptions {
  double margin = -1.0;  ///< < 0: the model's safety margin
  int max_boxes = 2000;  ///< per pair
  std::function<void(double)> progress;
};

/// The range every state value is proven over: limits, a full turn for revolute joints without
/// limits, [-pi, pi]^3 for rotation3d (all orientations); prismatic without limits and
/// translation3d are unbounded (NaN).
std::vector<std::array<double, 2>> jointRanges(const Model& model);

/// Analyses every pair of bodies in different frames (checked or not).
std::vector<PairReport> provePairs(const Model& model, const ProofOptions& options = {});

struct IgnoreOptions {
  bool keep_adjacent = false;  ///< check adjacent pairs (MoveIt's rule not applied)
  /// Bodies in the world frame are a link (a URDF's root link: kccd import), adjacent to the
  /// bodies one moving joint away. Otherwise they are obstacles (a table, a post) and the rule
  /// never ignores a pair with one of them; adjacent entries already in the file stay.
  bool world_is_link = false;
};

/// An ignore list and the model's entries it no longer carries.
struct IgnorePlan {
  std::vector<IgnoreEntry> ignore;   ///< the new `pairs: ignore` list, each entry with its reason
  std::vector<IgnoreEntry> dropped;  ///< old entries whose reason no longer holds (checked again)
};

/// The `pairs: ignore` list without proofs: the model's own user and SRDF entries (their reason
/// kept), rigid pairs, adjacent pairs (unless keep_adjacent), then the model's proof entries
/// (never, always_touching) as they are. Each pair once, in that order of reasons.
IgnorePlan structuralIgnores(const Model& model, const IgnoreOptions& options = {});

/// The `pairs: ignore` list the proofs justify: the model's user and SRDF entries, rigid pairs,
/// pairs proven never within the margin or always touching, adjacent pairs (unless
/// keep_adjacent). A model entry whose reason is a proof or a rule that no longer holds is dropped.
IgnorePlan ignoreList(const Model& model, const std::vector<PairReport>& reports, const IgnoreOptions& options = {});

/// Why the model does not check the pair of bodies `a`, `b` now: its `pairs: ignore` reason
/// (toString), or "not_included" when a model with `check: none` does not include it.
std::string currentIgnoreReason(const Model& model, int a, int b);

/// The reason `plan` ignores the pair of bodies `a`, `b` for (toString), or "" when it checks it.
std::string plannedIgnoreReason(const IgnorePlan& plan, const Model& model, int a, int b);

/// What a pair's verdict says about ignoring it, in words ("proven in 12 boxes: safe to ignore").
std::string verdictNote(const PairReport& report);

/// How many pairs have each verdict (rigid pairs counted as rigid only), and how many are rigid or
/// adjacent.
struct VerdictCounts {
  int never = 0, always_touching = 0, meets = 0, undecided = 0, unbounded = 0;
  int rigid = 0, adjacent = 0;
};
/// The counts of `reports`.
VerdictCounts countVerdicts(const std::vector<PairReport>& reports);

}  // namespace kccd::modelling
