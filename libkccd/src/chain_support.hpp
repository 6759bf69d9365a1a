// The exact stage: a body's swept volume through the joints up to an ancestor frame, kept as the
// core points under every combination of the joints' vertex maps (no point budget, nothing
// dropped), and its support function by branch and bound. Internal.
#pragma once

#include <cstdint>
#include <span>

#include "gjk_core.hpp"
#include "kccd/ssch.hpp"
#include "sweep.hpp"

namespace kccd::detail {

/// One level of a chain: the maps of the joint swept there (the first `count` of them), the radius
/// the cover adds at this level, and a sphere containing the core set after this level.
struct ChainLevel {
  const JointMaps* maps = nullptr;
  int count = 0;
  double growth = 0.0;
  Sphere core;
  double max_scale = 1.0;        ///< largest operator norm among the maps used
  bool rotation_apexes = false;  ///< the maps include a rotation3d joint's apexes
  /// How far the core set may lie beyond the true swept core (apexes reach past their arcs).
  double overshoot = 0.0;
  /// A box around the core set (the images of the box below), often tighter than `core`.
  bool has_box = false;
  Vec3 box_centre = Vec3::Zero();
  Vec3 box_half = Vec3::Zero();
};

/// The next level of a chain whose core set lies in `below` (the previous level's core sphere),
/// covering the joint with its chord maps only (`tangent` false) or with chords and apexes.
/// Growths use `swept`, the swept sphere of the level below (as the point volumes do), which holds
/// the core set when no level below used apexes (`below_in_swept`); otherwise `below` counts too.
/// `below_overshoot` is the level below's overshoot (0 for the body itself); the box below holds
/// the core set below.
ChainLevel chainLevel(const JointMaps& maps, bool tangent, const Sphere& below, const Sphere& swept,
                      bool below_in_swept, double below_overshoot, const Vec3& below_box_centre,
                      const Vec3& below_box_half) noexcept;

/// A body swept through levels[0..n): core points in the body frame, their sphere, the levels
/// (levels[0] is the joint nearest the body) and the radius of the whole volume.
struct ChainView {
  std::span<const Vec3> points;
  Sphere base;
  std::span<const ChainLevel> levels;
  double radius = 0.0;
};

/// Scratch space for chainSupport(), sized by chainWorkSize() for the longest chain.
struct ChainEntry {
  Vec3 row;
  double offset;
  double bound;
  int level;
  int choice;
};
struct ChainWork {
  ChainEntry* stack;
  int* choice;
  int* best_choice;   ///< the best leaf's map per level, kept for the next call
  bool warm = false;  ///< best_choice holds a leaf of this chain: start from it
};
int chainStackSize(int levels) noexcept;

/// The support of the chain's core set in direction `dir` (any length): the best point found and
/// the slack by which the true support value may exceed its value along dir / |dir| (0 when the
/// search completed, up to rounding). The search stops after `max_nodes` nodes with a valid slack.
/// A warm `work` starts from its last best leaf (successive GJK directions differ little), which
/// prunes most of the tree at once; `work` is left warm. Branches that cannot beat the best leaf by
/// more than `tolerance` (metres; negative: 1e-5 of the chain's extent) are not explored, their
/// excess counted in the slack. `nodes` (if not null) accumulates the nodes visited.
SupportHit chainSupport(const ChainView& chain, const Vec3& dir, ChainWork& work, int max_nodes,
                        double tolerance = -1.0, long* nodes = nullptr) noexcept;

/// A bound on |x| for every core point x of the chain (for rounding guards).
double chainExtent(const ChainView& chain) noexcept;

}  // namespace kccd::detail
