// Conservative joint sweeps and the point budget (ALGORITHMS.md sections 1-2). Internal.
#pragma once

#include <span>

#include "kccd/model.hpp"

namespace kccd::detail {

/// Largest angle one revolute piece may span; wider intervals are split into equal pieces.
inline constexpr double kMaxPieceAngle = 1.5707963267948966;  // pi / 2

/// How many output points one input point can become in sweepJoint() (worst case).
int sweepExpansion(const Joint& joint) noexcept;

/// Scratch space for sweepJoint(): room for one value per input point in each array.
struct SweepWork {
  double* rho;
  int* level;
  int* order;
};

/// Sweeps S(in, radius) through `joint` over the box [lo, hi] (joint.dof values each) and maps
/// the result into the joint's parent frame. Writes the core points to `out` (room for
/// sweepExpansion() * in.size()) and returns their count; `radius` grows as needed. A revolute
/// sweep refines its points' arcs only as far as `budget` output points allow (coarser arcs add
/// radius instead). Returns -1 when a value is not finite. The caller checks sweep-mode rules
/// (exact needs lo == hi).
int sweepJoint(const Joint& joint, const double* lo, const double* hi, std::span<const Vec3> in, Vec3* out,
               double& radius, int budget, SweepWork work) noexcept;

/// A sphere containing every position of sphere `in` under the joint's motion over [lo, hi],
/// in the joint's parent frame (cheap: no points are swept).
Sphere sweepSphere(const Joint& joint, const double* lo, const double* hi, const Sphere& in) noexcept;

/// Keeps at most `budget` of the n points (farthest-point selection) in pts[0..k) and grows
/// `radius` by the largest distance from a dropped point to a kept one. Returns k.
/// `dist` needs room for n values.
int reduceToBudget(Vec3* pts, int n, int budget, double* dist, double& radius) noexcept;

}  // namespace kccd::detail
