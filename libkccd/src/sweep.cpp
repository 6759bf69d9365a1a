#include "sweep.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include "rounding.hpp"

#include "kccd/rotation.hpp"

namespace kccd::detail {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kTwoPi = 6.283185307179586;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Rotation3d boxes of a smaller reach (radians) get apexes in the exact stage (jointMaps()).
constexpr double kMaxRotationApexReach = 0.3;
// An icosahedron's circumradius over its inradius (sqrt(3) sqrt(phi^2 + 1) / phi^2), rounded up.
constexpr double kIcosahedron = 1.2584086;

// The matrix of v x . (so that crossMatrix(v) p = v x p).
Eigen::Matrix3d crossMatrix(const Vec3& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

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

// The largest |p| (one square root: sqrt is monotone and correctly rounded, so this is the
// largest of the rounded norms).
double maxNorm(std::span<const Vec3> pts) {
  double m = 0.0;
  for (const Vec3& p : pts) m = std::max(m, p.squaredNorm());
  return std::sqrt(m);
}

// A revolute joint at the single angle of `trig` (no pieces) as one matrix: Rodrigues,
// R(q) = c I + s [a]x + (1 - c) a a^T, composed with the origin's rotation. Every entry of the
// product errs by a few ulps (|a| = 1, |c|, |s| <= 1, the origin's rotation orthonormal), so a
// point moves by at most about 20 ulps of |p| + |t| (t the origin's translation): the guard
// (kRigidGuardUlps) allows 64.
Eigen::Matrix3d revoluteMatrix(const Joint& j, const RevoluteTrig& trig) {
  const Vec3& a = j.axis;
  const double c = trig.c_end[0], s = trig.s_end[0];
  return j.origin.linear() * (c * Eigen::Matrix3d::Identity() + s * crossMatrix(a) + (1.0 - c) * (a * a.transpose()));
}

// Revolute sweep in the joint frame (the point volumes of the first stage, whatever the joint's
// mode): each point's arc is covered by its chords (pieces + 1 points) and the radius grows by the
// largest sagitta rho (1 - cos(step / 2)), an error second order in the interval width. The point
// budget is applied by reduceToBudget(), whose error is measured against the hull of the kept
// points. Tangent apexes (accurate joints) are used by the exact stage (jointMaps()).
int sweepRevolute(const Joint& j, const RevoluteTrig& trig, std::span<const Vec3> in, Vec3* out, double& radius,
                  int budget, double* rho, double rho_bound) {
  const Vec3& a = j.axis;
  const int pieces = trig.pieces;
  const int n_in = static_cast<int>(in.size());
  // Points are written straight into the parent frame: with A = R_o axial + t, B = R_o radial and
  // C = R_o (axis x radial), the point rotated by angle q is A + cos(q) B + sin(q) C.
  const Eigen::Matrix3d& rot = j.origin.linear();
  const Vec3& t = j.origin.translation();
  if (pieces == 0) {  // a single angle: a rigid map, one matrix for every point
    const Eigen::Matrix3d map = revoluteMatrix(j, trig);
    double in_sq = 0.0;
    for (int i = 0; i < n_in; ++i) {
      in_sq = std::max(in_sq, in[i].squaredNorm());
      out[i] = map * in[i] + t;
    }
    radius += roundingGuard(std::sqrt(in_sq) + t.norm(), kRigidGuardUlps);
    return n_in;
  }
  const double in_norm = maxNorm(in);
  const double* c_end = trig.c_end;
  const double* s_end = trig.s_end;
  const double half_cos = trig.half_cos;
  const double c_centre = trig.c_mid, s_centre = trig.s_mid;
  const double sagitta = 1.0 - half_cos;      // per unit rho
  const double half_chord = trig.half_chord;  // per unit rho
  // Chords for the points farthest from the axis, as many as the budget holds; the arc's middle
  // point (radius growth rho * 2 sin(w / 4)) for the rest. Squared distances from the axis
  // throughout (the order and the largest are those of the distances; one square root at the end).
  for (int i = 0; i < n_in; ++i) rho[i] = (in[i] - a.dot(in[i]) * a).squaredNorm();
  double chord_from = 0.0;  // points with rho^2 >= chord_from get chords
  const int chords_fit = std::min(n_in, (budget - n_in) / pieces);
  if (chords_fit < n_in) {
    // The chords_fit-th largest rho^2.
    double* r = rho + n_in;
    for (int i = 0; i < n_in; ++i) r[i] = rho[i];
    if (chords_fit <= 0) {
      chord_from = kInf;
    } else {
      std::nth_element(r, r + (chords_fit - 1), r + n_in, std::greater<double>());
      chord_from = r[chords_fit - 1];
    }
  }
  // With Ra the axis in the parent frame and Rp the point rotated by the origin: the axial part
  // R_o axial = (a.p) Ra, the radial part Rp - (a.p) Ra, and R_o (a x p) = Ra x Rp.
  const Vec3 ra = rot * a;
  double axis_sq = 0.0;  // largest rho^2 of the points kept on the axis
  double mid_sq = 0.0;   // largest rho^2 of the points kept at their arc's middle
  int n = 0;
  int chords = 0;
  for (int i = 0; i < n_in; ++i) {
    const Vec3& p = in[i];
    const Vec3 rp = rot * p;
    // On the axis (rho <= 1e-12 (1 + |p|) when 1e-24 (1 + |p|^2) holds): it stays within 2 rho of itself.
    if (rho[i] <= 1e-24 * (1.0 + p.squaredNorm())) {
      out[n++] = rp + t;
      axis_sq = std::max(axis_sq, rho[i]);
      continue;
    }
    const double ap = a.dot(p);
    const Vec3 A = ap * ra + t;
    const Vec3 B = rp - ap * ra;
    const Vec3 C = ra.cross(rp);
    if (rho[i] >= chord_from && chords < chords_fit) {
      for (int k = 0; k <= pieces; ++k) out[n++] = A + c_end[k] * B + s_end[k] * C;
      ++chords;
    } else {
      out[n++] = A + c_centre * B + s_centre * C;
      mid_sq = std::max(mid_sq, rho[i]);
    }
  }
  const double mid_growth = std::max(2.0 * std::sqrt(axis_sq), std::sqrt(mid_sq) * half_chord);
  // The growth: the sagitta of the farthest point the volume can hold (rho_bound, from the swept
  // sphere below: the same value the exact stage uses, so that its chord chains stay inside these
  // volumes), plus the middle points' distance to their chord ends.
  const double growth = roundedUp(rho_bound * sagitta, 4) + mid_growth;
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

// Distance from p to the segment [a, b] (exact up to rounding; a == b allowed).
double segmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 e = b - a;
  const double ee = e.squaredNorm();
  const double t = ee > 0.0 ? std::clamp((p - a).dot(e) / ee, 0.0, 1.0) : 0.0;
  return (p - (a + t * e)).norm();
}

// Distance from p to the triangle (a, b, c), degenerate triangles included.
double triangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a, w = p - a;
  const double d11 = e1.squaredNorm(), d12 = e1.dot(e2), d22 = e2.squaredNorm();
  const double det = d11 * d22 - d12 * d12;
  if (det > 1e-24 * d11 * d22) {
    const double w1 = w.dot(e1), w2 = w.dot(e2);
    const double s = (d22 * w1 - d12 * w2) / det, t = (d11 * w2 - d12 * w1) / det;
    if (s >= 0.0 && t >= 0.0 && s + t <= 1.0) return (p - (a + s * e1 + t * e2)).norm();
  }
  return std::min({segmentDistance(p, a, b), segmentDistance(p, b, c), segmentDistance(p, a, c)});
}

// True when p lies inside the tetrahedron (a, b, c, d) (by barycentric coordinates).
bool insideTetrahedron(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Eigen::Matrix3d m;
  m << b - a, c - a, d - a;
  const double det = m.determinant();
  const double scale = (b - a).norm() * (c - a).norm() * (d - a).norm();
  if (!(std::abs(det) > 1e-12 * scale)) return false;
  const Vec3 l = m.inverse() * (p - a);
  return l.minCoeff() >= 0.0 && l.sum() <= 1.0;
}

// An upper bound on the distance from p to conv(kept[0..k)), or any value <= `enough` once one is
// found (the caller only needs to know that the distance is at most `enough`): distances to the
// simplices spanned by its four nearest kept points (inside their tetrahedron: 0), cheapest first.
double hullDistanceBound(const Vec3& p, const Vec3* kept, int k, double enough) {
  int near[4] = {-1, -1, -1, -1};
  double near_sq[4] = {kInf, kInf, kInf, kInf};
  for (int i = 0; i < k; ++i) {
    double d = (kept[i] - p).squaredNorm();
    if (d >= near_sq[3]) continue;
    int idx = i;
    for (int m = 0; m < 4; ++m) {
      if (d < near_sq[m]) {
        std::swap(d, near_sq[m]);
        std::swap(idx, near[m]);
      }
    }
  }
  double best = std::sqrt(near_sq[0]);
  if (best <= enough || near[1] < 0) return best;
  const Vec3 &a = kept[near[0]], &b = kept[near[1]];
  best = std::min(best, segmentDistance(p, a, b));
  if (best <= enough || near[2] < 0) return best;
  const Vec3& c = kept[near[2]];
  best = std::min(best, triangleDistance(p, a, b, c));
  if (best <= enough || near[3] < 0) return best;
  const Vec3& d = kept[near[3]];
  if (insideTetrahedron(p, a, b, c, d)) return 0.0;
  return std::min({best, triangleDistance(p, a, b, d), triangleDistance(p, a, c, d), triangleDistance(p, b, c, d)});
}

}  // namespace

