#include "sweep.hpp"

#include <algorithm>
#include <cmath>
#include "rounding.hpp"

#include "kccd/rotation.hpp"

namespace kccd::detail {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kTwoPi = 6.283185307179586;

// Pieces for a revolute interval of width `width` (capped at a full turn).
int revolutePieces(double width) {
  if (!(width > 0.0)) return 0;
  return std::max(1, static_cast<int>(std::ceil(std::min(width, kTwoPi) / kMaxPieceAngle - 1e-12)));
}

// A revolute interval [lo, hi] as an arc of small angles: start in [-pi - 1e-14, pi] and width in
// [0, 2 pi]. The ends may be any finite doubles (files write +-3.4e38 for "unlimited"): evaluating
// cos(lo + k * step) directly would lose the step where one ulp of lo is radians. sin and cos of
// any double are accurate to an ulp, so atan2 gives the start to a few ulps of pi; the width
// hi - lo is exact or within a relative eps. The arc is widened by both errors, so it contains
// every angle of the interval.
struct Arc {
  double start;
  double width;
};

Arc revoluteArc(double lo, double hi) {
  const double width = hi - lo;  // may be +inf for ends near the double range: a full turn
  if (!(width < kTwoPi)) return {-kPi, kTwoPi};
  if (width == 0.0) return {lo, 0.0};  // a single angle: evaluated directly, exactly
  if (std::abs(lo) <= kTwoPi) return {lo, std::min(kTwoPi, roundedUp(width, 2) + roundingGuard(kTwoPi, 4))};
  const double start_error = roundingGuard(kTwoPi, 16);
  const double start = std::atan2(std::sin(lo), std::cos(lo)) - start_error;
  return {start, std::min(kTwoPi, roundedUp(width, 2) + 2.0 * start_error)};
}

double maxNorm(std::span<const Vec3> pts) {
  double m = 0.0;
  for (const Vec3& p : pts) m = std::max(m, p.norm());
  return m;
}

// Revolute sweep in the joint frame. Each point's arc is covered at one of three levels:
//   tangent  - chord ends plus tangent apexes (2*pieces + 1 points), exact cover;
//   chord    - chord ends (pieces + 1 points), radius grows by the sagitta rho (1 - cos(step / 2));
//   single   - the arc's middle point (1 point), radius grows by the half-arc chord 2 rho sin(w / 4).
// The sweep mode sets the best level (accurate: tangent, fast: chord). When the budget cannot hold
// every point at that level, points far from the axis keep the finer levels first, which keeps the
// radius growth (the largest error over all points) as small as the budget allows.
int sweepRevolute(const Joint& j, double lo, double hi, std::span<const Vec3> in, Vec3* out, double& radius,
                  int budget, SweepWork work) {
  const Vec3& a = j.axis;
  const Arc arc = revoluteArc(lo, hi);
  lo = arc.start;
  const double width = arc.width;
  const int pieces = revolutePieces(width);
  const int n_in = static_cast<int>(in.size());
  // Points are written straight into the parent frame: with A = R_o axial + t, B = R_o radial and
  // C = R_o (axis x radial), the point rotated by angle q is A + cos(q) B + sin(q) C.
  const Eigen::Matrix3d& rot = j.origin.linear();
  const Vec3& t = j.origin.translation();
  const double in_norm = maxNorm(in);
  if (pieces == 0) {  // a single angle: exact
    const double c = std::cos(lo), s = std::sin(lo);
    for (int i = 0; i < n_in; ++i) {
      const Vec3 axial = a.dot(in[i]) * a;
      const Vec3 radial = in[i] - axial;
      out[i] = rot * (axial + c * radial + s * a.cross(radial)) + t;
    }
    radius += roundingGuard(in_norm + t.norm(), 32);
    return n_in;
  }
  const double step = width / pieces;
  double c_end[5], s_end[5], c_mid[4], s_mid[4];
  for (int k = 0; k <= pieces; ++k) {
    c_end[k] = std::cos(lo + k * step);
    s_end[k] = std::sin(lo + k * step);
  }
  const double half_cos = std::cos(0.5 * step);
  for (int k = 0; k < pieces; ++k) {
    c_mid[k] = std::cos(lo + (k + 0.5) * step) / half_cos;
    s_mid[k] = std::sin(lo + (k + 0.5) * step) / half_cos;
  }
  const double c_centre = std::cos(lo + 0.5 * width), s_centre = std::sin(lo + 0.5 * width);
  const double sagitta = 1.0 - half_cos;                   // per unit rho
  const double half_chord = 2.0 * std::sin(0.25 * width);  // per unit rho

  // Levels: 0 single, 1 chord, 2 tangent. Start everyone at the mode's level; if that does not
  // fit, start at single and refine the points farthest from the axis first.
  const int top = j.sweep == SweepMode::Accurate ? 2 : 1;
  const int cost[3] = {1, pieces + 1, 2 * pieces + 1};
  int* level = work.level;
  double* rho = work.rho;
  int* order = work.order;
  const bool fits = n_in * cost[top] <= budget;
  for (int i = 0; i < n_in; ++i) {
    rho[i] = (in[i] - a.dot(in[i]) * a).norm();
    level[i] = fits ? top : 0;
    order[i] = i;
  }
  if (!fits) {
    std::sort(order, order + n_in, [rho](int x, int y) { return rho[x] > rho[y]; });
    int total = n_in;
    for (int up = 1; up <= top; ++up) {
      for (int k = 0; k < n_in; ++k) {
        const int i = order[k];
        const int extra = cost[up] - cost[up - 1];
        if (level[i] != up - 1 || total + extra > budget) break;
        level[i] = up;
        total += extra;
      }
    }
  }
  double growth = 0.0;
  int n = 0;
  for (int i = 0; i < n_in; ++i) {
    const Vec3& p = in[i];
    const Vec3 axial = a.dot(p) * a;
    const Vec3 radial = p - axial;
    if (rho[i] <= 1e-12 * (1.0 + p.norm())) {  // on the axis: it stays within 2 rho of itself
      out[n++] = rot * p + t;
      growth = std::max(growth, 2.0 * rho[i]);
      continue;
    }
    const Vec3 A = rot * axial + t;
    const Vec3 B = rot * radial;
    const Vec3 C = rot * a.cross(radial);
    switch (level[i]) {
      case 0:
        out[n++] = A + c_centre * B + s_centre * C;
        growth = std::max(growth, rho[i] * half_chord);
        break;
      case 1:
        for (int k = 0; k <= pieces; ++k) out[n++] = A + c_end[k] * B + s_end[k] * C;
        growth = std::max(growth, rho[i] * sagitta);
        break;
      default:
        for (int k = 0; k <= pieces; ++k) out[n++] = A + c_end[k] * B + s_end[k] * C;
        for (int k = 0; k < pieces; ++k) out[n++] = A + c_mid[k] * B + s_mid[k] * C;
        break;
    }
  }
  // Rounding: the outputs (at most |p| / cos(step / 2) + |t| from the origin) err by a few ulps.
  if (!std::isfinite(growth)) return -1;
  radius += roundedUp(growth, 8) + roundingGuard(in_norm / half_cos + t.norm(), 32);
  return n;
}

// A 3-DOF joint's interval box [lo, hi]: its centre and the radius of the ball around the centre
// that holds the box, widened by the joint's error bound.
struct Box3 {
  Vec3 centre;
  double reach;
};

Box3 box3(const Joint& joint, const double* lo, const double* hi) {
  const Vec3 l(lo[0], lo[1], lo[2]), h(hi[0], hi[1], hi[2]);
  return {0.5 * l + 0.5 * h, 0.5 * (h - l).norm() + joint.error};
}

// A rotation3d box: the rotation of its centre and the most any rotation in the box differs
// from it. Every rotation vector in the box lies within |half-diagonal| of the centre, and exp is
// 1-Lipschitz on SO(3). The centre's angle |c| is itself rounded (by a few ulps of |c|, which is
// radians for |c| near 1e16), so that error joins the reach; a reach of pi or more allows every
// rotation and the centre's is not needed.
struct Rotation3 {
  Eigen::Matrix3d rot;
  double reach;
};

Rotation3 rotation3(const Box3& box) {
  const double angle = box.centre.stableNorm();
  const double reach = box.reach + roundingGuard(angle, 8);
  if (!(reach < kPi)) return {Eigen::Matrix3d::Identity(), kPi};
  if (angle == 0.0) return {Eigen::Matrix3d::Identity(), reach};
  return {rotationAboutVector(box.centre, angle), reach};
}

// A rotation by at most `reach` radians moves a point p by at most the returned factor times |p|.
double rotationChord(double reach) { return reach >= kPi ? 2.0 : 2.0 * std::sin(0.5 * reach); }

}  // namespace

