// Queries over interval boxes: lazily swept volumes shared by all pairs, pairs compared in their
// least-common-ancestor frame, and an any-time table of lower bounds refined smallest first (the
// exact stage and the split refinement of a pair: checker_exact.cpp).
#include "kccd/checker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "bounding_sphere.hpp"
#include "chain_support.hpp"
#include "gjk_core.hpp"
#include "kccd/distance.hpp"
#include "kccd/kinematics.hpp"
#include "point_scan.hpp"
#include "rounding.hpp"
#include "support_cells.hpp"
#include "sweep.hpp"

namespace kccd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// With QueryOptions::tight_volumes, a sweep whose radius growth exceeds this fraction of the swept
// sphere's radius also tries the other cover (chords for every point, reduced to the budget).
constexpr double kCoarseCover = 0.02;
// A pair's last GJK direction is its warm start while its points have moved at most this many times
// its stored bound since (Checker::refresh).
constexpr double kWarmStartReach = 2.0;
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
  // Support cells only for the bodies some pair compares (a one-pair model, as the pair proofs
  // make, builds two).
  std::vector<bool> paired(model.bodies.size(), false);
  for (const BodyPair& pair : model.pairs) {
    paired[static_cast<std::size_t>(pair.a)] = true;
    paired[static_cast<std::size_t>(pair.b)] = true;
  }
  for (const Body& body : model.bodies) {
    double norm_sq = 0.0;
    for (const Vec3& p : body.points) norm_sq = std::max(norm_sq, p.squaredNorm());
    base_norm_.push_back(detail::roundedUp(std::sqrt(norm_sq), 2));
    base_summary_.push_back(detail::summarize(body.points));
    base_cells_.push_back(paired[base_cells_.size()] ? detail::supportCells(body.points) : detail::SupportCells{});
    base_sphere_.push_back(detail::boundingSphere(body.points, 0.0));
    Vec3 lo = body.points[0], hi = body.points[0];
    for (const Vec3& p : body.points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    base_box_.push_back(0.5 * lo + 0.5 * hi);
    base_box_.push_back(0.5 * (hi - lo) +
                        Vec3::Constant(detail::roundingGuard(lo.cwiseAbs().maxCoeff() + hi.cwiseAbs().maxCoeff(), 4)));
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
      v.body = b;
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
    v.exact = true;
    v.own = true;
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
          case JointType::Fixed:
            break;
          case JointType::Revolute:
            reach[0] += extent;
            break;
          case JointType::Prismatic:
            reach[0] += 1.0;
            break;
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
  // A rigid level over the body itself or a posed level: posed in turn, no point moved.
  if (below->exact && (level == 1 || below->posed) && joint.error == 0.0 && below->count <= v.capacity) {
    bool single = true;
    for (int k = 0; k < joint.dof; ++k) single = single && lo[k] == hi[k];
    if (single && pose(v, *below, level == 1, joint, lo, trig)) {
      v.stamp = cycle_;
      ++result_.stats.volumes_swept;
      return &v;
    }
  }
  const SschView in = written(*below);
  int n = detail::sweepJoint(joint, lo, hi, trig, in.points, scratch_.data(), radius, v.capacity, scratch_dist_.data(),
                             *below_sphere);
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
    int m = detail::sweepJoint(joint, lo, hi, trig, in.points, scratch_alt_.data(), alt_radius,
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
  // Still the body's points, rigidly moved: a joint at one value, with no error bound, and no
  // point dropped (the budget holds them all) or replaced by the other cover.
  bool rigid = below->exact && n == below->count && kept == scratch_.data() && joint.error == 0.0;
  for (int k = 0; k < joint.dof && rigid; ++k) rigid = lo[k] == hi[k];
  v.exact = rigid;
  v.posed = false;
  v.count = n;
  v.radius = radius;
  if (rigid) {
    // The sphere below moved by the same map: its centre's error is the guard its own sweep adds,
    // each point's at most the guard the points' sweep added (counted twice: on the point and in
    // the volume's radius).
    Vec3 centre;
    double centre_radius = below->bound.radius;
    if (detail::sweepJoint(joint, lo, hi, trig, {&below->bound.center, 1}, &centre, centre_radius, 1,
                           scratch_dist_.data(), *below_sphere) != 1)
      return nullptr;
    v.bound.center = centre;
    v.bound.radius = detail::roundedUp(centre_radius + 2.0 * (radius - below_radius), 4);
  } else {
    v.bound = detail::boundingSphere(view(v).points, radius);
  }
  if (!v.bound.center.allFinite() || !std::isfinite(v.bound.radius)) return nullptr;
  v.stamp = cycle_;
  ++result_.stats.volumes_swept;
  return &v;
}

// Poses rigid volume v from the volume below it (`first`: below is the body itself) and the
// joint's rigid map at `value`: lin' = A lin, off' = A off + b. Error bounds, with g = kRigidGuardUlps
// ulps and |.| the operator norm (bounded by Frobenius'): the map applied to a vector x errs by
// g |x| (each column of lin, so A lin by g |lin|_F) and to a point x by g (|x| + magnitude) (off);
// the exact map's linear part is within g sqrt(3) of A. Returns false when a value is not finite.
bool Checker::pose(Volume& v, const Volume& below, bool first, const Joint& joint, const double* value,
                   const detail::RevoluteTrig& trig) noexcept {
  using detail::roundedUp;
  using detail::roundingGuard;
  const detail::RigidMap m = detail::rigidMap(joint, value, trig);
  if (!m.ok) return false;
  const Eigen::Matrix3d lin0 = first ? Eigen::Matrix3d::Identity() : below.lin;
  const Vec3 off0 = first ? Vec3::Zero() : below.off;
  const double lin_error0 = first ? 0.0 : below.lin_error, off_error0 = first ? 0.0 : below.off_error;
  constexpr int g = detail::kRigidGuardUlps;
  const double exact_norm = roundedUp(m.lin.norm(), 4) + roundingGuard(1.0, 2 * g);  // bound on |exact A|
  v.lin = m.lin * lin0;
  v.off = m.lin * off0 + m.off;
  v.lin_error = roundedUp(exact_norm * lin_error0 + roundingGuard(roundedUp(lin0.norm(), 4), g), 4);
  v.off_error = roundedUp(exact_norm * off_error0 + roundingGuard(off0.norm() + m.magnitude, g), 4);
  // A point p of the body (|p| <= P) moved in floating point lies within
  // lin_error P + off_error + 8 ulps (|lin|_F P + |off|) of its exact place; a support chosen by
  // the direction moved into the body's frame (lin^T d, within lin_error + 8 ulps |lin|_F of the
  // exact one) falls short of the best by at most twice that times P, plus the dot products'
  // rounding. Both go into the radius.
  const Body& body = model_.bodies[v.body];
  const double P = base_norm_[v.body];
  const double lin_norm = roundedUp(v.lin.norm(), 4);
  const double off_norm = roundedUp(v.off.norm(), 4);
  const double moved = v.lin_error * P + v.off_error + roundingGuard(lin_norm * P + off_norm, 8);
  const double chosen = 2.0 * P * (v.lin_error + roundingGuard(lin_norm, 8)) + roundingGuard(lin_norm * P, 16);
  v.radius = body.radius + roundedUp(moved + chosen, 4);
  v.count = static_cast<int>(body.points.size());
  v.start = v.lin * base_summary_[v.body].centroid + v.off;
  v.scale = roundedUp(lin_norm * P + off_norm, 8);
  // The sphere below moved by the same map (its centre within the map's guard of its exact place)
  // and grown as the radius grew.
  v.bound.center = m.lin * below.bound.center + m.off;
  v.bound.radius = roundedUp(below.bound.radius + roundingGuard(below.bound.center.norm() + m.magnitude, g) +
                                 2.0 * std::max(0.0, v.radius - below.radius),
                             4);
  if (!v.lin.allFinite() || !v.off.allFinite() || !std::isfinite(v.radius) || !std::isfinite(v.scale) ||
      !v.bound.center.allFinite() || !std::isfinite(v.bound.radius))
    return false;
  v.exact = true;
  v.posed = true;
  v.written = 0;
  return true;
}

// The volume's points (a posed volume's written into the arena first).
SschView Checker::written(const Volume& v) noexcept {
  if (v.posed && v.written != cycle_) {
    const std::vector<Vec3>& pts = model_.bodies[v.body].points;
    Vec3* out = points_.data() + v.offset;
    for (std::size_t i = 0; i < pts.size(); ++i) out[i] = v.lin * pts[i] + v.off;
    v.written = cycle_;
  }
  return view(v);
}

namespace {

// GJK's support on one side of a pair: a swept point set as it is, or the body's own points
// (a level-0 or posed volume) searched in the body's frame among its direction cell's
// candidates (the same largest value as a scan of all, support_cells.hpp), moved when posed.
struct SideSupport {
  const Vec3* pts = nullptr;
  std::size_t n = 0;
  const detail::SupportCells* cells = nullptr;  // null: scan every point
  bool posed = false;
  Eigen::Matrix3d lin = Eigen::Matrix3d::Identity();
  Vec3 off = Vec3::Zero();
  detail::SupportHit operator()(const Vec3& dir) const noexcept {
    if (cells == nullptr) {
      const int i = detail::supportIndex({pts, n}, dir);
      return {pts[static_cast<std::size_t>(i)], static_cast<std::uint64_t>(i), 0.0};
    }
    const Vec3 local = posed ? Vec3(lin.transpose() * dir) : dir;
    const int i = detail::cellSupport(*cells, {pts, n}, local);
    const Vec3& p = pts[static_cast<std::size_t>(i)];
    return {posed ? Vec3(lin * p + off) : p, static_cast<std::uint64_t>(i), 0.0};
  }
};

}  // namespace

// The distance of two volumes of a pair: GJK on their supports (SideSupport), which is
// distance() on their points up to the rounding a posed volume's radius covers.
DistanceResult Checker::pairDistance(const Volume& a, const Volume& b, const GjkOptions& options) noexcept {
  for (const double r : {a.radius, b.radius})
    if (!(r >= 0.0 && r <= std::numeric_limits<double>::max())) return DistanceResult{};  // InvalidInput
  detail::SetsInfo info;
  info.starts_in_hulls = true;  // centroids of the points (a posed volume's: moved with them)
  SideSupport side[2];
  const Volume* vol[2] = {&a, &b};
  for (int k = 0; k < 2; ++k) {
    const Volume& v = *vol[k];
    SideSupport& s = side[k];
    const auto body = static_cast<std::size_t>(v.body);
    const std::vector<Vec3>& pts = model_.bodies[body].points;
    if (v.posed) {
      s = {pts.data(), pts.size(), &base_cells_[body], true, v.lin, v.off};
      (k == 0 ? info.scale_a : info.scale_b) = v.scale;
      (k == 0 ? info.start_a : info.start_b) = v.start;
    } else if (v.own) {
      const detail::PointSummary& sum = base_summary_[body];
      if (!sum.finite) return DistanceResult{};  // InvalidInput
      s = {pts.data(), pts.size(), &base_cells_[body], false, Eigen::Matrix3d::Identity(), Vec3::Zero()};
      (k == 0 ? info.scale_a : info.scale_b) = sum.scale;
      (k == 0 ? info.start_a : info.start_b) = sum.centroid;
    } else {
      const SschView w = view(v);
      const detail::PointSummary sum = detail::summarize(w.points);
      if (!sum.finite) return DistanceResult{};  // InvalidInput
      s = {w.points.data(), w.points.size(), nullptr, false, Eigen::Matrix3d::Identity(), Vec3::Zero()};
      (k == 0 ? info.scale_a : info.scale_b) = sum.scale;
      (k == 0 ? info.start_a : info.start_b) = sum.centroid;
    }
  }
  return detail::gjkDistance(side[0], side[1], a.radius, b.radius, info, options);
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
  v.swept_sphere =
      detail::sweepSphere(joint, box.lower.data() + joint.state_offset, box.upper.data() + joint.state_offset,
                          revoluteTrig(path_[idx - 1], box), *below);
  if (!v.swept_sphere.center.allFinite() || !std::isfinite(v.swept_sphere.radius)) return nullptr;
  v.sphere_stamp = geo_cycle_;
  return &v.swept_sphere;
}

SschView Checker::sweptVolume(int body, int frame) noexcept {
  if (body < 0 || body >= static_cast<int>(levels_.size())) return {};
  for (int level = 0; level < levels_[body]; ++level) {
    if (path_[level_begin_[body] + level] != frame) continue;
    const Volume* v = volume(body, level, Box{lower_, upper_});
    return v == nullptr ? SschView{} : written(*v);
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
      // The last direction starts GJK while the pair's points have moved at most twice the stored
      // bound since it was found (a moving robot); after a jump it points anywhere, and the
      // volumes' start points (their centroids) do better: random poses of the Panda and the
      // xArm 7 at the default import take 20-30 % fewer iterations, a trajectory as many.
      opt.warm_start = e.valid && e.moved <= kWarmStartReach * e.bound ? &e.direction : nullptr;
      // A collision query asks only whether the bound is within the margin. For two rigid volumes
      // (the bodies at one configuration, no exact stage after) GJK stops once two points of them
      // are (its upper bound): no refinement could lift the bound above the margin, and the lower
      // bound it has is the verdict. Other pairs go on to the exact stage, which starts from GJK's
      // last direction: a converged one saves it more than the early stop would.
      if (result_.type == QueryType::Collision && va->exact && vb->exact) opt.stop_below = result_.margin;
      const DistanceResult d = pairDistance(*va, *vb, opt);
      ++result_.stats.gjk_calls;
      result_.stats.gjk_iterations += d.iterations;
      if (d.status == GjkStatus::InvalidInput) return fail();
      bound = std::max(bound, d.distance);
      e.direction = d.direction;
      e.witness_a = d.witness_a;
      e.witness_b = d.witness_b;
      e.gjk = true;
      // The exact stage searches the same points when both volumes are the bodies rigidly moved
      // (the box is a single configuration for the pair): GJK's bound is already theirs.
      if (bound <= std::min(stop_above, exact_below_) && !(va->exact && vb->exact)) {
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
  e.moved = 0.0;
  for (int k = reach_begin_[p]; k < reach_begin_[p + 1]; ++k) {
    box_[2 * k] = box.lower[reach_state_[k]];
    box_[2 * k + 1] = box.upper[reach_state_[k]];
  }
  return bound;
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
                 : options.exact_below >= 0.0                                    ? options.exact_below
                 : options.type == QueryType::Collision                          ? margin
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
  budget.deadline = start + (budget.timed ? std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double, std::micro>(options.budget_us))
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
  int hit = -1;                                                    // Collision: the pair reported
  switch (options.type) {
    case QueryType::Collision:
      hit = refineCollision(candidates, margin, budget, box);
      break;
    case QueryType::Closest:
      refineClosest(candidates, margin, budget, box);
      break;
    case QueryType::NClosest:
      refineNClosest(n_wanted, budget, box);
      break;
    case QueryType::Distances:
      refineDistances(budget, box);
      break;
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
    e.moved = moved;
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
