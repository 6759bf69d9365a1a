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

// The pose of `frame` in the frame of its ancestor `top` when only fixed joints lie between
// (each joint's origin is then its whole motion).
Pose fixedPose(const Model& m, int frame, int top) {
  Pose pose = Pose::Identity();
  for (int f = frame; f != top && f != kWorld; f = m.joints[f].parent) pose = m.joints[f].origin * pose;
  return pose;
}

// A body's own points placed in an ancestor frame through fixed joints (its exact SSCH there:
// no point budget, no radius growth).
std::vector<Vec3> placed(const Model& m, int body, int top) {
  const Pose pose = fixedPose(m, m.bodies[body].frame, top);
  std::vector<Vec3> out;
  for (const Vec3& p : m.bodies[body].points) out.push_back(pose * p);
  return out;
}

// Adjacent through the revolute joint `g` (the one moving joint between the two bodies, above
// the child body): points on its axis are fixed in both bodies' frames. If one of them lies
// within the margin of both bodies, the bodies are within the margin at every angle. The child
// is taken in g's frame, the parent body in the pair's common frame `lca` (only fixed joints lie
// between either body and those frames, so both are exact).
bool sharesAxisPoint(const Model& m, int parent_body, int child_body, int g, int lca, double margin) {
  const Joint& j = m.joints[g];
  const std::vector<Vec3> child_points = placed(m, child_body, g), parent_points = placed(m, parent_body, lca);
  const SschView child{child_points, m.bodies[child_body].radius};
  const SschView parent{parent_points, m.bodies[parent_body].radius};
  if (child.points.empty() || parent.points.empty()) return false;
  const Pose to_lca = fixedPose(m, j.parent, lca) * j.origin;  // g's frame (on its axis: any angle)
  double extent = child.radius + parent.radius;
  for (const Vec3& p : child.points) extent = std::max(extent, p.norm() + child.radius);
  auto cost = [&](double t) {
    const Vec3 x = t * j.axis;
    const Vec3 y = to_lca * x;
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

bool samePair(const IgnoreEntry& e, const std::string& a, const std::string& b) {
  return (e.a == a && e.b == b) || (e.a == b && e.b == a);
}

// Appends (a, b, reason) unless the pair is listed already.
void addOnce(std::vector<IgnoreEntry>& list, const std::string& a, const std::string& b, IgnoreReason reason) {
  for (const IgnoreEntry& e : list)
    if (samePair(e, a, b)) return;
  list.push_back({a, b, reason});
}

// Whether the adjacency rule may ignore the pair: adjacent, and a body in the world frame is a
// link (a URDF's root) only when the options say so (otherwise it is an obstacle: a table, a post).
bool adjacentByRule(const Model& m, int a, int b, const IgnoreOptions& options, bool world_is_link) {
  if (options.keep_adjacent || connection(m, a, b) != Connection::Adjacent) return false;
  return world_is_link || (m.bodies[a].frame != kWorld && m.bodies[b].frame != kWorld);
}

// The model's user and SRDF entries, which keep their reason whatever the rules say.
void carryDecisions(const Model& m, IgnorePlan& plan) {
  for (const IgnoredPair& p : m.ignored)
    if (p.reason == IgnoreReason::User || p.reason == IgnoreReason::Srdf)
      addOnce(plan.ignore, m.bodies[p.a].name, m.bodies[p.b].name, p.reason);
}

// The model's other entries after `plan.ignore`'s: rigid and adjacent ones while the rule still
// holds (an adjacent entry in the file says its world body is a link), proof entries (never,
// always_touching) when `keep_proofs`; the rest go to `plan.dropped`.
void carryModelEntries(const Model& m, const IgnoreOptions& options, bool keep_proofs, IgnorePlan& plan) {
  for (const IgnoredPair& p : m.ignored) {
    const std::string &a = m.bodies[p.a].name, &b = m.bodies[p.b].name;
    bool keep = true;
    switch (p.reason) {
      case IgnoreReason::User:
      case IgnoreReason::Srdf:
        break;
      case IgnoreReason::Rigid:
        keep = connection(m, p.a, p.b) == Connection::Rigid;
        break;
      case IgnoreReason::Adjacent:
        keep = adjacentByRule(m, p.a, p.b, options, true);
        break;
      case IgnoreReason::Never:
      case IgnoreReason::AlwaysTouching:
        keep = keep_proofs;
        break;
    }
    bool listed = false;
    for (const IgnoreEntry& e : plan.ignore) listed = listed || samePair(e, a, b);
    if (!listed) (keep ? plan.ignore : plan.dropped).push_back({a, b, p.reason});
  }
}

}  // namespace

const char* toString(Verdict v) {
  switch (v) {
    case Verdict::Never:
      return "never";
    case Verdict::AlwaysTouching:
      return "always_touching";
    case Verdict::Meets:
      return "meets";
    case Verdict::Undecided:
      return "undecided";
    case Verdict::Unbounded:
      return "unbounded";
  }
  return "?";
}

Connection connection(const Model& m, int a, int b) {
  const int fa = m.bodies[a].frame, fb = m.bodies[b].frame;
  const int lca = m.commonAncestor(fa, fb);
  // The links on the path between the two bodies' links, and the moving joints among its joints.
  int moving = 0;
  bool bare = true;  // every link strictly between the two carries no body
  const auto carries = [&](int frame) {
    for (const Body& body : m.bodies)
      if (body.frame == frame) return true;
    return false;
  };
  for (int start : {fa, fb})
    for (int f = start; f != lca && f != kWorld; f = m.joints[f].parent) {
      moving += m.joints[f].type != JointType::Fixed;
      if (f != start && carries(f)) bare = false;
    }
  if (lca != fa && lca != fb && carries(lca)) bare = false;
  if (moving == 0) return Connection::Rigid;
  return moving == 1 && bare ? Connection::Adjacent : Connection::Distant;
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
        case JointType::Prismatic:
          out = j.limits ? *j.limits : std::array<double, 2>{nan, nan};
          break;
        case JointType::Rotation3d:
          out = {-kPi, kPi};
          break;
        default:
          out = {nan, nan};
          break;
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
        const Connection c = connection(m, a, b);
        r.adjacent = c == Connection::Adjacent;
        r.rigid = c == Connection::Rigid;
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

    if (r.rigid) {  // one configuration: its distance (of the exact volumes) decides
      ++r.boxes;
      const std::vector<Vec3> pa = placed(m, r.a, r.lca), pb = placed(m, r.b, r.lca);
      const DistanceResult d = distance(SschView{pa, m.bodies[r.a].radius}, SschView{pb, m.bodies[r.b].radius});
      r.bound = d.distance;
      r.verdict = d.distance > margin && d.status != GjkStatus::InvalidInput ? Verdict::Never : Verdict::AlwaysTouching;
      continue;
    }
    if (r.adjacent) {
      // The one moving joint between them; the child body hangs below it.
      int g = kWorld, child = r.a, parent = r.b;
      for (int body : {r.a, r.b})
        for (int f = m.bodies[body].frame; f != r.lca && f != kWorld; f = m.joints[f].parent)
          if (m.joints[f].type != JointType::Fixed) g = f, child = body, parent = body == r.a ? r.b : r.a;
      if (m.joints[g].type == JointType::Revolute && sharesAxisPoint(m, parent, child, g, r.lca, margin)) {
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

IgnorePlan structuralIgnores(const Model& m, const IgnoreOptions& options) {
  IgnorePlan plan;
  carryDecisions(m, plan);
  const int n = static_cast<int>(m.bodies.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (m.bodies[a].frame != m.bodies[b].frame && connection(m, a, b) == Connection::Rigid)
        addOnce(plan.ignore, m.bodies[a].name, m.bodies[b].name, IgnoreReason::Rigid);
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (m.bodies[a].frame != m.bodies[b].frame && adjacentByRule(m, a, b, options, options.world_is_link))
        addOnce(plan.ignore, m.bodies[a].name, m.bodies[b].name, IgnoreReason::Adjacent);
  carryModelEntries(m, options, true, plan);
  return plan;
}

IgnorePlan ignoreList(const Model& m, const std::vector<PairReport>& reports, const IgnoreOptions& options) {
  IgnorePlan plan;
  carryDecisions(m, plan);
  const auto names = [&](const PairReport& r) { return std::pair(m.bodies[r.a].name, m.bodies[r.b].name); };
  for (const PairReport& r : reports)
    if (r.rigid) addOnce(plan.ignore, names(r).first, names(r).second, IgnoreReason::Rigid);
  for (const PairReport& r : reports)
    if (r.verdict == Verdict::Never || r.verdict == Verdict::AlwaysTouching)
      addOnce(plan.ignore, names(r).first, names(r).second,
              r.verdict == Verdict::Never ? IgnoreReason::Never : IgnoreReason::AlwaysTouching);
  for (const PairReport& r : reports)
    if (adjacentByRule(m, r.a, r.b, options, options.world_is_link))
      addOnce(plan.ignore, names(r).first, names(r).second, IgnoreReason::Adjacent);
  carryModelEntries(m, options, false, plan);
  return plan;
}

std::string currentIgnoreReason(const Model& model, int a, int b) {
  for (const IgnoredPair& p : model.ignored)
    if ((p.a == a && p.b == b) || (p.a == b && p.b == a)) return toString(p.reason);
  return "not_included";
}

std::string plannedIgnoreReason(const IgnorePlan& plan, const Model& model, int a, int b) {
  const std::string& na = model.bodies[a].name;
  const std::string& nb = model.bodies[b].name;
  for (const IgnoreEntry& e : plan.ignore)
    if ((e.a == na && e.b == nb) || (e.a == nb && e.b == na)) return toString(e.reason);
  return "";
}

std::string verdictNote(const PairReport& r) {
  if (r.rigid)
    return std::string("rigid (only fixed joints between them): a constant distance, ") +
           (r.verdict == Verdict::Never ? "never within the margin" : "always within the margin") + ": ignore";
  switch (r.verdict) {
    case Verdict::Never:
      return "proven in " + std::to_string(r.boxes) + " boxes: safe to ignore";
    case Verdict::AlwaysTouching:
      return "adjacent, touch at every configuration: ignore";
    case Verdict::Meets:
      return "within the margin at a state inside the limits";
    case Verdict::Undecided:
      return "no proof within " + std::to_string(r.boxes) + " boxes: keep";
    case Verdict::Unbounded:
      return "a joint without limits moves them: keep";
  }
  return "";
}

VerdictCounts countVerdicts(const std::vector<PairReport>& reports) {
  VerdictCounts c;
  for (const PairReport& r : reports) {
    c.rigid += r.rigid;
    c.adjacent += r.adjacent;
    if (r.rigid) continue;
    switch (r.verdict) {
      case Verdict::Never:
        ++c.never;
        break;
      case Verdict::AlwaysTouching:
        ++c.always_touching;
        break;
      case Verdict::Meets:
        ++c.meets;
        break;
      case Verdict::Undecided:
        ++c.undecided;
        break;
      case Verdict::Unbounded:
        ++c.unbounded;
        break;
    }
  }
  return c;
}

}  // namespace kccd::modelling