RevoluteTrig revoluteTrig(double lo, double hi) noexcept {
  RevoluteTrig t;
  t.lo = lo;
  t.hi = hi;
  const Arc arc = revoluteArc(lo, hi);
  t.start = arc.start;
  t.width = arc.width;
  t.pieces = revolutePieces(arc.width);
  if (t.pieces == 0) {
    t.c_end[0] = std::cos(arc.start);
    t.s_end[0] = std::sin(arc.start);
    t.c_mid = t.c_end[0];
    t.s_mid = t.s_end[0];
    return t;
  }
  const double step = arc.width / t.pieces;
  for (int k = 0; k <= t.pieces; ++k) {
    t.c_end[k] = std::cos(arc.start + k * step);
    t.s_end[k] = std::sin(arc.start + k * step);
  }
  t.half_cos = std::cos(0.5 * step);
  t.c_mid = std::cos(arc.start + 0.5 * arc.width);
  t.s_mid = std::sin(arc.start + 0.5 * arc.width);
  t.c_half = std::cos(0.5 * arc.width);
  t.s_half = std::sin(0.5 * arc.width);
  t.half_chord = 2.0 * std::sin(0.25 * arc.width);
  return t;
}

int sweepExpansion(const Joint& joint) noexcept {
  const int pieces = revolutePieces(kTwoPi);
  switch (joint.type) {
    case JointType::Revolute:
      return pieces + 1;
    case JointType::Prismatic:
      return 2;
    default:
      return 1;
  }
}

