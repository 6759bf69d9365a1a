// Queries over interval boxes: lazily swept volumes shared by all pairs, pairs compared in their
// least-common-ancestor frame, and an any-time table of lower bounds refined smallest first.
#include "kccd/checker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "bounding_sphere.hpp"
#include "chain_support.hpp"
#include "kccd/distance.hpp"
#include "kccd/kinematics.hpp"
#include "rounding.hpp"
#include "sweep.hpp"

namespace kccd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Nodes one support search of the exact stage may visit (bounds its time; a search stopped early
// still gives a valid bound).
constexpr int kExactNodes = 2048;
// The apex chains are searched for a distance only when they can lift the bound by more than this.
constexpr double kExactDistanceGain = 2e-3;
// With QueryOptions::tight_volumes, a sweep whose radius growth exceeds this fraction of the swept
// sphere's radius also tries the other cover (chords for every point, reduced to the budget).
constexpr double kCoarseCover = 0.02;
using Clock = std::chrono::steady_clock;
using detail::shrunkBound;

}  // namespace

Checker::Checker(const Model& model) : model_(model) {
  layoutVolumes();
  computeReach();
  const int np = static_cast<int>(model.pairs.size());
  const int ns = model.stateSize();
  order_.resize(np);
  out_.resize(np);
  fresh_.assign(np, 0);
  nbest_.assign(np, 0.0);
  lower_.assign(ns, 0.0);
  upper_.assign(ns, 0.0);
  // The exact stage.
  const int nj = static_cast<int>(model.joints.size());
  joint_maps_.resize(nj);
  joint_maps_stamp_.assign(nj, 0);
  trig_.resize(nj);
  int max_levels = 0;
  for (int l : levels_) max_levels = std::max(max_levels, l);
  for (int variant = 0; variant < 2; ++variant) {
    chain_[variant].resize(volumes_.size());
    chain_stamp_[variant].assign(volumes_.size(), 0);
    chain_radius_[variant].assign(volumes_.size(), 0.0);
    chain_tangent_[variant].assign(volumes_.size(), 0);
  }
  for (const Body& body : model.bodies) {
    base_sphere_.push_back(detail::boundingSphere(body.points, 0.0));
    Vec3 lo = body.points[0], hi = body.points[0];
    for (const Vec3& p : body.points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    base_box_.push_back(0.5 * lo + 0.5 * hi);
    base_box_.push_back(0.5 * (hi - lo) + Vec3::Constant(detail::roundingGuard(lo.cwiseAbs().maxCoeff() + hi.cwiseAbs().maxCoeff(), 4)));
  }
  chain_stack_.resize(detail::chainStackSize(max_levels));
  split_box_.assign(2 * static_cast<std::size_t>(kMaxExactSplits) * static_cast<std::size_t>(ns), 0.0);
  split_extent_.assign(2 * static_cast<std::size_t>(std::max(max_levels, 1)), 0.0);
  centre_.assign(ns, 0.0);
  std::size_t most_points = 1;
  for (const Body& body : model.bodies) most_points = std::max(most_points, body.points.size());
  centre_points_.assign(2 * most_points, Vec3::Zero());
  split_grad_.assign(ns, 0.0);
  split_order_.assign(static_cast<std::size_t>(kMaxExactSplits), 0);
  split_key_.assign(static_cast<std::size_t>(kMaxExactSplits), 0.0);
  split_frames_.assign(2 * static_cast<std::size_t>(std::max(max_levels, 1)), Pose::Identity());
  chain_choice_.assign(std::max(max_levels, 1), 0);
  chain_best_.assign(2 * static_cast<std::size_t>(std::max(max_levels, 1)), 0);
}

Checker::~Checker() = default;

// Levels per body: level 0 is the body in its own frame, level l+1 the volume swept through the
// joint of level l and expressed in that joint's parent frame, up to the world. Every level gets
// its room in one arena of points, and the scratch space is sized for the widest sweep.
void Checker::layoutVolumes() {
  const Model& model = model_;
  const int nb = static_cast<int>(model.bodies.size());
  const int budget = model.point_budget;
  int max_points = budget;
  int arena = 0;
  for (int b = 0; b < nb; ++b) {
    const Body& body = model.bodies[b];
    level_begin_.push_back(static_cast<int>(volumes_.size()));
    int frame = body.frame;
    int level = 0;
    while (true) {
      Volume v;
      v.offset = arena;
      v.capacity = level == 0 ? static_cast<int>(body.points.size()) : budget;
      arena += v.capacity;
      volumes_.push_back(v);
      path_.push_back(frame);
      ++level;
      if (frame == kWorld) break;
      frame = model.joints[frame].parent;
    }
    levels_.push_back(level);
    max_points = std::max(max_points, static_cast<int>(body.points.size()));
  }
  points_.resize(arena);
  for (int b = 0; b < nb; ++b) {
    Volume& v = volumes_[level_begin_[b]];
    const Body& body = model.bodies[b];
    std::copy(body.points.begin(), body.points.end(), points_.begin() + v.offset);
    v.count = v.capacity;
    v.radius = body.radius;
    v.bound = detail::boundingSphere(body.points, body.radius);
    v.swept_sphere = v.bound;
  }
  int expansion = 1;
  for (const Joint& j : model.joints) expansion = std::max(expansion, detail::sweepExpansion(j));
  scratch_.resize(static_cast<std::size_t>(expansion) * max_points);
  scratch_dist_.resize(scratch_.size());
  scratch_alt_.resize(scratch_.size());
  scratch_order_.resize(scratch_.size());
}

// Per pair: the level of the LCA frame on each body's path, and how far each state value can
// move the pair's core points per unit change (for keeping stored bounds valid); then the empty
// any-time table with room for each stored bound's box.
void Checker::computeReach() {
  const Model& model = model_;
  const int np = static_cast<int>(model.pairs.size());
  const int ns = model.stateSize();
  std::vector<double> dense(static_cast<std::size_t>(np) * ns, 0.0);
  for (int p = 0; p < np; ++p) {
    const BodyPair& pair = model.pairs[p];
    for (int side = 0; side < 2; ++side) {
      const int b = side == 0 ? pair.a : pair.b;
      const Body& body = model.bodies[b];
      double extent = 0.0;  // bound on |core point| in the frame of the current level
      for (const Vec3& q : body.points) extent = std::max(extent, q.norm());
      int level = 0;
      for (; path_[level_begin_[b] + level] != pair.lca; ++level) {
        const Joint& j = model.joints[path_[level_begin_[b] + level]];
        double* reach = dense.data() + static_cast<std::size_t>(p) * ns + j.state_offset;
        switch (j.type) {
          case JointType::Fixed: break;
          case JointType::Revolute: reach[0] += extent; break;
          case JointType::Prismatic: reach[0] += 1.0; break;
          case JointType::Translation3d:
            for (int k = 0; k < 3; ++k) reach[k] += 1.0;
            break;
          case JointType::Rotation3d:  // exp is 1-Lipschitz: angle change <= sum of |component changes|
            for (int k = 0; k < 3; ++k) reach[k] += extent;
            break;
        }
        const bool unbounded_travel = j.type == JointType::Prismatic || j.type == JointType::Translation3d;
        extent = unbounded_travel ? kInf : extent + j.origin.translation().norm();
      }
      pair_level_.push_back(level);
    }
  }
  // Keep only the state values that move the pair (a sparse list per pair).
  reach_begin_.push_back(0);
  for (int p = 0; p < np; ++p) {
    for (int st = 0; st < ns; ++st) {
      const double r = dense[static_cast<std::size_t>(p) * ns + st];
      if (r == 0.0) continue;
      reach_state_.push_back(st);
      reach_.push_back(r);
    }
    reach_begin_.push_back(static_cast<int>(reach_.size()));
  }
  table_.assign(np, Entry{});
  box_.assign(2 * reach_.size(), 0.0);
}

void Checker::reset() noexcept {
  // Everything a query carries to the next, the GJK warm-start directions included: after a
  // reset the answer is bit for bit a new Checker's, whatever this one answered before.
  for (Entry& e : table_) e = Entry{};
}

bool Checker::validate(std::span<const double> lower, std::span<const double> upper) noexcept {
  const int ns = model_.stateSize();
  Status& s = result_.status;
  if (static_cast<int>(lower.size()) != ns || static_cast<int>(upper.size()) != ns) {
    s = Status::WrongStateSize;
    return false;
  }
  for (int i = 0; i < ns; ++i) {
    if (!std::isfinite(lower[i]) || !std::isfinite(upper[i])) {
      s = Status::NonFiniteState;
      return false;
    }
    if (lower[i] > upper[i]) {
      s = Status::LowerAboveUpper;
      return false;
    }
  }
  for (const Joint& j : model_.joints) {
    if (j.sweep != SweepMode::Exact) continue;
    for (int k = 0; k < j.dof; ++k) {
      if (lower[j.state_offset + k] != upper[j.state_offset + k]) {
        s = Status::ExactNeedsPoint;
        return false;
      }
    }
  }
  return true;
}

const Checker::Volume* Checker::volume(int body, int level, Box box) noexcept {
  const int idx = level_begin_[body] + level;
  Volume& v = volumes_[idx];
  if (level == 0 || v.stamp == cycle_) return &v;
  const Volume* below = volume(body, level - 1, box);
  if (below == nullptr) return nullptr;
  const Joint& joint = model_.joints[path_[idx - 1]];
  double radius = below->radius;
  const double* lo = box.lower.data() + joint.state_offset;
  const double* hi = box.upper.data() + joint.state_offset;
  const Sphere* below_sphere = sphere(body, level - 1, box);
  if (below_sphere == nullptr) return nullptr;
  const double below_radius = radius;
  const detail::RevoluteTrig& trig = revoluteTrig(path_[idx - 1], box);
  int n = detail::sweepJoint(joint, lo, hi, trig, view(*below).points, scratch_.data(), radius, v.capacity,
                             scratch_dist_.data(), *below_sphere);
  if (n < 0) return nullptr;
  n = detail::reduceToBudget(scratch_.data(), n, v.capacity, scratch_dist_.data(), scratch_order_.data(), radius);
  const Vec3* kept = scratch_.data();
  // With tight volumes asked for (display), when the budget made the cover coarse (middle points
  // of wide arcs add first-order growth), the other cover may be tighter: chords for every point,
  // then reduced to the budget with the distance of each dropped point to the kept points' hull.
  // Both keep the exact stage's chord chains inside (reductions only grow the volume), so the
  // smaller radius can be kept; it costs a farthest-point selection per sweep.
  if (tight_volumes_ && radius - below_radius > kCoarseCover * (below_sphere->radius + 1e-9)) {
    double alt_radius = below_radius;
    int m = detail::sweepJoint(joint, lo, hi, trig, view(*below).points, scratch_alt_.data(), alt_radius,
                               std::numeric_limits<int>::max(), scratch_dist_.data(), *below_sphere);
    if (m > 0) {
      m = detail::reduceToBudget(scratch_alt_.data(), m, v.capacity, scratch_dist_.data(), scratch_order_.data(),
                                 alt_radius);
      if (alt_radius < radius) {
        radius = alt_radius;
        n = m;
        kept = scratch_alt_.data();
      }
    }
  }
  std::copy(kept, kept + n, points_.begin() + v.offset);
  v.count = n;
  v.radius = radius;
  v.bound = detail::boundingSphere(view(v).points, radius);
  if (!std::isfinite(v.bound.radius)) return nullptr;
  v.stamp = cycle_;
  ++result_.stats.volumes_swept;
  return &v;
}

SschView Checker::view(const Volume& v) const noexcept {
  return {{points_.data() + v.offset, static_cast<std::size_t>(v.count)}, v.radius};
}

const Sphere* Checker::sphere(int body, int level, Box box) noexcept {
  const int idx = level_begin_[body] + level;
  Volume& v = volumes_[idx];
  if (level == 0 || v.sphere_stamp == geo_cycle_) return &v.swept_sphere;
  const Sphere* below = sphere(body, level - 1, box);
  if (below == nullptr) return nullptr;
  const Joint& joint = model_.joints[path_[idx - 1]];
  v.swept_sphere = detail::sweepSphere(joint, box.lower.data() + joint.state_offset,
                                       box.upper.data() + joint.state_offset, revoluteTrig(path_[idx - 1], box), *below);
  if (!v.swept_sphere.center.allFinite() || !std::isfinite(v.swept_sphere.radius)) return nullptr;
  v.sphere_stamp = geo_cycle_;
  return &v.swept_sphere;
}

SschView Checker::sweptVolume(int body, int frame) noexcept {
  if (body < 0 || body >= static_cast<int>(levels_.size())) return {};
  for (int level = 0; level < levels_[body]; ++level) {
    if (path_[level_begin_[body] + level] != frame) continue;
    const Volume* v = volume(body, level, Box{lower_, upper_});
    return v == nullptr ? SschView{} : view(*v);
  }
  return {};
}

// The trigonometry of a revolute joint's interval in `box`, made when the interval differs from
// the one it was last made for (every body swept through the joint shares it; other joints get
// an unused default).
const detail::RevoluteTrig& Checker::revoluteTrig(int joint, Box box) noexcept {
  detail::RevoluteTrig& t = trig_[static_cast<std::size_t>(joint)];
  const Joint& j = model_.joints[static_cast<std::size_t>(joint)];
  if (j.type != JointType::Revolute) return t;
  const double lo = box.lower[static_cast<std::size_t>(j.state_offset)];
  const double hi = box.upper[static_cast<std::size_t>(j.state_offset)];
  if (t.lo != lo || t.hi != hi) t = detail::revoluteTrig(lo, hi);
  return t;
}

const detail::JointMaps* Checker::jointMaps(int joint, Box box) noexcept {
  if (joint_maps_stamp_[joint] != geo_cycle_) {
    const Joint& j = model_.joints[joint];
    joint_maps_[joint] = detail::jointMaps(j, box.lower.data() + j.state_offset, box.upper.data() + j.state_offset,
                                           revoluteTrig(joint, box));
    joint_maps_stamp_[joint] = geo_cycle_;
  }
  return &joint_maps_[joint];
}

// The chain of `body` up to `level` (levels swept, as in volume()); variant 0 covers every revolute
// joint by chords, variant 1 by each joint's mode (accurate: chords and tangent apexes).
bool Checker::chain(int body, int level, int variant, Box box, detail::ChainView& out) noexcept {
  const int begin = level_begin_[body];
  const Body& b = model_.bodies[body];
  std::vector<detail::ChainLevel>& levels = chain_[variant];
  double radius = b.radius;
  bool tangent = false;
  for (int l = 1; l <= level; ++l) {
    const int idx = begin + l;
    if (chain_stamp_[variant][idx] != geo_cycle_) {
      const int joint = path_[idx - 1];
      const Sphere& below = l == 1 ? base_sphere_[body] : levels[idx - 1].core;
      const bool apexes = variant == 1 && model_.joints[joint].sweep == SweepMode::Accurate;
      const Sphere* swept = sphere(body, l - 1, box);
      if (swept == nullptr) return false;
      const bool below_in_swept = l == 1 || chain_tangent_[variant][idx - 1] == 0;
      const double below_overshoot = l == 1 ? 0.0 : levels[idx - 1].overshoot;
      const Vec3& box_centre = l == 1 ? base_box_[2 * body] : levels[idx - 1].box_centre;
      const Vec3& box_half = l == 1 ? base_box_[2 * body + 1] : levels[idx - 1].box_half;
      levels[idx] = detail::chainLevel(*jointMaps(joint, box), apexes, below, *swept, below_in_swept, below_overshoot,
                                       box_centre, box_half);
      const double below_radius = l == 1 ? b.radius : chain_radius_[variant][idx - 1];
      chain_radius_[variant][idx] = below_radius + levels[idx].growth;
      chain_tangent_[variant][idx] =
          (l > 1 && chain_tangent_[variant][idx - 1]) || levels[idx].count != levels[idx].maps->chord_count;
      if (!levels[idx].core.center.allFinite() || !std::isfinite(levels[idx].core.radius) ||
          !std::isfinite(chain_radius_[variant][idx]))
        return false;
      chain_stamp_[variant][idx] = geo_cycle_;
    }
    radius = chain_radius_[variant][idx];
    tangent = chain_tangent_[variant][idx] != 0;
  }
  (void)tangent;
  out.points = b.points;
  out.base = base_sphere_[body];
  out.levels = std::span<const detail::ChainLevel>(levels.data() + begin + 1, static_cast<std::size_t>(level));
  out.radius = radius;
  return true;
}

namespace {
bool hasRotationApexes(const detail::ChainView& c) {
  for (const detail::ChainLevel& l : c.levels)
    if (l.rotation_apexes) return true;
  return false;
}
}  // namespace

// Refines a pair's bound with the exact stage: the chord chains first, then (when an accurate
// joint adds apexes) the chains in each joint's mode; the bound is the best of all. Returns false
// on a numerical failure.
bool Checker::exactStage(int p, double stop_above, Box box, double& bound) noexcept {
  const BodyPair& pair = model_.pairs[p];
  Entry& e = table_[p];
  const int la = pair_level_[2 * p], lb = pair_level_[2 * p + 1];
  const int max_levels = static_cast<int>(chain_choice_.size());
  // Once a chain is proven within the margin it cannot clear the pair: a collision query, and any
  // query that asks the exact stage for verdicts only (exact_below up to the margin), needs no more.
  const double stop_below =
      result_.type == QueryType::Collision || exact_below_ <= result_.margin ? result_.margin : -kInf;
  double chord_upper = kInf;  // upper bound on the distance of the chord chains' cores
  double chord_lower = -kInf; // the chord chains' lower bound
  // A pair already clear of the margin is refined for its distance only: supports to within
  // kExactDistanceTolerance (their slack counted in the bound) and GJK to a relative 1e-3.
  const bool for_distance = bound > result_.margin;
  for (int variant = 0; variant < 2; ++variant) {
    if (bound > stop_above) break;
    detail::ChainView ca, cb;
    if (!chain(pair.a, la, variant, box, ca) || !chain(pair.b, lb, variant, box, cb)) return false;
    if (variant == 1 && (la == 0 || !chain_tangent_[1][level_begin_[pair.a] + la]) &&
        (lb == 0 || !chain_tangent_[1][level_begin_[pair.b] + lb]))
      break;  // no apexes anywhere: the same chains as variant 0
    // The apex chains hold the chord chains' cores (chord ends are among their maps) with smaller
    // radii: when the chord cores are proven close enough, the apex chains are within the margin too.
    if (variant == 1 && chord_upper - ca.radius - cb.radius <= stop_below) break;
    // Nor can they lift a distance above that: refined for its distance, a pair whose bound is
    // already within the tolerance of it keeps the chord chains' bound.
    if (variant == 1 && for_distance && chord_upper - ca.radius - cb.radius <= bound + kExactDistanceGain) break;
    // Once the chord chains prove the pair clear (the verdict), the apexes could only tighten its
    // distance. On the whole box a revolute joint's apexes cost a third map per level for that (the
    // searches' tree grows from 2^n to 3^n leaves, over the widest arcs): a distance query's
    // splitting tightens the pair instead, and its sub-boxes (arcs halved) are searched with every
    // apex (bench_trade: about 60 % of the time at much the same looseness). A rotation3d joint's
    // apexes remove a pose error's first-order growth, which no split of the box can shrink, and
    // stay. The chord chains lie inside every budget's point volumes, so this choice does not
    // depend on the budget, and splitting still only raises a bound.
    if (variant == 1 && !in_sub_box_ && chord_lower > result_.margin && !hasRotationApexes(ca) &&
        !hasRotationApexes(cb))
      break;
    detail::SetsInfo info;
    info.scale_a = detail::chainExtent(ca);
    info.scale_b = detail::chainExtent(cb);
    info.start_a = ca.levels.empty() ? ca.base.center : ca.levels.back().core.center;
    info.start_b = cb.levels.empty() ? cb.base.center : cb.levels.back().core.center;
    // One work area per side (each keeps its chain's last best leaf); the stack is shared.
    detail::ChainWork work_a{chain_stack_.data(), chain_choice_.data(), chain_best_.data()};
    detail::ChainWork work_b{chain_stack_.data(), chain_choice_.data(), chain_best_.data() + max_levels};
    const double tolerance = for_distance ? kExactDistanceTolerance : -1.0;
    auto support_a = [&](const Vec3& dir) { return detail::chainSupport(ca, dir, work_a, kExactNodes, tolerance); };
    auto support_b = [&](const Vec3& dir) { return detail::chainSupport(cb, dir, work_b, kExactNodes, tolerance); };
    GjkOptions opt;
    opt.stop_above = stop_above;
    opt.stop_below = stop_below;
    opt.warm_start = &e.direction;
    opt.max_iterations = 64;
    opt.relative_tolerance = for_distance ? 1e-3 : 1e-9;
    const DistanceResult d = detail::gjkDistance(support_a, support_b, ca.radius, cb.radius, info, opt);
    ++result_.stats.exact_calls;
    if (d.status == GjkStatus::InvalidInput || !std::isfinite(d.distance)) return false;
    if (variant == 0) {
      chord_upper = d.hull_upper;
      chord_lower = d.distance;
    }
    if (d.distance > bound) {
      bound = d.distance;
      e.witness_a = d.witness_a;
      e.witness_b = d.witness_b;
      e.gjk = true;
    }
    e.direction = d.direction;
  }
  return true;
}

double Checker::refresh(int p, double stop_above, Box box) noexcept {
  const BodyPair& pair = model_.pairs[p];
  Entry& e = table_[p];
  const int la = pair_level_[2 * p], lb = pair_level_[2 * p + 1];
  ++result_.stats.pairs_checked;
  auto fail = [&]() {
    result_.status = Status::NumericalFailure;
    e.valid = false;
    e.current = 0.0;
    return 0.0;
  };
  auto sphereGap = [](const Sphere& x, const Sphere& y) {
    return std::max(0.0, shrunkBound((x.center - y.center).norm() - x.radius - y.radius));
  };
  // Cheapest first: spheres swept without sweeping any point often prove the pair clear.
  const Sphere* sa = sphere(pair.a, la, box);
  const Sphere* sb = sphere(pair.b, lb, box);
  if (sa == nullptr || sb == nullptr) return fail();
  double bound = sphereGap(*sa, *sb);
  e.gjk = false;
  if (bound <= stop_above) {
    // Then the spheres around the swept points, then GJK on the points themselves.
    const Volume* va = volume(pair.a, la, box);
    const Volume* vb = volume(pair.b, lb, box);
    if (va == nullptr || vb == nullptr) return fail();
    bound = std::max(bound, sphereGap(va->bound, vb->bound));
    if (bound <= stop_above) {
      GjkOptions opt;
      opt.stop_above = stop_above;
      opt.warm_start = &e.direction;
      const DistanceResult d = distance(view(*va), view(*vb), opt);
      ++result_.stats.gjk_calls;
      if (d.status == GjkStatus::InvalidInput) return fail();
      bound = std::max(bound, d.distance);
      e.direction = d.direction;
      e.witness_a = d.witness_a;
      e.witness_b = d.witness_b;
      e.gjk = true;
      if (bound <= std::min(stop_above, exact_below_)) {
        if (!exactStage(p, stop_above, box, bound)) return fail();
        if (splits_ > 1 && bound > result_.margin && bound <= std::min(stop_above, exact_below_) &&
            !splitPair(p, box, bound))
          return fail();
      }
    }
  }
  e.valid = true;
  e.bound = bound;
  e.current = bound;
  for (int k = reach_begin_[p]; k < reach_begin_[p + 1]; ++k) {
    box_[2 * k] = box.lower[reach_state_[k]];
    box_[2 * k + 1] = box.upper[reach_state_[k]];
  }
  return bound;
}

// The joint swept at `level` (1 up to the body's levels) of `body`'s path.
const Joint& Checker::levelJoint(int body, int level) const noexcept {
  return model_.joints[static_cast<std::size_t>(path_[level_begin_[body] + level - 1])];
}

// Splits the box of pair p, refined for its distance with the bound `bound`, when the bound lies
// more than split_gap_ (QueryOptions::exact_split_gap) below an upper bound on the pair's true
// smallest distance (its distance at two configurations of the box: the centre, and the corner
// the gradient there points to), and some accurate joint moves it. The sub-boxes: splits_ of
// them, made by halving level by level each sub-box's state value that moves the pair's points
// farthest over its interval (width times the extent of the volume below its joint, from the
// whole box's swept spheres; metres for translations): a choice from the geometry only, the same
// in every sweep mode. Each sub-box is refined by the exact stage from `bound` (which holds for
// every part); the pair's bound becomes the smallest over the sub-boxes, which cover the box, up
// to exact_below_. Stops early when a sub-box gains nothing. The exact stage runs under stamps of
// its own (geo_cycle_), and a fresh stamp is left for the box, so the spheres, joint maps and
// chains are recomputed for it when next needed; the point volumes (cycle_) are not touched.
bool Checker::splitPair(int p, Box box, double& bound) noexcept {
  const BodyPair& pair = model_.pairs[p];
  Entry& e = table_[p];
  const auto nsz = static_cast<std::size_t>(model_.stateSize());
  const int side_level[2] = {pair_level_[2 * p], pair_level_[2 * p + 1]};
  const int side_body[2] = {pair.a, pair.b};
  const int max_levels = static_cast<int>(split_extent_.size() / 2);
  // Splitting is part of accurate's refinement: pairs moved by fast joints only are left as they are.
  bool accurate = false;
  for (int s = 0; s < 2; ++s)
    for (int l = 1; l <= side_level[s]; ++l)
      accurate = accurate || levelJoint(side_body[s], l).sweep == SweepMode::Accurate;
  if (!accurate) return true;
  // An upper bound on the true smallest distance: the nominal distance (no error bounds) at the
  // box centre and at the corner the distance's gradient there points away from, both
  // configurations of the box. No split can gain more than it lies above the bound.
  std::fill(split_grad_.begin(), split_grad_.end(), 0.0);
  for (std::size_t k = 0; k < nsz; ++k) centre_[k] = box.lower[k] + 0.5 * (box.upper[k] - box.lower[k]);
  double upper = posedDistance(p, centre_.data(), split_grad_.data());
  if (!(upper - bound > split_gap_)) return true;
  for (std::size_t k = 0; k < nsz; ++k)
    if (split_grad_[k] != 0.0) centre_[k] = split_grad_[k] > 0.0 ? box.lower[k] : box.upper[k];
  upper = std::min(upper, posedDistance(p, centre_.data(), nullptr));
  if (!(upper - bound > split_gap_)) return true;
  for (int s = 0; s < 2; ++s)
    for (int l = 1; l <= side_level[s]; ++l) {
      const Sphere* below = sphere(side_body[s], l - 1, box);
      if (below == nullptr) return false;
      split_extent_[static_cast<std::size_t>(s * max_levels + l - 1)] = below->center.norm() + below->radius;
    }
  const Vec3 witness_a = e.witness_a, witness_b = e.witness_b, direction = e.direction;
  const bool gjk = e.gjk;
  ++result_.stats.split_pairs;
  auto lo = [&](int leaf) { return split_box_.data() + 2 * static_cast<std::size_t>(leaf) * nsz; };
  auto hi = [&](int leaf) { return lo(leaf) + nsz; };
  std::copy(box.lower.begin(), box.lower.end(), lo(0));
  std::copy(box.upper.begin(), box.upper.end(), hi(0));
  int leaves = 1;
  for (; leaves < splits_; leaves *= 2)
    for (int leaf = 0; leaf < leaves; ++leaf) {
      int arg = -1;
      double move = 0.0;
      for (int s = 0; s < 2; ++s)
        for (int l = 1; l <= side_level[s]; ++l) {
          const Joint& j = levelJoint(side_body[s], l);
          const double extent = split_extent_[static_cast<std::size_t>(s * max_levels + l - 1)];
          const bool turns = j.type == JointType::Revolute || j.type == JointType::Rotation3d;
          for (int k = 0; k < j.dof; ++k) {
            const int st = j.state_offset + k;
            const double m = (hi(leaf)[st] - lo(leaf)[st]) * (turns ? extent : 1.0);
            if (m > move) {
              move = m;
              arg = st;
            }
          }
        }
      const int other = leaves + leaf;
      std::copy(lo(leaf), lo(leaf) + 2 * nsz, lo(other));
      if (arg < 0) continue;  // nothing moves: the copy covers the same box
      const double mid = lo(leaf)[arg] + 0.5 * (hi(leaf)[arg] - lo(leaf)[arg]);
      hi(leaf)[arg] = mid;
      lo(other)[arg] = mid;
    }
  // The sub-box nearest the obstacle first (by the nominal distance at its centre): the smallest
  // bound is then found early, and every later sub-box's search stops once it is proven above it
  // (or above the band's top), since only the smallest counts.
  for (int leaf = 0; leaf < leaves; ++leaf) {
    for (std::size_t k = 0; k < nsz; ++k) centre_[k] = lo(leaf)[k] + 0.5 * (hi(leaf)[k] - lo(leaf)[k]);
    split_order_[static_cast<std::size_t>(leaf)] = leaf;
    const double key = posedDistance(p, centre_.data(), nullptr);
    split_key_[static_cast<std::size_t>(leaf)] = std::isnan(key) ? kInf : key;
  }
  std::sort(split_order_.begin(), split_order_.begin() + leaves,
            [&](int x, int y) { return split_key_[static_cast<std::size_t>(x)] < split_key_[static_cast<std::size_t>(y)]; });
  double split = kInf;
  Vec3 best_a = witness_a, best_b = witness_b;
  for (int i = 0; i < leaves && split > bound; ++i) {
    const int leaf = split_order_[static_cast<std::size_t>(i)];
    geo_cycle_ = ++stamps_;
    double b = bound;
    e.witness_a = witness_a;
    e.witness_b = witness_b;
    in_sub_box_ = true;
    const bool ok = exactStage(p, std::min(split, exact_below_),
                               Box{std::span<const double>(lo(leaf), nsz), std::span<const double>(hi(leaf), nsz)}, b);
    in_sub_box_ = false;
    if (!ok) return false;
    if (b < split) {
      split = b;
      best_a = e.witness_a;
      best_b = e.witness_b;
    }
  }
  // The entry as the whole box left it, and a fresh stamp for the box's spheres, maps and chains.
  e.witness_a = witness_a;
  e.witness_b = witness_b;
  e.direction = direction;
  e.gjk = gjk;
  geo_cycle_ = ++stamps_;
  // Up to the top of the band: what a distance query asks to be tight (beyond it, the point
  // volumes' bound is what every other pair reports).
  split = std::min(split, exact_below_);
  if (split > bound && split < kInf) {
    bound = split;
    e.witness_a = best_a;
    e.witness_b = best_b;
  }
  return true;
}

// An upper bound on pair p's smallest distance at configuration q over its joints' error bounds:
// its two bodies posed in the pair's common-ancestor frame without error, GJK's upper distance
// (the hulls' less the radii), less every translation3d error bound on either path (an error of
// that length along the separating direction is one of the pose's true values, and moves the
// witness points that much closer; rotation errors are not counted). With `grad`, adds to it the
// nominal distance's derivative along each state value of the pair's joints (the witness points
// moved by each joint's motion, along the separating direction). Used to choose whether and how
// to split; +inf when GJK fails.
double Checker::posedDistance(int p, const double* q, double* grad) noexcept {
  const BodyPair& pair = model_.pairs[p];
  const int side_level[2] = {pair_level_[2 * p], pair_level_[2 * p + 1]};
  const int side_body[2] = {pair.a, pair.b};
  const int max_levels = static_cast<int>(split_extent_.size() / 2);
  SschView posed[2];
  double error = 0.0;  // translation error bounds on both paths
  for (int s = 0; s < 2; ++s) {
    Pose above = Pose::Identity();  // from the frame below level l's motion to the common frame
    for (int l = side_level[s]; l >= 1; --l) {
      const Joint& j = levelJoint(side_body[s], l);
      if (j.type == JointType::Translation3d) error += j.error;
      const Pose frame = above * j.origin;
      split_frames_[static_cast<std::size_t>(s * max_levels + l - 1)] = frame;
      above = frame * jointMotion(j, q + j.state_offset);
    }
    const Body& body = model_.bodies[static_cast<std::size_t>(side_body[s])];
    Vec3* out = centre_points_.data() + static_cast<std::size_t>(s) * (centre_points_.size() / 2);
    for (std::size_t i = 0; i < body.points.size(); ++i) out[i] = above * body.points[i];
    posed[s] = {{out, body.points.size()}, body.radius};
  }
  const DistanceResult d = distance(posed[0], posed[1]);
  if (d.status == GjkStatus::InvalidInput) return kInf;
  const double nominal = std::max(0.0, d.hull_upper - posed[0].radius - posed[1].radius);
  const double upper = std::max(0.0, nominal - error);
  if (grad == nullptr || !(nominal > 0.0)) return upper;
  const Vec3 n = -d.direction;  // from a towards b
  for (int s = 0; s < 2; ++s) {
    const Vec3& w = s == 0 ? d.witness_a : d.witness_b;
    const double sign = s == 0 ? -1.0 : 1.0;  // a moving along n comes closer, b moving along n goes away
    for (int l = 1; l <= side_level[s]; ++l) {
      const Joint& j = levelJoint(side_body[s], l);
      const Pose& f = split_frames_[static_cast<std::size_t>(s * max_levels + l - 1)];
      const Vec3 arm = w - f.translation();
      double* g = grad + j.state_offset;
      switch (j.type) {
        case JointType::Fixed: break;
        case JointType::Revolute: g[0] += sign * n.dot((f.linear() * j.axis).cross(arm)); break;
        case JointType::Prismatic: g[0] += sign * n.dot(f.linear() * j.axis); break;
        case JointType::Translation3d:
          for (int k = 0; k < 3; ++k) g[k] += sign * n.dot(f.linear().col(k));
          break;
        case JointType::Rotation3d:  // about the frame's axes (exact at a zero rotation vector)
          for (int k = 0; k < 3; ++k) g[k] += sign * n.dot(f.linear().col(k).cross(arm));
          break;
      }
    }
  }
  return upper;
}

void Checker::report(int p, PairDistance& out) const noexcept {
  const Entry& e = table_[p];
  out.pair = p;
  out.distance = e.current;
  out.fresh = fresh_[p] != 0;
  out.has_witness = out.fresh && e.gjk;
  out.witness_a = e.witness_a;
  out.witness_b = e.witness_b;
}

const QueryResult& Checker::query(std::span<const double> lower, std::span<const double> upper,
                                  const QueryOptions& options) noexcept {
  const Clock::time_point start = Clock::now();
  result_ = QueryResult{};
  result_.type = options.type;
  result_.margin = options.margin >= 0.0 ? options.margin : model_.safety_margin;
  const double margin = result_.margin;
  tight_volumes_ = options.tight_volumes;
  const double band = options.exact_band > 0.0 ? options.exact_band : 0.0;  // (NaN: none)
  exact_below_ = std::isnan(options.exact_below) || options.exact_below == -kInf ? -kInf
                 : options.exact_below >= 0.0                                 ? options.exact_below
                 : options.type == QueryType::Collision                       ? margin
                                                                              : margin + band;
  if (!validate(lower, upper)) {
    result_.collision = true;
    result_.min_distance = 0.0;
    return result_;
  }
  cycle_ = ++stamps_;
  geo_cycle_ = ++stamps_;
  std::copy(lower.begin(), lower.end(), lower_.begin());
  std::copy(upper.begin(), upper.end(), upper_.begin());
  const Box box{lower_, upper_};

  carryBounds(box);
  const int candidates = orderCandidates(options.type, margin);

  // Budgets beyond kMaxBudgetUs (and NaN) mean unlimited: converting them to clock ticks would overflow.
  Budget budget;
  budget.timed = options.budget_us > 0.0 && options.budget_us <= kMaxBudgetUs;
  budget.deadline =
      start + (budget.timed
                   ? std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::micro>(options.budget_us))
                   : Clock::duration::zero());
  budget.max_pairs = options.max_pairs;
  std::fill(fresh_.begin(), fresh_.end(), 0);
  // Splitting: distance queries whose exact stage reaches above the margin.
  splits_ = 0;
  if (options.type != QueryType::Collision && exact_below_ > margin)
    for (int s = 2; s <= std::min(options.exact_splits, kMaxExactSplits); s *= 2) splits_ = s;
  split_gap_ = options.exact_split_gap >= 0.0 ? options.exact_split_gap : QueryOptions{}.exact_split_gap;

  const int np = static_cast<int>(model_.pairs.size());
  const int n_wanted = std::clamp(options.n, 1, std::max(np, 1));  // NClosest
  int hit = -1;  // Collision: the pair reported
  switch (options.type) {
    case QueryType::Collision: hit = refineCollision(candidates, margin, budget, box); break;
    case QueryType::Closest: refineClosest(candidates, margin, budget, box); break;
    case QueryType::NClosest: refineNClosest(n_wanted, budget, box); break;
    case QueryType::Distances: refineDistances(budget, box); break;
  }

  publishAnswer(options.type, margin, hit, n_wanted);
  result_.stats.time_us = std::chrono::duration<double, std::micro>(Clock::now() - start).count();
  return result_;
}

