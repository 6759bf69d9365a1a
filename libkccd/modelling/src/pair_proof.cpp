#include "kccd/modelling/pair_proof.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>

#include "kccd/checker.hpp"
#include "kccd/distance.hpp"

namespace kccd::modelling {
namespace {

constexpr double kPi = std::numbers::pi;

// Joints between `frame` and its ancestor `top` (exclusive).
std::vector<int> jointsBetween(const Model& m, int frame, int top) {
  std::vector<int> out;
  for (int f = frame; f != top && f != kWorld; f = m.joints[f].parent) out.push_back(f);
  return out;
}

// An upper bound on the distance between SSCHs (0 when they overlap).
double distanceUpper(const SschView& a, const SschView& b) {
  const DistanceResult d = distance(a, b);
  return std::max(0.0, d.hull_upper - a.radius - b.radius);
}

// Adjacent through a revolute joint: points on its axis are fixed in both frames. If one of
// them lies within the margin of both bodies, the bodies are within the margin at every angle.
bool sharesAxisPoint(const Model& m, Checker& checker, int parent_body, int child_body, double margin) {
  const Joint& j = m.joints[m.bodies[child_body].frame];
  const SschView child = checker.sweptVolume(child_body, m.bodies[child_body].frame);
  const SschView parent = checker.sweptVolume(parent_body, j.parent);
  if (child.points.empty() || parent.points.empty()) return false;
  double extent = child.radius + parent.radius;
  for (const Vec3& p : child.points) extent = std::max(extent, p.norm() + child.radius);
  auto cost = [&](double t) {
    const Vec3 x = t * j.axis;
    const Vec3 y = j.origin * x;
    return distanceUpper(SschView{std::span<const Vec3>(&x, 1), 0.0}, child) +
           distanceUpper(SschView{std::span<const Vec3>(&y, 1), 0.0}, parent);
  };
  double best_t = 0.0, best = cost(0.0);
  for (int i = -200; i <= 200; ++i) {
    const double t = extent * i / 200.0, v = cost(t);
    if (v < best) best = v, best_t = t;
  }
  double lo = best_t - extent / 200.0, hi = best_t + extent / 200.0;  // the cost is convex in t
  for (int i = 0; i < 60 && best > margin; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    const double c1 = cost(m1), c2 = cost(m2);
    best = std::min({best, c1, c2});
    (c1 < c2 ? hi : lo) = c1 < c2 ? m2 : m1;
  }
  return best <= margin;
}

}  // namespace

const char* toString(Verdict v) {
  switch (v) {
    case Verdict::Never: return "never";
    case Verdict::AlwaysTouching: return "always_touching";
    case Verdict::Meets: return "meets";
    case Verdict::Undecided: return "undecided";
    case Verdict::Unbounded: return "unbounded";
  }
  return "?";
}

std::vector<std::array<double, 2>> jointRanges(const Model& m) {
  std::vector<std::array<double, 2>> r(m.stateSize());
  const double nan = std::nan("");
  for (const Joint& j : m.joints) {
    for (int k = 0; k < j.dof; ++k) {
      auto& out = r[j.state_offset + k];
      switch (j.type) {
        case JointType::Revolute:  // limits a turn or more apart (files write +-3.4e38) allow every angle
          out = j.limits && (*j.limits)[1] - (*j.limits)[0] < 2 * kPi ? *j.limits : std::array<double, 2>{-kPi, kPi};
          break;
        case JointType::Prismatic: out = j.limits ? *j.limits : std::array<double, 2>{nan, nan}; break;
        case JointType::Rotation3d: out = {-kPi, kPi}; break;
        default: out = {nan, nan}; break;
      }
    }
  }
  return r;
}

std::vector<PairReport> provePairs(const Model& model, const ProofOptions& options) {
  Model m = model;  // analysed with accurate sweeps everywhere (exact mode takes no intervals)
  for (Joint& j : m.joints)
    if (j.sweep == SweepMode::Exact) j.sweep = SweepMode::Accurate;
  const double margin = options.margin >= 0 ? options.margin : model.safety_margin;
  const auto ranges = jointRanges(m);
  const int n = static_cast<int>(m.bodies.size());

  std::vector<PairReport> out;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (m.bodies[a].frame != m.bodies[b].frame) {
        PairReport r;
        r.a = a, r.b = b;
        r.lca = m.commonAncestor(m.bodies[a].frame, m.bodies[b].frame);
        for (const BodyPair& p : model.pairs)
          if ((p.a == a && p.b == b) || (p.a == b && p.b == a)) r.checked = true;
        const int fa = m.bodies[a].frame, fb = m.bodies[b].frame;
        r.adjacent = (fb != kWorld && m.joints[fb].parent == fa) || (fa != kWorld && m.joints[fa].parent == fb);
        out.push_back(r);
      }

  std::vector<double> lower(m.stateSize(), 0.0), upper(m.stateSize(), 0.0);
  struct Box {
    std::vector<double> lo, hi;
  };
  for (std::size_t i = 0; i < out.size(); ++i) {
    PairReport& r = out[i];
    if (options.progress) options.progress(static_cast<double>(i) / out.size());
    Model single = m;
    single.pairs = {BodyPair{r.a, r.b, r.lca}};
    Checker checker(single);

    // The state values that move the two bodies relative to each other.
    // Each with a lever arm: how far a unit change can move the bodies (an estimate, used only
    // to choose which interval to split).
    std::vector<int> dims;
    std::vector<double> lever;
    bool unbounded = false;
    for (int body : {r.a, r.b}) {
      const Body& bd = m.bodies[body];
      double reach = bd.radius;
      for (const Vec3& p : bd.points) reach = std::max(reach, p.norm() + bd.radius);
      for (int j : jointsBetween(m, bd.frame, r.lca)) {
        const bool rotational = m.joints[j].type == JointType::Revolute || m.joints[j].type == JointType::Rotation3d;
        for (int k = 0; k < m.joints[j].dof; ++k) {
          const int s = m.joints[j].state_offset + k;
          dims.push_back(s);
          lever.push_back(rotational ? reach : 1.0);
          if (std::isnan(ranges[s][0])) unbounded = true;
        }
        reach += m.joints[j].origin.translation().norm();
      }
    }
    // Values that do not move the pair sit mid-range (any value would do).
    for (int s = 0; s < m.stateSize(); ++s)
      lower[s] = upper[s] = std::isnan(ranges[s][0]) ? 0.0 : 0.5 * ranges[s][0] + 0.5 * ranges[s][1];
    const QueryOptions qopt{.type = QueryType::Distances, .margin = margin};

    if (r.adjacent) {
      const int child = m.bodies[r.b].frame != kWorld && m.joints[m.bodies[r.b].frame].parent == m.bodies[r.a].frame
                            ? r.b
                            : r.a;
      const int parent = child == r.b ? r.a : r.b;
      const Joint& j = m.joints[m.bodies[child].frame];
      checker.query(lower, upper, qopt);
      bool always = false;
      if (j.type == JointType::Revolute)
        always = sharesAxisPoint(m, checker, parent, child, margin);
      else if (j.type == JointType::Fixed)
        always = distanceUpper(checker.sweptVolume(r.a, r.lca), checker.sweptVolume(r.b, r.lca)) <= margin;
      if (always) {
        r.verdict = Verdict::AlwaysTouching;
        continue;
      }
    }
    if (unbounded) {
      r.verdict = Verdict::Unbounded;
      continue;
    }
    // Branch and bound over the relevant dimensions, breadth first (large boxes first: their
    // centres find real encounters early).
    std::deque<Box> stack;
    Box root;
    for (int s : dims) root.lo.push_back(ranges[s][0]), root.hi.push_back(ranges[s][1]);
    stack.push_back(root);
    double min_bound = INFINITY;
    r.verdict = Verdict::Never;
    while (!stack.empty()) {
      if (r.boxes >= options.max_boxes) {
        r.verdict = Verdict::Undecided;
        break;
      }
      Box box = std::move(stack.front());
      stack.pop_front();
      for (std::size_t d = 0; d < dims.size(); ++d) lower[dims[d]] = box.lo[d], upper[dims[d]] = box.hi[d];
      const QueryResult& q = checker.query(lower, upper, qopt);
      ++r.boxes;
      if (q.status == Status::Ok && q.min_distance > margin) {
        min_bound = std::min(min_bound, q.min_distance);
        continue;
      }
      // Not proven here: is the centre a real encounter?
      for (std::size_t d = 0; d < dims.size(); ++d) lower[dims[d]] = upper[dims[d]] = 0.5 * box.lo[d] + 0.5 * box.hi[d];
      const QueryResult& c = checker.query(lower, upper, qopt);
      ++r.boxes;
      if (c.status == Status::Ok) {
        const double at = distanceUpper(checker.sweptVolume(r.a, r.lca), checker.sweptVolume(r.b, r.lca));
        if (at <= margin) {
          r.verdict = Verdict::Meets;
          r.witness = lower;
          r.witness_distance = at;
          break;
        }
      }
      if (dims.empty()) {  // no motion and not within the margin: only rounding can be left
        r.verdict = Verdict::Undecided;
        break;
      }
      std::size_t widest = 0;  // the interval that moves the bodies most
      for (std::size_t d = 1; d < dims.size(); ++d)
        if ((box.hi[d] - box.lo[d]) * lever[d] > (box.hi[widest] - box.lo[widest]) * lever[widest]) widest = d;
      Box other = box;
      const double mid = 0.5 * box.lo[widest] + 0.5 * box.hi[widest];
      box.hi[widest] = mid;
      other.lo[widest] = mid;
      stack.push_back(std::move(other));
      stack.push_back(std::move(box));
    }
    r.bound = r.verdict == Verdict::Never ? min_bound : 0.0;
  }
  if (options.progress) options.progress(1.0);
  return out;
}

std::vector<std::array<std::string, 2>> ignoreList(const Model& model, const std::vector<PairReport>& reports) {
  const auto proven = [](const PairReport& r) {
    return r.verdict == Verdict::Never || r.verdict == Verdict::AlwaysTouching;
  };
  std::vector<std::array<std::string, 2>> ignore;
  for (const PairReport& r : reports)
    if (proven(r)) ignore.push_back({model.bodies[r.a].name, model.bodies[r.b].name});
  // Pairs the model already ignores stay ignored.
  for (const PairReport& r : reports)
    if (!r.checked && !proven(r)) ignore.push_back({model.bodies[r.a].name, model.bodies[r.b].name});
  return ignore;
}

}  // namespace kccd::modelling
