// GJK distance with the signed-volumes sub-algorithm (after Montanari, Petrinic and Barbieri,
// "Improving the GJK algorithm for faster and more reliable distance queries between convex
// objects", ACM TOG 2017), returning an any-time lower bound.
//
// Lower bound: for any direction v and w = s(-v), the support point of the Minkowski difference
// D = conv(Pa) - conv(Pb) in direction -v, every x in D satisfies |x| >= v.w / |v|. The best such
// value seen is kept, so the bound is valid whenever the iteration stops.
#include <algorithm>
#include <cmath>
#include <limits>

#include "kccd/distance.hpp"
#include "rounding.hpp"

namespace kccd {
namespace {

// The current simplex: up to four vertices of D with the indices of the points that made them.
// Unused slots stay finite (zero): the sub-algorithm weighs all four slots.
struct Simplex {
  Vec3 w[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  int ia[4] = {0, 0, 0, 0};
  int ib[4] = {0, 0, 0, 0};
  double lambda[4] = {0.0, 0.0, 0.0, 0.0};
  int size = 0;
};

// Both non-zero with equal signs; bitwise operators keep it free of branches.
inline bool sameSign(double a, double b) {
  return (a != 0.0) & (b != 0.0) & (std::signbit(a) == std::signbit(b));
}

// Branch-free select of an index.
inline int pick(bool condition, int if_true, int if_false) {
  return if_false ^ ((if_true ^ if_false) & -static_cast<int>(condition));
}

inline int argMaxAbs(const Vec3& v) {
  const double x = std::abs(v.x()), y = std::abs(v.y()), z = std::abs(v.z());
  if (x >= y && x >= z) return 0;
  return y >= z ? 1 : 2;
}

inline Vec3 combine(const Vec3* w, const double* lam) {
  return lam[0] * w[0] + lam[1] * w[1] + lam[2] * w[2] + lam[3] * w[3];
}

inline void clear(double* lam) { lam[0] = lam[1] = lam[2] = lam[3] = 0.0; }

// Closest point of segment (w[i], w[j]) to the origin, as barycentric coordinates in lam.
void closestOnSegment(const Vec3* w, int i, int j, double* lam) {
  clear(lam);
  const Vec3 t = w[j] - w[i];
  const int axis = argMaxAbs(t);
  if (t[axis] == 0.0) {  // coincident vertices
    lam[i] = 1.0;
    return;
  }
  // Orthogonal projection of the origin onto the line, then 1-D barycentrics on the longest axis.
  const Vec3 p0 = w[j] - (w[j].dot(t) / t.squaredNorm()) * t;
  const double mu = w[i][axis] - w[j][axis];
  const double ci = p0[axis] - w[j][axis];
  const double cj = w[i][axis] - p0[axis];
  if (sameSign(mu, ci) && sameSign(mu, cj)) {
    lam[i] = ci / mu;
    lam[j] = cj / mu;
  } else if (sameSign(mu, ci)) {
    lam[i] = 1.0;
  } else {
    lam[j] = 1.0;
  }
}

// Keeps the candidate with the smaller norm.
inline void keepBest(const Vec3* w, const double* cand, double* best, double& best_vv) {
  const double vv = combine(w, cand).squaredNorm();
  if (vv < best_vv) {
    best_vv = vv;
    std::copy(cand, cand + 4, best);
  }
}

// Closest point of triangle (w[i], w[j], w[k]) to the origin.
void closestOnTriangle(const Vec3* w, int i, int j, int k, double* lam) {
  const Vec3 n = (w[j] - w[i]).cross(w[k] - w[i]);
  const int axis = argMaxAbs(n);
  const int ids[3] = {i, j, k};
  double c[3] = {0.0, 0.0, 0.0};
  double mu = 0.0;
  if (n[axis] != 0.0) {
    // Project the origin onto the plane, then compare signed areas in the projection that
    // drops the axis of the largest normal component (the best-conditioned 2-D view).
    const Vec3 p0 = (w[i].dot(n) / n.squaredNorm()) * n;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    auto area = [u, v](const Vec3& a, const Vec3& b, const Vec3& d) {
      return (b[u] - a[u]) * (d[v] - a[v]) - (b[v] - a[v]) * (d[u] - a[u]);
    };
    mu = area(w[i], w[j], w[k]);
    c[0] = area(p0, w[j], w[k]);
    c[1] = area(w[i], p0, w[k]);
    c[2] = area(w[i], w[j], p0);
    if (sameSign(mu, c[0]) && sameSign(mu, c[1]) && sameSign(mu, c[2])) {
      clear(lam);
      for (int e = 0; e < 3; ++e) lam[ids[e]] = c[e] / mu;
      return;
    }
  }
  // Outside (or degenerate): the closest point lies on an edge facing the origin's projection.
  double best[4] = {0.0, 0.0, 0.0, 0.0};
  double best_vv = std::numeric_limits<double>::infinity();
  double cand[4];
  for (int e = 0; e < 3; ++e) {
    if (mu != 0.0 && sameSign(mu, c[e])) continue;
    closestOnSegment(w, ids[(e + 1) % 3], ids[(e + 2) % 3], cand);
    keepBest(w, cand, best, best_vv);
  }
  std::copy(best, best + 4, lam);
}

inline double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

// Closest point of tetrahedron w[0..3] to the origin.
void closestOnTetrahedron(const Vec3* w, double* lam) {
  // Cofactors: c[x] is the signed volume with vertex x replaced by the origin.
  const double c[4] = {det3(w[1], w[2], w[3]), -det3(w[0], w[2], w[3]), det3(w[0], w[1], w[3]),
                       -det3(w[0], w[1], w[2])};
  const double vol = c[0] + c[1] + c[2] + c[3];
  if (vol != 0.0 && sameSign(vol, c[0]) && sameSign(vol, c[1]) && sameSign(vol, c[2]) &&
      sameSign(vol, c[3])) {
    for (int x = 0; x < 4; ++x) lam[x] = c[x] / vol;
    return;
  }
  double best[4] = {0.0, 0.0, 0.0, 0.0};
  double best_vv = std::numeric_limits<double>::infinity();
  double cand[4];
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int x = 0; x < 4; ++x) {
    if (vol != 0.0 && sameSign(vol, c[x])) continue;
    closestOnTriangle(w, kFace[x][0], kFace[x][1], kFace[x][2], cand);
    keepBest(w, cand, best, best_vv);
  }
  std::copy(best, best + 4, lam);
}

// Runs the sub-algorithm on s, drops vertices with zero weight and returns the closest point.
Vec3 reduce(Simplex& s) {
  double lam[4] = {0.0, 0.0, 0.0, 0.0};
  switch (s.size) {
    case 1: lam[0] = 1.0; break;
    case 2: closestOnSegment(s.w, 0, 1, lam); break;
    case 3: closestOnTriangle(s.w, 0, 1, 2, lam); break;
    default: closestOnTetrahedron(s.w, lam); break;
  }
  int n = 0;
  for (int x = 0; x < s.size; ++x) {
    if (lam[x] > 0.0) {
      s.w[n] = s.w[x];
      s.ia[n] = s.ia[x];
      s.ib[n] = s.ib[x];
      s.lambda[n] = lam[x];
      ++n;
    }
  }
  s.size = n;
  Vec3 v = Vec3::Zero();
  for (int x = 0; x < n; ++x) v += s.lambda[x] * s.w[x];
  return v;
}

// Index of the point farthest along d. Four independent running maxima with branch-free
// selects: the winner changes unpredictably, and one serial compare chain would bound the speed.
inline int supportIndex(std::span<const Vec3> pts, const Vec3& d) {
  const double dx = d.x(), dy = d.y(), dz = d.z();
  const int n = static_cast<int>(pts.size());
  auto dot = [&](int k) { return pts[k].x() * dx + pts[k].y() * dy + pts[k].z() * dz; };
  double best_dot[4];
  int best[4];
  for (int lane = 0; lane < 4; ++lane) {
    best[lane] = lane < n ? lane : 0;
    best_dot[lane] = dot(best[lane]);
  }
  int k = 4;
  for (; k + 4 <= n; k += 4) {
    for (int lane = 0; lane < 4; ++lane) {
      const double value = dot(k + lane);
      best[lane] = pick(value > best_dot[lane], k + lane, best[lane]);
      best_dot[lane] = std::max(value, best_dot[lane]);
    }
  }
  for (; k < n; ++k) {
    const double value = dot(k);
    best[0] = pick(value > best_dot[0], k, best[0]);
    best_dot[0] = std::max(value, best_dot[0]);
  }
  const int ab = pick(best_dot[1] > best_dot[0], 1, 0);
  const int cd = pick(best_dot[3] > best_dot[2], 3, 2);
  return best[pick(best_dot[cd] > best_dot[ab], cd, ab)];
}

// One pass over a point set: its largest absolute coordinate (the rounding scale), whether every
// coordinate is finite, and its centroid (a point of the hull, to start the descent from).
struct SetSummary {
  double scale = 0.0;
  bool finite = true;
  Vec3 centroid = Vec3::Zero();
};

SetSummary summarize(std::span<const Vec3> pts) {
  SetSummary out;
  double m = 0.0;
  double sx = 0.0, sy = 0.0, sz = 0.0;
  for (const Vec3& p : pts) {
    sx += p.x();
    sy += p.y();
    sz += p.z();
    m = std::max(m, std::max(std::abs(p.x()), std::max(std::abs(p.y()), std::abs(p.z()))));
  }
  out.centroid = Vec3(sx, sy, sz) / static_cast<double>(pts.size());
  // A NaN or infinite coordinate makes its sum NaN or infinite (so does an overflowing sum, which
  // is rejected as well); an infinity also shows in the maximum.
  out.finite = out.centroid.allFinite() && m <= std::numeric_limits<double>::max();
  out.scale = m;
  return out;
}

}  // namespace

bool allFinite(std::span<const Vec3> points) noexcept {
  return std::all_of(points.begin(), points.end(), [](const Vec3& p) { return p.allFinite(); });
}

DistanceResult distance(const SschView& a, const SschView& b, const GjkOptions& options) noexcept {
  DistanceResult result;
  if (a.points.empty() || b.points.empty() || !(a.radius >= 0.0) || !(b.radius >= 0.0) ||
      !std::isfinite(a.radius) || !std::isfinite(b.radius)) {
    return result;  // InvalidInput, distance 0
  }
  const SetSummary sum_a = summarize(a.points);
  const SetSummary sum_b = summarize(b.points);
  if (!sum_a.finite || !sum_b.finite) return result;
  const double scale_a = sum_a.scale, scale_b = sum_b.scale;

  // Rounding guard: the dot products behind a bound err by a few ulps of the coordinates.
  const double radii = a.radius + b.radius;
  const double guard = detail::roundingGuard(scale_a + scale_b, 32) + detail::roundingGuard(radii, 4);
  const double overlap_tol = detail::roundingGuard(scale_a + scale_b, 16);
  const double overlap_vv = overlap_tol * overlap_tol;
  const double tol = std::max(options.relative_tolerance, 0.0);

  // Start from the centroids' difference: a point of the Minkowski difference near its middle.
  Vec3 v = sum_a.centroid - sum_b.centroid;
  if (options.warm_start != nullptr && options.warm_start->allFinite() &&
      options.warm_start->squaredNorm() > 0.0) {
    v = *options.warm_start;
  }

  Simplex s;
  double lower = -std::numeric_limits<double>::infinity();
  GjkStatus status = GjkStatus::IterationLimit;
  int iter = 0;
  if (v.squaredNorm() <= overlap_vv) {
    status = GjkStatus::Overlap;  // the centroids (or the warm start) coincide: a common point
    lower = 0.0;
  } else {
    for (; iter < options.max_iterations; ++iter) {
      const double vv = v.squaredNorm();
      const int ia = supportIndex(a.points, -v);
      const int ib = supportIndex(b.points, v);
      const Vec3 w = a.points[ia] - b.points[ib];
      const double vw = v.dot(w);
      lower = std::max(lower, vw / std::sqrt(vv));
      if (lower - radii - guard >= options.stop_above) {
        status = GjkStatus::StoppedEarly;
        break;
      }
      if (s.size > 0 && vv - vw <= tol * vv) {
        status = GjkStatus::Converged;
        break;
      }
      bool duplicate = false;
      for (int x = 0; x < s.size; ++x) duplicate |= (s.ia[x] == ia && s.ib[x] == ib);
      if (duplicate) {  // no new support point: v is optimal up to rounding
        status = GjkStatus::Converged;
        break;
      }
      const int previous_size = s.size;
      s.w[s.size] = w;
      s.ia[s.size] = ia;
      s.ib[s.size] = ib;
      ++s.size;
      const Vec3 next = reduce(s);
      const double next_vv = next.squaredNorm();
      if (s.size == 4 || next_vv <= overlap_vv) {
        v = next;
        status = GjkStatus::Overlap;
        ++iter;
        break;
      }
      if (next_vv >= vv && previous_size > 0) {  // rounding: no descent any more
        status = GjkStatus::NoProgress;
        ++iter;
        break;
      }
      v = next;
    }
  }

  result.iterations = iter;
  result.status = status;
  Vec3 pa = sum_a.centroid;
  Vec3 pb = sum_b.centroid;
  if (s.size > 0) {
    pa.setZero();
    pb.setZero();
    for (int x = 0; x < s.size; ++x) {
      pa += s.lambda[x] * a.points[s.ia[x]];
      pb += s.lambda[x] * b.points[s.ib[x]];
    }
  }
  const Vec3 gap = pa - pb;
  const double gap_norm = gap.norm();
  const double v_norm = v.norm();
  if (v_norm > 0.0 && status != GjkStatus::Overlap) result.direction = v / v_norm;
  result.hull_lower = std::max(0.0, lower - guard);
  result.hull_upper = std::max(result.hull_lower, gap_norm + guard);
  result.distance = std::max(0.0, lower - radii - guard);
  if (result.distance > 0.0 && gap_norm > 0.0) {
    const Vec3 n = gap / gap_norm;
    result.witness_a = pa - a.radius * n;
    result.witness_b = pb + b.radius * n;
  } else {
    result.witness_a = pa;
    result.witness_b = pb;
  }
  return result;
}

}  // namespace kccd
