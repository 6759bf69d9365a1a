// The motion of a synthetic recording: a smooth trajectory within the joint limits with
// near-collisions and (optionally) one real collision, found by a seeded search, logged as a state
// log at its own rate and clock, and checked frame by frame at the logged states.
#pragma once

#include "kccd/input_error.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "kccd/checker.hpp"
#include "kccd/model.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// A smooth bump of the trajectory towards a goal configuration.
struct TrajectoryEvent {
  enum Kind { Near, Collision } kind = Near;
  double time = 0.0, half_width = 0.5;
  double beta = 0.0;     ///< the blend towards the goal at the top of the bump (0 ... 1)
  double plateau = 0.0;  ///< fraction of the half width held at the full blend
  std::vector<double> goal;
  double min_distance = 0.0;  ///< over the log samples in its window
};

/// Per state value a centre plus two sines, blended towards goal configurations by smooth bumps
/// (events). Everything stays within the joint limits (convex blends of in-limit values).
struct Trajectory {
  std::vector<double> centre;
  std::vector<std::array<double, 6>> waves;  ///< amplitude, omega, phase (x2)
  std::vector<TrajectoryEvent> events;

  /// State and velocity at time t (position, velocity and acceleration continuous).
  void at(double t, std::span<double> q, std::span<double> qd) const;
};

/// The smallest distance bound of the model at one configuration: +inf without pairs, -1 for an
/// unsafe status. Every configuration on its own (a fresh table): the answer does not depend on
/// the order of queries.
class DistanceProbe {
 public:
  explicit DistanceProbe(const Model& m) : checker_(m) {}
  /// With `pair`, also the index of the pair at the smallest bound (-1 when none).
  double operator()(std::span<const double> q, int* pair = nullptr);

 private:
  Checker checker_;
};

/// What the trajectory search needs of the options.
struct TrajectorySearch {
  std::string model;     ///< the model as named in errors
  double seconds = 5.0;  ///< recording length: places the events
  double fps = 25.0;     ///< frames must show the collision
  std::uint64_t seed = 1;
  bool collision = true;  ///< false: near-collisions only
  FieldSpelling spell;    ///< how hints name the options (SynthOptions::spell)
};

/// Searches a trajectory over log times t0 ... t1 sampled every dt. Throws SynthError when none is
/// found (or the model checks no pair and a collision is wanted).
Trajectory searchTrajectory(const Model& m, const TrajectorySearch& search, double t0, double t1, double dt);

/// The state log of `tr` as CSV text: time, every state value, every velocity (.vel); log time
/// tau runs from 0 at `rate` and covers every frame time in [0, duration] plus `offset`, a few
/// samples beyond; the state at log time tau is the trajectory's at tau - offset.
std::string stateLogText(const Model& m, const Trajectory& tr, double offset, double rate, double duration);

/// The recording's motion as the frames show it.
struct SynthMotion {
  Trajectory trajectory;
  std::string log_text;  ///< states.csv
  StateLog log;          ///< log_text parsed
  int frames = 0;
  std::vector<std::vector<double>> states;    ///< per frame: the logged state at its log time
  std::vector<double> min_distance;           ///< per frame (DistanceProbe)
  std::vector<int> closest;                   ///< per frame: the pair at the smallest bound, or -1
  std::vector<std::array<int, 2>> intervals;  ///< runs of colliding frames (first, last)
};

/// The motion of a recording of `frames` frames at `fps` with its log at `log_rate`, log clock =
/// video clock + `time_offset`: trajectories are searched (from `search.seed`, then from other
/// streams, up to 8) until the frames at their logged states have exactly one collision interval
/// (none without search.collision). Throws SynthError when none does.
SynthMotion searchMotion(const Model& m, const TrajectorySearch& search, int frames, double log_rate,
                         double time_offset);

}  // namespace kccd::overlay
