#include "kccd/explain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "kccd/checker.hpp"
#include "kccd/distance.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/rotation.hpp"

namespace kccd {
namespace {

constexpr double kFullTurn = 2.0 * std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kArmijo = 1e-4;          // sufficient decrease, as a fraction of the predicted one
constexpr int kMaxHalvings = 40;          // backtracking steps before a descent gives up
constexpr double kStepTolerance = 1e-10;  // a step this small (rad or m) ends a descent
constexpr double kRotationStep = 1e-6;    // central-difference step for rotation3d (rad)

// One searched state value and the window it is searched in (inside its interval).
struct Variable {
  int index = 0;
  double lo = 0.0, hi = 0.0;
};

// The window of one state value: its interval, or one full turn inside a wider revolute interval
// starting at the value nearest zero.
Variable window(int index, double lower, double upper, bool revolute) {
  if (!revolute || !(upper - lower > kFullTurn)) return {index, lower, upper};
  const double start = std::clamp(0.0, lower, std::max(lower, upper - kFullTurn));
  return {index, start, std::min(upper, start + kFullTurn)};
}

// Uniform in [0, 1) from 53 random bits (the same on every platform).
double unit(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// A joint of a chain placed at a configuration: its frame before and after its own motion,
// both in the pair's LCA frame.
struct Placed {
  int joint = 0;
  Pose before = Pose::Identity();
  Pose after = Pose::Identity();
};

// The distance of one pair as a function of the state values between its bodies and their LCA:
// forward kinematics along the two chains only, GJK, and the gradient from the witness points.
class PairFunction {
 public:
  PairFunction(const Model& model, int pair) : model_(model), pair_(model.pairs[static_cast<std::size_t>(pair)]) {
    chain(pair_.a, chain_a_);
    chain(pair_.b, chain_b_);
    const Body& a = model.bodies[static_cast<std::size_t>(pair_.a)];
    const Body& b = model.bodies[static_cast<std::size_t>(pair_.b)];
    points_a_.resize(a.points.size());
    points_b_.resize(b.points.size());
  }

  // The state indices the pair depends on, each once, in chain order.
  std::vector<int> stateIndices() const {
    std::vector<int> out;
    for (const std::vector<Placed>* c : {&chain_a_, &chain_b_})
      for (const Placed& p : *c) {
        const Joint& j = model_.joints[static_cast<std::size_t>(p.joint)];
        for (int k = 0; k < j.dof; ++k) out.push_back(j.state_offset + k);
      }
    return out;
  }

  // The distance (rounded up) at `state`; fills `gradient`, one entry per variable (`slot` maps a
  // state index to its variable or -1). +inf (zero gradient) when GJK rejects the placed volumes.
  double evaluate(std::span<const double> state, const std::vector<int>& slot, std::vector<double>& gradient) {
    place(chain_a_, pair_.a, state, points_a_);
    place(chain_b_, pair_.b, state, points_b_);
    const Body& a = model_.bodies[static_cast<std::size_t>(pair_.a)];
    const Body& b = model_.bodies[static_cast<std::size_t>(pair_.b)];
    GjkOptions opt;
    opt.warm_start = have_direction_ ? &direction_ : nullptr;
    const DistanceResult r = distance({points_a_, a.radius}, {points_b_, b.radius}, opt);
    std::fill(gradient.begin(), gradient.end(), 0.0);
    if (r.status == GjkStatus::InvalidInput) return kInf;
    direction_ = r.direction;
    have_direction_ = true;
    witness_a_ = r.witness_a;
    witness_b_ = r.witness_b;
    const double d = std::max(0.0, r.hull_upper - a.radius - b.radius);
    const Vec3 gap = r.witness_a - r.witness_b;
    const double gap_norm = gap.norm();
    if (d > 0.0 && gap_norm > 0.0) {
      const Vec3 n = gap / gap_norm;
      addGradient(chain_a_, state, r.witness_a, n, slot, gradient);
      addGradient(chain_b_, state, r.witness_b, -n, slot, gradient);
    }
    return d;
  }

  // The witness points of the last evaluation, in the LCA frame.
  const Vec3& witnessA() const { return witness_a_; }
  const Vec3& witnessB() const { return witness_b_; }
  int lca() const { return pair_.lca; }

 private:
  // The joints from just below the LCA down to the body's frame, root first.
  void chain(int body, std::vector<Placed>& out) const {
    for (int f = model_.bodies[static_cast<std::size_t>(body)].frame; f != pair_.lca;
         f = model_.joints[static_cast<std::size_t>(f)].parent)
      out.push_back({f, Pose::Identity(), Pose::Identity()});
    std::reverse(out.begin(), out.end());
  }

  // Poses of the chain's joints in the LCA frame and the body's core points there.
  void place(std::vector<Placed>& c, int body, std::span<const double> state, std::vector<Vec3>& points) const {
    Pose pose = Pose::Identity();
    for (Placed& p : c) {
      const Joint& j = model_.joints[static_cast<std::size_t>(p.joint)];
      p.before = pose * j.origin;
      p.after = p.before * jointMotion(j, state.data() + j.state_offset);
      pose = p.after;
    }
    const Body& b = model_.bodies[static_cast<std::size_t>(body)];
    for (std::size_t i = 0; i < points.size(); ++i) points[i] = pose * b.points[i];
  }

  // Adds n . dx/dq for the material point x moving with the chain's last frame.
  void addGradient(const std::vector<Placed>& c, std::span<const double> state, const Vec3& x, const Vec3& n,
                   const std::vector<int>& slot, std::vector<double>& gradient) const {
    for (const Placed& p : c) {
      const Joint& j = model_.joints[static_cast<std::size_t>(p.joint)];
      for (int k = 0; k < j.dof; ++k) {
        const int v = slot[static_cast<std::size_t>(j.state_offset + k)];
        if (v >= 0) gradient[static_cast<std::size_t>(v)] += n.dot(velocity(j, p, state.data() + j.state_offset, k, x));
      }
    }
  }

  // dx/dq_k of a point x (LCA frame) moved by joint j at its state values q.
  static Vec3 velocity(const Joint& j, const Placed& p, const double* q, int k, const Vec3& x) {
    switch (j.type) {
      case JointType::Fixed:
        return Vec3::Zero();
      case JointType::Revolute:
        return (p.before.linear() * j.axis).cross(x - p.before.translation());
      case JointType::Prismatic:
        return p.before.linear() * j.axis;
      case JointType::Translation3d:
        return p.before.linear().col(k);
      case JointType::Rotation3d: {
        // x = before * R(v) * y with y fixed in the joint frame; dR/dv_k by central differences.
        const Eigen::Matrix3d r = p.after.linear();
        const Vec3 v(q[0], q[1], q[2]);
        Vec3 step = Vec3::Zero();
        step[k] = kRotationStep;
        const Eigen::Matrix3d dr =
            (rotationFromVector(v + step) - rotationFromVector(v - step)) / (2.0 * kRotationStep);
        const Vec3 y = r.transpose() * (x - p.after.translation());
        return p.before.linear() * (dr * y);
      }
    }
    return Vec3::Zero();
  }

  const Model& model_;
  const BodyPair& pair_;
  std::vector<Placed> chain_a_, chain_b_;
  std::vector<Vec3> points_a_, points_b_;
  Vec3 direction_ = Vec3::UnitX();
  bool have_direction_ = false;
  Vec3 witness_a_ = Vec3::Zero(), witness_b_ = Vec3::Zero();
};

void checkArguments(const Model& model, int pair, std::span<const double> lower, std::span<const double> upper,
                    const SearchOptions& options) {
  if (pair < 0 || pair >= static_cast<int>(model.pairs.size()))
    throw std::invalid_argument("closestConfiguration: pair " + std::to_string(pair) + " out of range");
  if (static_cast<int>(lower.size()) != model.stateSize() || static_cast<int>(upper.size()) != model.stateSize())
    throw std::invalid_argument("closestConfiguration: the box needs " + std::to_string(model.stateSize()) +
                                " values per end");
  for (std::size_t i = 0; i < lower.size(); ++i) {
    if (!std::isfinite(lower[i]) || !std::isfinite(upper[i]))
      throw std::invalid_argument("closestConfiguration: non-finite interval end at state value " + std::to_string(i));
    if (lower[i] > upper[i])
      throw std::invalid_argument("closestConfiguration: lower above upper at state value " + std::to_string(i));
  }
  if (options.starts < 1 || options.max_steps < 0)
    throw std::invalid_argument("closestConfiguration: starts must be >= 1 and max_steps >= 0");
}

// Multi-start projected gradient descent over the variables' windows.
class Search {
 public:
  Search(const Model& model, int pair, std::span<const double> lower, std::span<const double> upper,
         const SearchOptions& options)
      : f_(model, pair), options_(options), slot_(static_cast<std::size_t>(model.stateSize()), -1) {
    state_.resize(lower.size());
    for (std::size_t i = 0; i < lower.size(); ++i)
      state_[i] = std::clamp(0.5 * lower[i] + 0.5 * upper[i], lower[i], upper[i]);
    for (int s : f_.stateIndices()) {
      if (slot_[static_cast<std::size_t>(s)] >= 0) continue;
      slot_[static_cast<std::size_t>(s)] = static_cast<int>(vars_.size());
      vars_.push_back(
          window(s, lower[static_cast<std::size_t>(s)], upper[static_cast<std::size_t>(s)], isRevolute(model, s)));
    }
    for (const Variable& v : vars_) {
      state_[static_cast<std::size_t>(v.index)] = std::clamp(0.5 * v.lo + 0.5 * v.hi, v.lo, v.hi);
      width_ = std::max(width_, v.hi - v.lo);
    }
    gradient_.assign(vars_.size(), 0.0);
    best_.pair = pair;
    best_.distance = kInf;
    best_.state = state_;
  }

  // Starts in order: the box centre, the corner down the centre's gradient, then a Latin
  // hypercube of random points (every variable's window cut into equal strata, one start each).
  ClosestConfiguration run() {
    std::uint64_t rng = options_.seed;
    const int randoms = std::max(0, options_.starts - 2);
    const std::vector<std::vector<int>> strata = latinHypercube(randoms, rng);
    for (int start = 0; start < options_.starts && best_.distance > options_.stop_below; ++start) {
      if (start == 0) {
        setStart([](const Variable& v, std::size_t) { return 0.5 * v.lo + 0.5 * v.hi; });
      } else if (start == 1) {
        const std::vector<double> g = centre_gradient_;
        setStart([&g](const Variable& v, std::size_t i) { return g[i] < 0.0 ? v.hi : v.lo; });
      } else {
        const auto k = static_cast<std::size_t>(start - 2);
        setStart([&](const Variable& v, std::size_t i) {
          const double u = (strata[i][k] + unit(splitmix(rng))) / randoms;
          return v.lo * (1.0 - u) + v.hi * u;
        });
      }
      descend();
      if (vars_.empty()) break;  // a single configuration
    }
    return best_;
  }

  int lca() const { return f_.lca(); }

 private:
  static bool isRevolute(const Model& model, int state_index) {
    for (const Joint& j : model.joints)
      if (j.dof > 0 && state_index >= j.state_offset && state_index < j.state_offset + j.dof)
        return j.type == JointType::Revolute;
    return false;
  }

  static std::uint64_t splitmix(std::uint64_t& s) {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }

  // Per variable, a random permutation of the strata 0 .. n-1.
  std::vector<std::vector<int>> latinHypercube(int n, std::uint64_t& rng) const {
    std::vector<std::vector<int>> strata(vars_.size(), std::vector<int>(static_cast<std::size_t>(n)));
    for (std::vector<int>& s : strata) {
      for (int k = 0; k < n; ++k) s[static_cast<std::size_t>(k)] = k;
      for (int k = n - 1; k > 0; --k)
        std::swap(s[static_cast<std::size_t>(k)], s[splitmix(rng) % static_cast<std::uint64_t>(k + 1)]);
    }
    return strata;
  }

  template <class F>
  void setStart(F value) {
    for (std::size_t i = 0; i < vars_.size(); ++i)
      state_[static_cast<std::size_t>(vars_[i].index)] = std::clamp(value(vars_[i], i), vars_[i].lo, vars_[i].hi);
  }

  // Evaluates the current state, keeping the best configuration seen.
  double evaluate() {
    const double d = f_.evaluate(state_, slot_, gradient_);
    ++best_.evaluations;
    if (d < best_.distance) {
      best_.distance = d;
      best_.state = state_;
      best_.point_a = f_.witnessA();
      best_.point_b = f_.witnessB();
    }
    return d;
  }

  // One projected gradient descent from state_ with a backtracking line search.
  void descend() {
    double f = evaluate();
    if (centre_gradient_.empty()) centre_gradient_ = gradient_;
    x_.resize(vars_.size());
    for (std::size_t i = 0; i < vars_.size(); ++i) x_[i] = state_[static_cast<std::size_t>(vars_[i].index)];
    double step = -1.0;
    for (int it = 0; it < options_.max_steps && std::isfinite(f) && f > options_.stop_below; ++it) {
      g_ = gradient_;
      double g_max = 0.0;
      for (double gi : g_) g_max = std::max(g_max, std::abs(gi));
      if (!(g_max > 0.0)) return;
      if (step < 0.0) step = std::min(width_, 1e12) / g_max;  // the first step may cross the widest window
      const double before = f;
      if (!lineSearch(f, step)) return;
      if (before - f <= 1e-12 * std::max(1.0, f)) return;
      step *= 2.0;
    }
  }

  // Halves `step` from x_ along -g_ (projected on the windows) until the Armijo condition holds;
  // on success moves x_ there and updates f. False when the step became negligible.
  bool lineSearch(double& f, double& step) {
    for (int h = 0; h < kMaxHalvings; ++h, step *= 0.5) {
      double predicted = 0.0, moved = 0.0;
      for (std::size_t i = 0; i < vars_.size(); ++i) {
        const double xi = g_[i] == 0.0 ? x_[i] : std::clamp(x_[i] - step * g_[i], vars_[i].lo, vars_[i].hi);
        state_[static_cast<std::size_t>(vars_[i].index)] = xi;
        predicted += g_[i] * (xi - x_[i]);
        moved = std::max(moved, std::abs(xi - x_[i]));
      }
      if (moved <= kStepTolerance) return false;
      const double fy = evaluate();
      if (fy <= f + kArmijo * predicted) {
        f = fy;
        for (std::size_t i = 0; i < vars_.size(); ++i) x_[i] = state_[static_cast<std::size_t>(vars_[i].index)];
        return true;
      }
    }
    return false;
  }

  PairFunction f_;
  SearchOptions options_;
  std::vector<int> slot_;  // per state index: its variable, or -1
  std::vector<Variable> vars_;
  std::vector<double> state_;     // the full state being evaluated
  std::vector<double> gradient_;  // per variable, at the last evaluation
  std::vector<double> centre_gradient_;
  std::vector<double> x_, g_;  // the descent's point and its gradient (per variable)
  double width_ = 0.0;         // widest window
  ClosestConfiguration best_;  // the best configuration seen (points in the LCA frame)
};

}  // namespace

ClosestConfiguration closestConfiguration(const Model& model, int pair, std::span<const double> lower,
                                          std::span<const double> upper, const SearchOptions& options) {
  checkArguments(model, pair, lower, upper, options);
  Search search(model, pair, lower, upper, options);
  ClosestConfiguration out = search.run();
  std::vector<Pose> poses(model.joints.size());
  if (framePoses(model, out.state, poses)) {
    const Pose& lca = framePose(poses, search.lca());
    out.point_a = lca * out.point_a;
    out.point_b = lca * out.point_b;
  }
  return out;
}

const char* toString(PairVerdict verdict) {
  switch (verdict) {
    case PairVerdict::Clear:
      return "clear";
    case PairVerdict::Possible:
      return "possible";
    case PairVerdict::Real:
      return "real";
  }
  return "possible";
}

PairVerdict verdict(double bound, double found, double margin) noexcept {
  if (bound > margin) return PairVerdict::Clear;
  if (found <= margin) return PairVerdict::Real;
  return PairVerdict::Possible;
}

std::vector<PairExplanation> explainFlagged(const Model& model, std::span<const double> lower,
                                            std::span<const double> upper, double margin,
                                            const SearchOptions& options) {
  Checker checker(model);
  QueryOptions q;
  q.type = QueryType::Distances;
  q.margin = margin;
  const QueryResult& r = checker.query(lower, upper, q);
  if (r.status != Status::Ok)
    throw std::invalid_argument(std::string("explainFlagged: query status ") + toString(r.status));
  std::vector<PairExplanation> out;
  for (const PairDistance& pd : r.pairs)
    if (pd.distance <= r.margin) out.push_back({pd.pair, pd.distance, {}, PairVerdict::Possible});
  std::sort(out.begin(), out.end(), [](const PairExplanation& x, const PairExplanation& y) { return x.pair < y.pair; });
  for (PairExplanation& e : out) {
    e.closest = closestConfiguration(model, e.pair, lower, upper, options);
    e.verdict = verdict(e.bound, e.closest.distance, r.margin);
  }
  return out;
}

}  // namespace kccd