// Carries every stored bound over to this box: unchanged while the box stays inside the stored
// one, otherwise lowered by the most the pair's points can have moved (docs/algorithms.md section 7).
void Checker::carryBounds(Box box) noexcept {
  const int np = static_cast<int>(model_.pairs.size());
  for (int p = 0; p < np; ++p) {
    Entry& e = table_[p];
    if (!e.valid) {
      e.current = 0.0;
      continue;
    }
    double moved = 0.0;
    for (int k = reach_begin_[p]; k < reach_begin_[p + 1]; ++k) {
      const int st = reach_state_[k];
      const double grow = std::max({0.0, box_[2 * k] - box.lower[st], box.upper[st] - box_[2 * k + 1]});
      if (grow > 0.0) moved += reach_[k] * grow;
    }
    e.current = moved == 0.0 ? e.bound : std::max(0.0, shrunkBound(e.bound - moved));
    if (!std::isfinite(e.current)) e.current = 0.0;
  }
}

// Refinement order: smallest bound first, in order_. Collision and closest queries only ever
// refine pairs within the margin, so only those are sorted (and counted); the others come after
// them. Returns the number of sorted candidates at the front of order_.
int Checker::orderCandidates(QueryType type, double margin) noexcept {
  const int np = static_cast<int>(model_.pairs.size());
  for (int p = 0; p < np; ++p) order_[p] = p;
  auto sorted_end = order_.end();
  if (type == QueryType::Collision || type == QueryType::Closest) {
    sorted_end = std::partition(order_.begin(), order_.end(), [&](int x) { return table_[x].current <= margin; });
  }
  std::sort(order_.begin(), sorted_end, [this](int x, int y) { return table_[x].current < table_[y].current; });
  return static_cast<int>(sorted_end - order_.begin());
}

