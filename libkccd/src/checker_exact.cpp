// The exact stage of a pair's refinement (chains of exact support points searched by GJK) and the
// split refinement of its box: part of Checker (checker.cpp holds the rest of the query).
#include "kccd/checker.hpp"

#include <algorithm>
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
using detail::shrunkBound;

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
  double chord_upper = kInf;   // upper bound on the distance of the chord chains' cores
  double chord_lower = -kInf;  // the chord chains' lower bound
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
  std::sort(split_order_.begin(), split_order_.begin() + leaves, [&](int x, int y) {
    return split_key_[static_cast<std::size_t>(x)] < split_key_[static_cast<std::size_t>(y)];
  });
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
        case JointType::Fixed:
          break;
        case JointType::Revolute:
          g[0] += sign * n.dot((f.linear() * j.axis).cross(arm));
          break;
        case JointType::Prismatic:
          g[0] += sign * n.dot(f.linear() * j.axis);
          break;
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

}  // namespace kccd
