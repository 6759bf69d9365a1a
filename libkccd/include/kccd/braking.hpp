// Braking intervals (docs/algorithms.md section 8): where each joint can stop if braking starts now.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <utility>

#include "kccd/model.hpp"

namespace kccd {

/// Per-joint-value braking parameters (SI units: m or rad, per s, per s^2).
struct BrakingParams {
  double position_error = 0.0;    ///< e_q: bound on the position measurement error
  double velocity_error = 0.0;    ///< e_v: bound on the velocity measurement error
  double latency = 0.0;           ///< t_l: one full cycle plus delays, seconds
  double max_acceleration = 0.0;  ///< a_acc: worst-case acceleration during the latency
  double deceleration = 1.0;      ///< a_brk: guaranteed braking deceleration (> 0)
};

/// The first value of `params` outside the ranges every front end accepts (latency 0 ... 1e3 s,
/// deceleration 1e-9 ... 1e9, max_acceleration 0 ... 1e9, position_error 0 ... 1e3,
/// velocity_error 0 ... 1e6): its field ("latency", ...) and rangeProblem's wording; none when all fit.
std::optional<std::pair<std::string, std::string>> brakingRangeProblem(const BrakingParams& params);

/// Distance travelled in the positive direction before standing still, starting at speed u:
/// S(u) = max(0, u t_l + a_acc t_l^2 / 2 + max(0, u + a_acc t_l)^2 / (2 a_brk)).
double stoppingDistance(double speed, const BrakingParams& params) noexcept;

/// Interval [lower, upper] covering every stop of one value at position q, velocity v.
void brakingInterval(double q, double v, const BrakingParams& params, double& lower, double& upper) noexcept;

/// Fills lower/upper (length model.stateSize()) from positions and velocities, one parameter set
/// per state value, clamped to the joint limits where the model has them. Returns false (and
/// leaves the output untouched) on wrong lengths, non-finite input or a deceleration <= 0.
bool brakingIntervals(const Model& model, std::span<const double> q, std::span<const double> v,
                      std::span<const BrakingParams> params, std::span<double> lower, std::span<double> upper) noexcept;

}  // namespace kccd