// True when a budget stops refinement (and records that it did).
bool Checker::expired(const Budget& budget) noexcept {
  if ((budget.max_pairs >= 0 && result_.stats.pairs_checked >= budget.max_pairs) ||
      (budget.timed && Clock::now() > budget.deadline)) {
    result_.stats.budget_exhausted = true;
    return true;
  }
  return false;
}

// Recomputes one pair's bound for this query and marks it fresh.
void Checker::refine(int p, double stop_above, Box box) noexcept {
  refresh(p, stop_above, box);
  fresh_[p] = 1;
}

// Collision: refines candidates until one is proven within the margin (or a budget runs out,
// which makes the next candidate the answer). Every pair after the candidates clears the margin
// already. Returns the pair to report, or -1 when none collides.
int Checker::refineCollision(int candidates, double margin, const Budget& budget, Box box) noexcept {
  for (int i = 0; i < candidates; ++i) {
    const int p = order_[i];
    if (expired(budget)) return p;
    refine(p, margin, box);
    if (table_[p].current <= margin) return p;
  }
  return -1;
}

// Closest: refines candidates, smallest bound first, until the next stored bound cannot beat the
// best one refined so far.
void Checker::refineClosest(int candidates, double margin, const Budget& budget, Box box) noexcept {
  double best = kInf;
  for (int i = 0; i < candidates; ++i) {
    const int p = order_[i];
    if (table_[p].current >= best) break;
    if (expired(budget)) break;
    refine(p, std::min(best, margin), box);
    best = std::min(best, table_[p].current);
  }
}

