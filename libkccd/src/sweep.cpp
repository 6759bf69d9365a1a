#include "sweep.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kccd::detail {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 6.283185307179586;

// Pieces for a revolute interval of width `width` (capped at a full turn).
int revolutePieces(double width) {
  if (!(width > 0.0)) return 0;
  return std::max(1, static_cast<int>(std::ceil(std::min(width, kTwoPi) / kMaxPieceAngle - 1e-12)));
}

double maxNorm(std::span<const Vec3> pts) {
  double m = 0.0;
  for (const Vec3& p : pts) m = std::max(m, p.norm());
  return m;
}

// Revolute sweep in the joint frame: chords (fast) or chords plus tangent apexes (accurate).
int sweepRevolute(const Joint& j, double lo, double hi, std::span<const Vec3> in, Vec3* out, double& radius) {
  const Vec3& a = j.axis;
  const double width = std::min(hi - lo, kTwoPi);
  const int pieces = revolutePieces(width);
  const double step = pieces > 0 ? width / pieces : 0.0;
  const bool accurate = j.sweep == SweepMode::Accurate;
  // Angles: piece ends lo + k*step (k = 0..pieces), apexes at piece middles.
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
  if (pieces == 0) {
    c_end[0] = std::cos(lo);
    s_end[0] = std::sin(lo);
  }
  double growth = 0.0;
  int n = 0;
  for (const Vec3& p : in) {
    const Vec3 axial = a.dot(p) * a;
    const Vec3 radial = p - axial;
    const Vec3 ortho = a.cross(radial);
    const double rho = radial.norm();
    if (pieces == 0) {
      out[n++] = axial + c_end[0] * radial + s_end[0] * ortho;
      continue;
    }
    if (rho <= 1e-12 * (1.0 + p.norm())) {  // on the axis: it stays within 2*rho of itself
      out[n++] = p;
      growth = std::max(growth, 2.0 * rho);
      continue;
    }
    for (int k = 0; k <= pieces; ++k) out[n++] = axial + c_end[k] * radial + s_end[k] * ortho;
    if (accurate) {
      for (int k = 0; k < pieces; ++k) out[n++] = axial + c_mid[k] * radial + s_mid[k] * ortho;
    } else {
      growth = std::max(growth, rho * (1.0 - half_cos));  // the sagitta of each chord
    }
  }
  // Rounding in the rotated points is a few ulps of their size.
  radius += growth + 16.0 * kEps * maxNorm(in);
  return n;
}

// Rotation by a rotation vector (Rodrigues).
Eigen::Matrix3d rotationFromVector(const Vec3& w) {
  const double angle = w.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

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
               double& radius) noexcept {
  int n = 0;
  const double in_norm = maxNorm(in);
  switch (joint.type) {
    case JointType::Fixed:
      for (const Vec3& p : in) out[n++] = p;
      break;
    case JointType::Revolute:
      n = sweepRevolute(joint, lo[0], hi[0], in, out, radius);
      break;
    case JointType::Prismatic:
      // Minkowski sum with the segment [lo, hi] along the axis: exact.
      for (const Vec3& p : in) out[n++] = p + lo[0] * joint.axis;
      if (hi[0] > lo[0])
        for (const Vec3& p : in) out[n++] = p + hi[0] * joint.axis;
      radius += 8.0 * kEps * (in_norm + std::max(std::abs(lo[0]), std::abs(hi[0])));
      break;
    case JointType::Translation3d: {
      // Translate by the box centre; the ball around it covers the box and the error bound.
      const Vec3 l(lo[0], lo[1], lo[2]), h(hi[0], hi[1], hi[2]);
      const Vec3 centre = 0.5 * (l + h);
      for (const Vec3& p : in) out[n++] = p + centre;
      radius += 0.5 * (h - l).norm() + joint.error + 8.0 * kEps * (in_norm + centre.norm());
      break;
    }
    case JointType::Rotation3d: {
      // Rotate by the box centre. Every rotation vector in the box lies within |half-diagonal|
      // of it, and exp is 1-Lipschitz on SO(3), so the extra angle is at most that plus the
      // error bound; a point then moves at most 2 sin(angle / 2) |p|.
      const Vec3 l(lo[0], lo[1], lo[2]), h(hi[0], hi[1], hi[2]);
      const Eigen::Matrix3d rot = rotationFromVector(0.5 * (l + h));
      for (const Vec3& p : in) out[n++] = rot * p;
      const double angle = 0.5 * (h - l).norm() + joint.error;
      const double chord = angle >= 3.141592653589793 ? 2.0 : 2.0 * std::sin(0.5 * angle);
      radius += chord * in_norm * (1.0 + 4.0 * kEps) + 16.0 * kEps * in_norm;
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
  radius += 8.0 * kEps * (out_norm + t.norm());
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
  radius += std::sqrt(worst) * (1.0 + 4.0 * kEps);
  return budget;
}

Sphere boundingSphere(std::span<const Vec3> pts, double radius) noexcept {
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Sphere s;
  s.center = 0.5 * (lo + hi);
  double r = 0.0;
  for (const Vec3& p : pts) r = std::max(r, (p - s.center).squaredNorm());
  s.radius = std::sqrt(r) * (1.0 + 4.0 * kEps) + radius;
  return s;
}

}  // namespace kccd::detail