double rhoBound(const Vec3& axis, const Sphere& s) noexcept {
  return (s.center - axis.dot(s.center) * axis).norm() + s.radius;
}

RigidMap rigidMap(const Joint& joint, const double* value, const RevoluteTrig& trig) noexcept {
  RigidMap m;
  const Eigen::Matrix3d& rot = joint.origin.linear();
  const Vec3& t = joint.origin.translation();
  switch (joint.type) {
    case JointType::Fixed:
      m.lin = rot;
      m.off = t;
      m.magnitude = t.norm();
      m.ok = true;
      break;
    case JointType::Revolute:
      if (trig.pieces != 0) break;
      m.lin = revoluteMatrix(joint, trig);
      m.off = t;
      m.magnitude = t.norm();
      m.ok = m.lin.allFinite();
      break;
    case JointType::Prismatic:
      // rot (p + q axis) + t, with rot (q axis) + t computed once: a few ulps of |q| + |t|.
      m.lin = rot;
      m.off = rot * (value[0] * joint.axis) + t;
      m.magnitude = std::abs(value[0]) + t.norm();
      m.ok = std::isfinite(m.magnitude) && m.off.allFinite();
      break;
    case JointType::Translation3d:
    case JointType::Rotation3d:
      break;
  }
  return m;
}

