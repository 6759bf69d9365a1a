// A search for the closest configuration of one body pair inside an interval box, for
// bench_trade: dense random sampling of the box, then coordinate (compass) descent from the best
// samples. Every distance it returns was measured at a configuration inside the box, so it is an
// upper bound on the pair's true smallest distance over the box (the nominal geometry: a joint's
// error bound is not applied). A Checker bound above it would be a proven violation.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "kccd/model.hpp"

namespace kccd::bench {

struct BoxSearchOptions {
  int samples = 192;           ///< random configurations (half at corners, half inside)
  int starts = 4;              ///< descents from the best samples
  int max_evaluations = 1500;  ///< per descent
  double min_step = 1e-6;      ///< stop a coordinate when its step is below this (rad or m)
  std::uint64_t seed = 1;
};

struct BoxSearchResult {
  double distance = 0.0;      ///< SSCH distance at `state` (nominal geometry)
  std::vector<double> state;  ///< inside the box
  int evaluations = 0;
};

class BoxSearch {
 public:
  explicit BoxSearch(const Model& model);

  /// The smallest distance of pair `pair` found inside [lower, upper].
  BoxSearchResult closest(int pair, std::span<const double> lower, std::span<const double> upper,
                          const BoxSearchOptions& options = {});

  /// The SSCH distance of `pair` at one configuration: the distance between points actually on
  /// the two volumes (GJK's upper end), 0 when they overlap.
  double distanceAt(int pair, std::span<const double> state);

 private:
  // The state values that change the pair's distance: joints between each body and the pair's
  // common ancestor frame (joints above it move both bodies rigidly).
  std::vector<int> movingState(int pair) const;
  void descend(int pair, const std::vector<int>& moving, std::span<const double> lower, std::span<const double> upper,
               int max_evaluations, double min_step, std::vector<double>& q, double& best, int& evaluations);

  const Model& model_;
  std::vector<Pose> poses_;
  std::vector<Vec3> a_, b_;
};

}  // namespace kccd::bench