int sweepExpansion(const Joint& joint) noexcept {
  const int pieces = revolutePieces(kTwoPi);
  switch (joint.type) {
    case JointType::Revolute: return joint.sweep == SweepMode::Accurate ? 2 * pieces + 1 : pieces + 1;
    case JointType::Prismatic: return 2;
    default: return 1;
  }
}

int sweepJoint(const Joint& joint, const double* lo, const double* hi, std::span<const Vec3> in, Vec3* out,
               double& radius, int budget, SweepWork work) noexcept {
  if (joint.type == JointType::Revolute)  // writes straight into the parent frame
    return sweepRevolute(joint, lo[0], hi[0], in, out, radius, budget, work);
  int n = 0;
  const double in_norm = maxNorm(in);
  switch (joint.type) {
    case JointType::Fixed:
    case JointType::Revolute:
      for (const Vec3& p : in) out[n++] = p;
      break;
    case JointType::Prismatic:
      // Minkowski sum with the segment [lo, hi] along the axis: exact.
      for (const Vec3& p : in) out[n++] = p + lo[0] * joint.axis;
      if (hi[0] > lo[0])
        for (const Vec3& p : in) out[n++] = p + hi[0] * joint.axis;
      radius += roundingGuard(in_norm + std::max(std::abs(lo[0]), std::abs(hi[0])), 8);
      break;
    case JointType::Translation3d: {
      // Translate by the box centre; the ball around it covers the box and the error bound.
      const Box3 box = box3(joint, lo, hi);
      for (const Vec3& p : in) out[n++] = p + box.centre;
      radius += box.reach + roundingGuard(in_norm + box.centre.norm(), 8);
      break;
    }
    case JointType::Rotation3d: {
      // Rotate by the box centre; every other rotation in the box moves a point by at most
      // rotationChord() |p|.
      const Rotation3 r3 = rotation3(box3(joint, lo, hi));
      for (const Vec3& p : in) out[n++] = r3.rot * p;
      radius += roundedUp(rotationChord(r3.reach) * in_norm, 4) + roundingGuard(in_norm, 16);
      break;
    }
  }
  // Into the parent frame.
  const Eigen::Matrix3d& rot = joint.origin.linear();
  const Vec3& t = joint.origin.translation();
  double out_norm = 0.0;
  for (int k = 0; k < n; ++k) {
    out[k] = rot * out[k] + t;
    out_norm = std::max(out_norm, out[k].cwiseAbs().maxCoeff());
  }
  radius += roundingGuard(out_norm + t.norm(), 8);
  if (!std::isfinite(out_norm) || !std::isfinite(radius)) return -1;
  return n;
}