// NClosest: refines pairs, smallest bound first, until the next stored bound cannot beat the n-th
// smallest refined one. nbest_[0..fresh) holds the smallest fresh bounds so far, sorted.
void Checker::refineNClosest(int n, const Budget& budget, Box box) noexcept {
  int fresh = 0;
  double* best = nbest_.data();
  for (int p : order_) {
    const double nth = fresh >= n ? best[n - 1] : kInf;
    if (table_[p].current >= nth) break;
    if (expired(budget)) break;
    refine(p, nth, box);
    const double d = table_[p].current;
    int k = std::min(fresh, n - 1);
    if (fresh < n || d < best[k]) {
      while (k > 0 && best[k - 1] > d) {
        best[k] = best[k - 1];
        --k;
      }
      best[k] = d;
      fresh = std::min(fresh + 1, n);
    }
  }
}

// Distances: refines every pair to its full bound, smallest stored bound first.
void Checker::refineDistances(const Budget& budget, Box box) noexcept {
  for (int p : order_) {
    if (expired(budget)) break;
    refine(p, kInf, box);
  }
}

// The answer: every bound in the table is valid for this box. Reports the pairs the query type
// asks for into out_ and sets the result's distance, collision flag and pair list.
void Checker::publishAnswer(QueryType type, double margin, int hit, int n_wanted) noexcept {
  const int np = static_cast<int>(model_.pairs.size());
  int count = 0;  // pairs reported
  double min_distance = kInf;
  int argmin = -1;
  for (int p = 0; p < np; ++p) {
    if (table_[p].current < min_distance) {
      min_distance = table_[p].current;
      argmin = p;
    }
  }
  if (type == QueryType::Collision && hit >= 0) {
    report(hit, out_[count++]);
  } else if (type == QueryType::Closest && argmin >= 0 && min_distance <= margin) {
    report(argmin, out_[count++]);
  } else if (type == QueryType::NClosest) {
    std::sort(order_.begin(), order_.end(), [this](int x, int y) { return table_[x].current < table_[y].current; });
    for (int k = 0; k < std::min(n_wanted, np); ++k) report(order_[k], out_[count++]);
  } else if (type == QueryType::Distances) {
    for (int p = 0; p < np; ++p) report(p, out_[count++]);
  }
  if (result_.status != Status::Ok) min_distance = 0.0;
  result_.min_distance = min_distance;
  result_.collision = result_.status != Status::Ok || min_distance <= margin;
  result_.pairs = std::span<const PairDistance>(out_.data(), static_cast<std::size_t>(count));
}

}  // namespace kccd
