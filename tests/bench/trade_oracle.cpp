#include "trade_oracle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

#include "kccd/distance.hpp"
#include "kccd/kinematics.hpp"

namespace kccd::bench {

BoxSearch::BoxSearch(const Model& model) : model_(model), poses_(model.joints.size()) {}

double BoxSearch::distanceAt(int pair, std::span<const double> state) {
  if (!framePoses(model_, state, poses_)) return 0.0;
  const BodyPair& p = model_.pairs[static_cast<std::size_t>(pair)];
  const Body& a = model_.bodies[static_cast<std::size_t>(p.a)];
  const Body& b = model_.bodies[static_cast<std::size_t>(p.b)];
  const Pose& pa = framePose(poses_, a.frame);
  const Pose& pb = framePose(poses_, b.frame);
  a_.clear();
  b_.clear();
  for (const Vec3& v : a.points) a_.push_back(pa * v);
  for (const Vec3& v : b.points) b_.push_back(pb * v);
  const DistanceResult r = distance({a_, a.radius}, {b_, b.radius});
  if (r.status == GjkStatus::Overlap || r.status == GjkStatus::InvalidInput) return 0.0;
  return std::max(0.0, r.hull_upper - a.radius - b.radius);
}

std::vector<int> BoxSearch::movingState(int pair) const {
  const BodyPair& p = model_.pairs[static_cast<std::size_t>(pair)];
  std::vector<int> out;
  for (int body : {p.a, p.b})
    for (int f = model_.bodies[static_cast<std::size_t>(body)].frame; f != kWorld && f != p.lca;
         f = model_.joints[static_cast<std::size_t>(f)].parent) {
      const Joint& j = model_.joints[static_cast<std::size_t>(f)];
      for (int k = 0; k < j.dof; ++k) out.push_back(j.state_offset + k);
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Compass search: per moving coordinate try a step up and down, keep an improvement (and double
// the step), otherwise halve it; until every step is below min_step or the evaluations run out.
void BoxSearch::descend(int pair, const std::vector<int>& moving, std::span<const double> lower,
                        std::span<const double> upper, int max_evaluations, double min_step, std::vector<double>& q,
                        double& best, int& evaluations) {
  std::vector<double> step(moving.size());
  for (std::size_t i = 0; i < moving.size(); ++i) {
    const auto s = static_cast<std::size_t>(moving[i]);
    step[i] = 0.25 * (upper[s] - lower[s]);
  }
  int used = 0;
  bool active = true;
  while (active && used < max_evaluations && best > 0.0) {
    active = false;
    for (std::size_t i = 0; i < moving.size() && used < max_evaluations; ++i) {
      if (step[i] < min_step) continue;
      active = true;
      const auto s = static_cast<std::size_t>(moving[i]);
      const double keep = q[s];
      bool improved = false;
      for (double sign : {1.0, -1.0}) {
        q[s] = std::clamp(keep + sign * step[i], lower[s], upper[s]);
        if (q[s] == keep) continue;
        const double d = distanceAt(pair, q);
        ++used;
        if (d < best) {
          best = d;
          improved = true;
          break;
        }
      }
      if (improved) {
        step[i] = std::min(2.0 * step[i], upper[s] - lower[s]);
      } else {
        q[s] = keep;
        step[i] *= 0.5;
      }
    }
  }
  evaluations += used;
}

BoxSearchResult BoxSearch::closest(int pair, std::span<const double> lower, std::span<const double> upper,
                                   const BoxSearchOptions& options) {
  const std::vector<int> moving = movingState(pair);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> q(lower.size());
  for (std::size_t s = 0; s < q.size(); ++s) q[s] = 0.5 * (lower[s] + upper[s]);
  BoxSearchResult result;

  // Samples: the centre, then alternately a random corner and a random inside point.
  std::vector<std::pair<double, std::vector<double>>> samples;
  for (int i = 0; i < options.samples; ++i) {
    if (i > 0)
      for (int s : moving) {
        const auto k = static_cast<std::size_t>(s);
        const double t = i % 2 == 1 ? (u(rng) < 0.5 ? 0.0 : 1.0) : u(rng);
        q[k] = lower[k] + t * (upper[k] - lower[k]);
      }
    samples.emplace_back(distanceAt(pair, q), q);
    ++result.evaluations;
  }
  const auto starts = std::min<std::size_t>(static_cast<std::size_t>(options.starts), samples.size());
  std::partial_sort(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(starts), samples.end(),
                    [](const auto& x, const auto& y) { return x.first < y.first; });

  result.distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < starts; ++i) {
    auto& [d, start] = samples[i];
    descend(pair, moving, lower, upper, options.max_evaluations, options.min_step, start, d, result.evaluations);
    if (d < result.distance) {
      result.distance = d;
      result.state = start;
    }
  }
  return result;
}

}  // namespace kccd::bench
