#include "chain_support.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rounding.hpp"

namespace kccd::detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative tolerance of a support value (times the chain's extent).
constexpr double kSupportTolerance = 1e-5;

// The largest distance from the axis (through the origin) of a point of the box centre +- half.
double rhoBoxBound(const Vec3& axis, const Vec3& centre, const Vec3& half) {
  double rho = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner(centre.x() + ((k & 1) ? half.x() : -half.x()), centre.y() + ((k & 2) ? half.y() : -half.y()),
                      centre.z() + ((k & 4) ? half.z() : -half.z()));
    rho = std::max(rho, (corner - axis.dot(corner) * axis).norm());
  }
  return roundedUp(rho, 8);
}

// The chain's sphere below level l (level 0: the body's own).
const Sphere& sphereBelow(const ChainView& c, int l) {
  return l == 0 ? c.base : c.levels[static_cast<std::size_t>(l) - 1].core;
}

}  // namespace

ChainLevel chainLevel(const JointMaps& maps, bool tangent, const Sphere& below, const Sphere& swept,
                      bool below_in_swept, double below_overshoot, const Vec3& below_box_centre,
                      const Vec3& below_box_half) noexcept {
  ChainLevel out;
  out.maps = &maps;
  out.count = tangent ? maps.count : maps.chord_count;
  // Images of the sphere below: ball(lin c + off, scale R) for every map; one sphere around them.
  Vec3 lo = Vec3::Constant(kInf), hi = Vec3::Constant(-kInf);
  Vec3 centres[JointMaps::kMax];
  for (int v = 0; v < out.count; ++v) {
    centres[v] = maps.lin[v] * below.center + maps.off[v];
    lo = lo.cwiseMin(centres[v]);
    hi = hi.cwiseMax(centres[v]);
    out.max_scale = std::max(out.max_scale, maps.scale[v]);
  }
  out.core.center = 0.5 * lo + 0.5 * hi;
  // The box: images of the box below (centre lin c + off, half-sizes |lin| h), one box around them.
  Vec3 blo = Vec3::Constant(kInf), bhi = Vec3::Constant(-kInf);
  for (int v = 0; v < out.count; ++v) {
    const Vec3 c = maps.lin[v] * below_box_centre + maps.off[v];
    const Vec3 h = maps.lin[v].cwiseAbs() * below_box_half;
    blo = blo.cwiseMin(c - h);
    bhi = bhi.cwiseMax(c + h);
  }
  out.box_centre = 0.5 * blo + 0.5 * bhi;
  const double box_guard = roundingGuard(blo.cwiseAbs().maxCoeff() + bhi.cwiseAbs().maxCoeff() + maps.offset_norm, 32);
  out.box_half = (0.5 * (bhi - blo)).array() + box_guard;
  out.has_box = out.box_centre.allFinite() && out.box_half.allFinite();
  double reach = 0.0;
  for (int v = 0; v < out.count; ++v)
    reach = std::max(reach, (centres[v] - out.core.center).norm() + below.radius * maps.scale[v]);
  const double extent = below.center.norm() + below.radius;  // |x| bound in the joint frame
  out.core.radius = roundedUp(reach, 8) + roundingGuard(extent * out.max_scale + maps.offset_norm, 32);
  // What the cover adds to the radius: the sagitta of the farthest point from the axis (chords of
  // a revolute joint), the 3-DOF joints' box reach, and rounding of the mapped points. A core set
  // of chords only lies in the hull of the true swept core, hence in `swept` (the same sphere the
  // point volumes use); apexes below reach beyond it, and then the core's own sphere counts too.
  const double swept_extent = swept.center.norm() + swept.radius;
  const double point_extent = below_in_swept ? swept_extent : std::max(extent, swept_extent);
  const bool rotation_apexes = tangent && maps.rotation_apexes;
  out.rotation_apexes = rotation_apexes;
  double growth = maps.fixed_growth + (rotation_apexes ? maps.apex_point_growth : maps.point_growth) * point_extent;
  if (maps.revolute && !tangent) {
    // The core's own sphere and box hold it too: the smallest of the bounds serves (a smaller
    // growth keeps the chord chain inside the point volumes, which use the swept sphere).
    const double own = std::min(rhoBound(maps.axis, below), rhoBoxBound(maps.axis, below_box_centre, below_box_half));
    const double rho = below_in_swept ? std::min(rhoBound(maps.axis, swept), own) : own;
    growth += maps.sagitta * rho;
  }
  out.growth =
      roundedUp(growth, 8) + roundingGuard(std::max(extent, swept_extent) * out.max_scale + maps.offset_norm, 32);
  // A map moves a point within e of a true position to within scale * e of the mapped true
  // position; an apex lies rho (1 / cos - 1) beyond the arc's middle, a true position.
  double overshoot = below_overshoot * out.max_scale;
  if (maps.revolute && tangent) overshoot += maps.apex_excess * rhoBound(maps.axis, swept);
  if (rotation_apexes) overshoot += maps.apex_excess * point_extent;
  out.overshoot = overshoot == 0.0 ? 0.0 : roundedUp(overshoot, 8) + roundingGuard(swept_extent, 32);
  return out;
}

int chainStackSize(int levels) noexcept { return levels * JointMaps::kMax + 1; }

double chainExtent(const ChainView& chain) noexcept {
  const Sphere& top = sphereBelow(chain, static_cast<int>(chain.levels.size()));
  return top.center.norm() + top.radius;
}