int sweepJoint(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig,
               std::span<const Vec3> in, Vec3* out, double& radius, int budget, double* rho,
               const Sphere& below) noexcept {
  if (joint.type == JointType::Revolute)  // writes straight into the parent frame
    return sweepRevolute(joint, trig, in, out, radius, budget, rho, rhoBound(joint.axis, below));
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
      const double extent = std::max(in_norm, below.center.norm() + below.radius);
      radius += roundedUp(rotationChord(r3.reach) * extent, 4) + roundingGuard(extent, 16);
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

int reduceToBudget(Vec3* pts, int n, int budget, double* dist, int* order, double& radius) noexcept {
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
  // The radius grows by the largest distance from a dropped point to the hull of the kept ones,
  // bounded from above by its distance to a point of that hull (hullDistanceBound). Dropped points
  // are bounded worst first, and only while their distance to the nearest kept point (itself a
  // bound) exceeds the growth found so far.
  double growth = 0.0;
  double extent = 0.0;
  for (int i = 0; i < n; ++i) extent = std::max(extent, pts[i].cwiseAbs().maxCoeff());
  // Dropped points in order of their distance to the nearest kept point, largest first.
  const int dropped = n - budget;
  for (int i = 0; i < dropped; ++i) order[i] = budget + i;
  std::sort(order, order + dropped, [dist](int x, int y) { return dist[x] > dist[y]; });
  for (int i = 0; i < dropped; ++i) {
    const int q = order[i];
    if (dist[q] <= growth * growth) break;
    growth = std::max(growth, std::min(std::sqrt(dist[q]), hullDistanceBound(pts[q], pts, budget, growth)));
  }
  // Every dropped point lies within `growth` of conv(kept) (the bounds are exact distances to
  // points of that hull, computed to a few ulps of the coordinates).
  radius += roundedUp(growth, 8) + roundingGuard(extent, 64);
  return budget;
}

JointMaps jointMaps(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig) noexcept {
  JointMaps m;
  const Eigen::Matrix3d& rot = joint.origin.linear();
  const Vec3& t = joint.origin.translation();
  m.axis = joint.axis;
  auto add = [&m](const Eigen::Matrix3d& lin, const Vec3& off, double scale) {
    m.lin[m.count] = lin;
    m.off[m.count] = off;
    m.scale[m.count] = scale;
    ++m.count;
  };
  m.offset_norm = t.norm();
  switch (joint.type) {
    case JointType::Fixed:
      add(rot, t, 1.0);
      break;
    case JointType::Revolute: {
      const Vec3& a = joint.axis;
      const Eigen::Matrix3d axial = a * a.transpose();
      const Eigen::Matrix3d radial = Eigen::Matrix3d::Identity() - axial;
      const Eigen::Matrix3d cross = crossMatrix(a);
      auto rotation = [&](double c, double s) -> Eigen::Matrix3d { return rot * (axial + c * radial + s * cross); };
      const int pieces = trig.pieces;
      if (pieces == 0) {
        add(rotation(trig.c_end[0], trig.s_end[0]), t, 1.0);
        break;
      }
      m.revolute = true;
      const double step = trig.width / pieces;
      const double half_cos = trig.half_cos;
      for (int k = 0; k <= pieces; ++k) add(rotation(trig.c_end[k], trig.s_end[k]), t, 1.0);
      m.chord_count = m.count;
      // Tangent apexes: the middle direction scaled by 1 / cos(step / 2) (the operator norm).
      const double apex_scale = roundedUp(1.0 / half_cos, 4);
      for (int k = 0; k < pieces; ++k) {
        const double mid = trig.start + (k + 0.5) * step;
        add(rotation(std::cos(mid) / half_cos, std::sin(mid) / half_cos), t, apex_scale);
      }
      m.sagitta = roundedUp(1.0 - half_cos, 8) + 8.0 * kEps;
      m.apex_excess = roundedUp(apex_scale - 1.0, 8) + 8.0 * kEps;
      return m;
    }
    case JointType::Prismatic:
      add(rot, rot * (lo[0] * joint.axis) + t, 1.0);
      if (hi[0] > lo[0]) add(rot, rot * (hi[0] * joint.axis) + t, 1.0);
      m.offset_norm += std::max(std::abs(lo[0]), std::abs(hi[0]));
      break;
    case JointType::Translation3d: {
      // The box's corners (one per distinct corner, at most 8: the Minkowski sum with the box is
      // the hull of the translates by its corners, exact) and the error ball as growth.
      double corner_norm = 0.0;
      for (int k = 0; k < 8; ++k) {
        bool repeat = false;
        Vec3 corner;
        for (int i = 0; i < 3; ++i) {
          const bool high = (k >> i) & 1;
          repeat = repeat || (high && !(hi[i] > lo[i]));
          corner[i] = high ? hi[i] : lo[i];
        }
        if (repeat) continue;
        add(rot, rot * corner + t, 1.0);
        corner_norm = std::max(corner_norm, corner.norm());
      }
      m.fixed_growth = joint.error > 0.0 ? roundedUp(joint.error, 2) : 0.0;
      m.offset_norm += corner_norm;
      break;
    }
    case JointType::Rotation3d: {
      const Rotation3 r3 = rotation3(box3(joint, lo, hi));
      const Eigen::Matrix3d centre = rot * r3.rot;
      add(centre, t, 1.0);
      m.point_growth = roundedUp(rotationChord(r3.reach), 4);
      m.chord_count = m.count;
      // Apexes. Every rotation of the box is the centre's times exp(v), |v| <= reach =: r. With
      // w = (sin|v| / |v|) v, exp(v) p lies within (1 - cos r) |p| of p + w x p (its second-order
      // part), and |w| <= r puts w in the icosahedron with vertices n of norm s = kIcosahedron r
      // (its inscribed ball has radius r), so p + w x p is a convex combination of the
      // p + n x p; each lies within (s - sin s + 1 - cos s) |p| <= (s^3 / 6 + s^2 / 2) |p| of
      // exp(n) p. Hence the hull of the images under the twelve maps centre exp(n), grown by
      // (s^3 / 6 + s^2 / 2 + r^2 / 2) |p|, holds every motion: second order in r where the chord
      // map's ball is first order. The apexes turn by s, beyond the box: at most (s - r) |p| past
      // a true position.
      const double r = r3.reach;
      if (r < kMaxRotationApexReach) {
        const double s = roundedUp(kIcosahedron * r, 2);
        const double growth = roundedUp(s * s * s / 6.0 + s * s / 2.0 + r * r / 2.0, 8) + 16.0 * kEps;
        if (growth < 0.5 * m.point_growth) {
          // Rodrigues with one sine and cosine for all twelve: exp(s u) = I + sin s [u] + (1 - cos s) [u]^2.
          constexpr double kPhi = 1.618033988749895;
          const double sin_s = std::sin(s), versine = 2.0 * std::sin(0.5 * s) * std::sin(0.5 * s);
          for (int k = 0; k < 3; ++k)
            for (const double a : {1.0, -1.0})
              for (const double b : {kPhi, -kPhi}) {
                Vec3 u = Vec3::Zero();  // (0, +-1, +-phi) and its cyclic shifts, normalised
                u[(k + 1) % 3] = a;
                u[(k + 2) % 3] = b;
                u.normalize();
                const Eigen::Matrix3d cross = crossMatrix(u);
                add(centre * (Eigen::Matrix3d::Identity() + sin_s * cross + versine * (cross * cross)), t, 1.0);
              }
          m.rotation_apexes = true;
          m.apex_point_growth = growth;
          m.apex_excess = roundedUp(s - r, 4) + 8.0 * kEps;
        }
      }
      return m;
    }
  }
  m.chord_count = m.count;
  m.shared_lin = joint.type != JointType::Revolute && joint.type != JointType::Rotation3d;
  return m;
}

Sphere sweepSphere(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig,
                   const Sphere& in) noexcept {
  Sphere out = in;
  const Vec3& c = in.center;
  switch (joint.type) {
    case JointType::Fixed:
      break;
    case JointType::Revolute: {
      // The centre's arc lies within rho sin(w / 2) of its chord's middle (w < pi), or within
      // rho of the axis point for wider arcs.
      const Vec3& a = joint.axis;
      const Vec3 axial = a.dot(c) * a;
      const Vec3 radial = c - axial;
      const double rho = radial.norm();
      if (trig.width >= kPi) {
        out.center = axial;
        out.radius += rho;
      } else {
        out.center = axial + trig.c_half * (trig.c_mid * radial + trig.s_mid * a.cross(radial));
        out.radius += rho * trig.s_half;
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
