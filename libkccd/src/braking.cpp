#include "kccd/braking.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "kccd/input_error.hpp"

namespace kccd {

std::optional<std::pair<std::string, std::string>> brakingRangeProblem(const BrakingParams& b) {
  const std::tuple<const char*, double, double, double> ranges[] = {{"latency", b.latency, 0, 1e3},
                                                                    {"deceleration", b.deceleration, 1e-9, 1e9},
                                                                    {"max_acceleration", b.max_acceleration, 0, 1e9},
                                                                    {"position_error", b.position_error, 0, 1e3},
                                                                    {"velocity_error", b.velocity_error, 0, 1e6}};
  for (const auto& [field, value, lo, hi] : ranges)
    if (const std::optional<std::string> wrong = rangeProblem(value, lo, hi)) return std::pair{field, *wrong};
  return std::nullopt;
}

double stoppingDistance(double u, const BrakingParams& p) noexcept {
  const double t = p.latency;
  const double after_latency = std::max(0.0, u + p.max_acceleration * t);
  return std::max(0.0,
                  u * t + 0.5 * p.max_acceleration * t * t + after_latency * after_latency / (2.0 * p.deceleration));
}

void brakingInterval(double q, double v, const BrakingParams& p, double& lower, double& upper) noexcept {
  upper = q + p.position_error + stoppingDistance(v + p.velocity_error, p);
  lower = q - p.position_error - stoppingDistance(-v + p.velocity_error, p);
}

bool brakingIntervals(const Model& model, std::span<const double> q, std::span<const double> v,
                      std::span<const BrakingParams> params, std::span<double> lower,
                      std::span<double> upper) noexcept {
  const std::size_t n = static_cast<std::size_t>(model.stateSize());
  if (q.size() != n || v.size() != n || params.size() != n || lower.size() != n || upper.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const BrakingParams& p = params[i];
    const bool ok = std::isfinite(q[i]) && std::isfinite(v[i]) && std::isfinite(p.position_error) &&
                    std::isfinite(p.velocity_error) && std::isfinite(p.latency) && std::isfinite(p.max_acceleration) &&
                    std::isfinite(p.deceleration) && p.deceleration > 0.0 && p.position_error >= 0.0 &&
                    p.velocity_error >= 0.0 && p.latency >= 0.0 && p.max_acceleration >= 0.0;
    if (!ok) return false;
  }
  for (const Joint& j : model.joints) {
    for (int k = 0; k < j.dof; ++k) {
      const std::size_t i = static_cast<std::size_t>(j.state_offset + k);
      double lo = 0.0, hi = 0.0;
      brakingInterval(q[i], v[i], params[i], lo, hi);
      if (j.limits) {
        lo = std::clamp(lo, (*j.limits)[0], (*j.limits)[1]);
        hi = std::clamp(hi, (*j.limits)[0], (*j.limits)[1]);
      }
      lower[i] = lo;
      upper[i] = hi;
    }
  }
  return true;
}

}  // namespace kccd