SupportHit chainSupport(const ChainView& chain, const Vec3& dir, ChainWork& work, int max_nodes, double tolerance,
                        long* nodes) noexcept {
  const int depth = static_cast<int>(chain.levels.size());
  const double dn = dir.norm();
  const Vec3 d = dn > 0.0 ? Vec3(dir / dn) : Vec3::UnitX();
  const std::span<const Vec3> pts = chain.points;
  const int np = static_cast<int>(pts.size());

  // The best leaf: its value d.x, the choice per level and the point index.
  double best = -kInf;
  int best_point = 0;
  double overflow = -kInf;  // largest bound left unexplored when the node limit stops the search
  double pruned = -kInf;    // largest bound pruned within the tolerance of the best leaf
  int visited = 0;
  // Branches whose bound exceeds the best leaf by at most this are not explored: near-ties are
  // common (directions where several maps give almost the same value), and the slack they leave
  // costs the distance bound at most this much per support.
  if (!(tolerance >= 0.0)) tolerance = kSupportTolerance * chainExtent(chain);

  auto leaf = [&](const Vec3& row, double offset) {
    int arg = 0;
    double value = row.dot(pts[0]);
    for (int i = 1; i < np; ++i) {
      const double x = row.dot(pts[static_cast<std::size_t>(i)]);
      if (x > value) {
        value = x;
        arg = i;
      }
    }
    value += offset;
    if (value > best) {
      best = value;
      best_point = arg;
      std::copy(work.choice, work.choice + depth, work.best_choice);
    }
  };
  if (depth == 0) {
    leaf(d, 0.0);
  } else {
    if (work.warm) {  // the last best leaf first: its value prunes most of the tree at once
      Vec3 row = d;
      double offset = 0.0;
      for (int level = depth; level >= 1; --level) {
        const ChainLevel& lv = chain.levels[static_cast<std::size_t>(level) - 1];
        const int v = std::clamp(work.best_choice[level - 1], 0, lv.count - 1);
        work.choice[level - 1] = v;
        offset += row.dot(lv.maps->off[v]);
        row = lv.maps->lin[v].transpose() * row;
      }
      leaf(row, offset);
    }
    ChainEntry* stack = work.stack;
    int top = 0;
    // Pushes the children of a node at `level` (maps of that level still to choose) in ascending
    // bound order, so that the most promising child is popped first.
    auto expand = [&](int level, const Vec3& row, double offset) {
      const ChainLevel& lv = chain.levels[static_cast<std::size_t>(level) - 1];
      const Sphere& s = sphereBelow(chain, level - 1);
      const ChainLevel* hull = level >= 2 ? &chain.levels[static_cast<std::size_t>(level) - 2] : nullptr;
      const int first = top;
      auto push = [&](int v, double row_off) {  // row_off: row . off[v]
        ChainEntry e;
        e.row = lv.maps->lin[v].transpose() * row;
        e.offset = offset + row_off;
        const double row_norm = e.row.norm();
        e.bound = e.offset + e.row.dot(s.center) + row_norm * s.radius;
        if (hull != nullptr && hull->has_box) {
          e.bound = std::min(e.bound, e.offset + e.row.dot(hull->box_centre) + e.row.cwiseAbs().dot(hull->box_half));
        }
        e.level = level;
        e.choice = v;
        int k = top++;
        while (k > first && stack[k - 1].bound > e.bound) {
          stack[k] = stack[k - 1];
          --k;
        }
        stack[k] = e;
      };
      if (!lv.maps->shared_lin) {
        for (int v = 0; v < lv.count; ++v) push(v, row.dot(lv.maps->off[v]));
        return;
      }
      // Maps that share their linear part (translations) differ only by the offset: the child
      // of the largest offset along the row is the best of them, whatever lies below.
      int best_v = 0;
      double best_off = row.dot(lv.maps->off[0]);
      for (int v = 1; v < lv.count; ++v) {
        const double o = row.dot(lv.maps->off[v]);
        if (o > best_off) {
          best_off = o;
          best_v = v;
        }
      }
      push(best_v, best_off);
    };
    expand(depth, d, 0.0);
    while (top > 0) {
      const ChainEntry e = stack[--top];
      if (e.bound <= best + tolerance) {  // cannot beat the best leaf by more than the tolerance
        if (e.bound > best) pruned = std::max(pruned, e.bound);
        continue;
      }
      if (++visited > max_nodes) {
        overflow = std::max(overflow, e.bound);
        for (int k = 0; k < top; ++k) overflow = std::max(overflow, stack[k].bound);
        break;
      }
      work.choice[e.level - 1] = e.choice;
      if (e.level == 1) {
        leaf(e.row, e.offset);
      } else {
        expand(e.level - 1, e.row, e.offset);
      }
    }
  }
  if (nodes != nullptr) *nodes += visited;
  work.warm = true;

  // The point: the body point mapped up through the chosen maps.
  Vec3 x = pts[static_cast<std::size_t>(best_point)];
  std::uint64_t key = static_cast<std::uint64_t>(best_point);
  double scale = 1.0;
  for (int l = 0; l < depth; ++l) {
    const ChainLevel& lv = chain.levels[static_cast<std::size_t>(l)];
    const int v = work.best_choice[l];
    x = lv.maps->lin[v] * x + lv.maps->off[v];
    static_assert(JointMaps::kMax < 16, "one hex digit per level");
    key = key * 16u + static_cast<std::uint64_t>(v) + 1u;
    scale *= lv.max_scale;
  }
  // Rounding: values and the point are sums of products through `depth` levels of magnitude at
  // most the chain's extent (grown by the maps' norms).
  const double guard = roundingGuard((chainExtent(chain) + 1e-300) * scale, 16 * (depth + 2));
  const double value = d.dot(x);
  const double upper = std::max({best, overflow, pruned});
  return SupportHit{x, key, std::max(0.0, upper - value) + guard};
}

}  // namespace kccd::detail