int reduceToBudget(Vec3* pts, int n, int budget, double* dist, double& radius) noexcept {
  if (n <= budget) return n;
  // Start from the point farthest from the centroid: an extreme point of the set.
  Vec3 centroid = Vec3::Zero();
  for (int i = 0; i < n; ++i) centroid += pts[i];
  centroid /= n;
  int first = 0;
  double far = -1.0;
  for (int i = 0; i < n; ++i) {
    const double d = (pts[i] - centroid).squaredNorm();
    if (d > far) {
      far = d;
      first = i;
    }
  }
  std::swap(pts[0], pts[first]);
  for (int i = 1; i < n; ++i) dist[i] = (pts[i] - pts[0]).squaredNorm();
  // Farthest-point selection: kept points are pts[0..k), dist[i] = squared distance to them.
  for (int k = 1; k < budget; ++k) {
    int best = k;
    for (int i = k + 1; i < n; ++i)
      if (dist[i] > dist[best]) best = i;
    std::swap(pts[k], pts[best]);
    std::swap(dist[k], dist[best]);
    for (int i = k + 1; i < n; ++i) dist[i] = std::min(dist[i], (pts[i] - pts[k]).squaredNorm());
  }
  double worst = 0.0;
  for (int i = budget; i < n; ++i) worst = std::max(worst, dist[i]);
  // Each dropped point lies within sqrt(worst) of a kept one, hence of their hull.
  radius += roundedUp(std::sqrt(worst), 4);
  return budget;
}

Sphere sweepSphere(const Joint& joint, const double* lo, const double* hi, const Sphere& in) noexcept {
  Sphere out = in;
  const Vec3& c = in.center;
  switch (joint.type) {
    case JointType::Fixed: break;
    case JointType::Revolute: {
      // The centre's arc lies within rho sin(w / 2) of its chord's middle (w < pi), or within
      // rho of the axis point for wider arcs.
      const Vec3& a = joint.axis;
      const Vec3 axial = a.dot(c) * a;
      const Vec3 radial = c - axial;
      const double rho = radial.norm();
      const Arc arc = revoluteArc(lo[0], hi[0]);
      const double width = arc.width;
      if (width >= kPi) {
        out.center = axial;
        out.radius += rho;
      } else {
        const double mid = arc.start + 0.5 * width;
        out.center = axial + std::cos(0.5 * width) * (std::cos(mid) * radial + std::sin(mid) * a.cross(radial));
        out.radius += rho * std::sin(0.5 * width);
      }
      out.radius += roundingGuard(c.norm(), 16);
      break;
    }
    case JointType::Prismatic:
      out.center = c + 0.5 * (lo[0] + hi[0]) * joint.axis;
      out.radius += 0.5 * (hi[0] - lo[0]) + roundingGuard(c.norm() + std::abs(lo[0]) + std::abs(hi[0]), 8);
      break;
    case JointType::Translation3d: {
      const Box3 box = box3(joint, lo, hi);
      out.center = c + box.centre;
      out.radius += box.reach + roundingGuard(c.norm() + out.center.norm(), 8);
      break;
    }
    case JointType::Rotation3d: {
      const Rotation3 r3 = rotation3(box3(joint, lo, hi));
      out.center = r3.rot * c;
      out.radius += roundedUp(rotationChord(r3.reach) * c.norm(), 4) + roundingGuard(c.norm(), 16);
      break;
    }
  }
  out.center = joint.origin * out.center;
  out.radius += roundingGuard(out.center.norm() + joint.origin.translation().norm(), 8);
  return out;
}

}  // namespace kccd::detail
