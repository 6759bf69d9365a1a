// GJK distance with the signed-volumes sub-algorithm (after Montanari, Petrinic and Barbieri,
// "Improving the GJK algorithm for faster and more reliable distance queries between convex
// objects", ACM TOG 2017), on any two convex sets given by support functions. Internal.
//
// Lower bound: for any direction v (u = v / |v|) and support points sa = s_a(-v), sb = s_b(v) whose
// support values are exact up to a slack (h_a(-u) <= -u.sa + slack_a, h_b(u) <= u.sb + slack_b),
// every point x of the Minkowski difference a - b satisfies |x| >= u.(sa - sb) - slack_a - slack_b.
// The best such value seen is kept, so the bound is valid whenever the iteration stops.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "kccd/distance.hpp"
#include "rounding.hpp"

namespace kccd::detail {

/// One support point of a convex set: the point, a key that identifies it (equal keys, equal
/// points) and the slack of its support value (0 when the point attains the support).
struct SupportHit {
  Vec3 point;
  std::uint64_t key = 0;
  double slack = 0.0;
};

// The current simplex: up to four vertices w = a - b of D, the support points a and b that made
// them and their keys. Unused slots stay finite (zero): the sub-algorithm weighs all four slots.
struct Simplex {
  Vec3 w[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 a[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 b[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  std::uint64_t ka[4] = {0, 0, 0, 0};
  std::uint64_t kb[4] = {0, 0, 0, 0};
  double lambda[4] = {0.0, 0.0, 0.0, 0.0};
  int size = 0;
};

// Both non-zero with equal signs; bitwise operators keep it free of branches.
inline bool sameSign(double a, double b) { return (a != 0.0) & (b != 0.0) & (std::signbit(a) == std::signbit(b)); }

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
inline void closestOnSegment(const Vec3* w, int i, int j, double* lam) {
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

// Closest point of triangle (w[i], w[j], w[k]) to the origin. `newest` is the vertex GJK just
// added (or -1): the closest point involves it, since the old vertices' closest point v is farther
// than the segment from v towards it, so the edge opposite it is tried only if no other edge is.
inline void closestOnTriangle(const Vec3* w, int i, int j, int k, double* lam, int newest = -1) {
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
  // Outside (or degenerate): the closest point lies on an edge facing the origin's projection
  // (with one such edge, that edge's closest point is the answer: no comparison).
  int facing[3];
  int nf = 0;
  for (int e = 0; e < 3; ++e)
    if (!((mu != 0.0 && sameSign(mu, c[e])) || ids[e] == newest)) facing[nf++] = e;
  if (nf == 1) {
    closestOnSegment(w, ids[(facing[0] + 1) % 3], ids[(facing[0] + 2) % 3], lam);
    return;
  }
  double best[4] = {0.0, 0.0, 0.0, 0.0};
  double best_vv = std::numeric_limits<double>::infinity();
  double cand[4];
  for (int f = 0; f < nf; ++f) {
    const int e = facing[f];
    closestOnSegment(w, ids[(e + 1) % 3], ids[(e + 2) % 3], cand);
    keepBest(w, cand, best, best_vv);
  }
  if (best_vv == std::numeric_limits<double>::infinity()) {  // rounding left no edge: try them all
    for (int e = 0; e < 3; ++e) {
      closestOnSegment(w, ids[(e + 1) % 3], ids[(e + 2) % 3], cand);
      keepBest(w, cand, best, best_vv);
    }
  }
  std::copy(best, best + 4, lam);
}

inline double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

// Closest point of tetrahedron w[0..3] to the origin; w[3] is the vertex GJK just added, so the
// face opposite it is tried only if no other face is (as for a triangle).
inline void closestOnTetrahedron(const Vec3* w, double* lam) {
  constexpr int kNewest = 3;
  // Cofactors: c[x] is the signed volume with vertex x replaced by the origin.
  const double c[4] = {det3(w[1], w[2], w[3]), -det3(w[0], w[2], w[3]), det3(w[0], w[1], w[3]),
                       -det3(w[0], w[1], w[2])};
  const double vol = c[0] + c[1] + c[2] + c[3];
  if (vol != 0.0 && sameSign(vol, c[0]) && sameSign(vol, c[1]) && sameSign(vol, c[2]) && sameSign(vol, c[3])) {
    for (int x = 0; x < 4; ++x) lam[x] = c[x] / vol;
    return;
  }
  // Outside: the closest point lies on a face facing the origin (one such face: its point).
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  int facing[4];
  int nf = 0;
  for (int x = 0; x < 4; ++x)
    if (!((vol != 0.0 && sameSign(vol, c[x])) || x == kNewest)) facing[nf++] = x;
  if (nf == 1) {
    closestOnTriangle(w, kFace[facing[0]][0], kFace[facing[0]][1], kFace[facing[0]][2], lam, kNewest);
    return;
  }
  double best[4] = {0.0, 0.0, 0.0, 0.0};
  double best_vv = std::numeric_limits<double>::infinity();
  double cand[4];
  for (int f = 0; f < nf; ++f) {
    const int x = facing[f];
    closestOnTriangle(w, kFace[x][0], kFace[x][1], kFace[x][2], cand, kNewest);
    keepBest(w, cand, best, best_vv);
  }
  if (best_vv == std::numeric_limits<double>::infinity()) {  // rounding left no face: try them all
    for (int x = 0; x < 4; ++x) {
      closestOnTriangle(w, kFace[x][0], kFace[x][1], kFace[x][2], cand);
      keepBest(w, cand, best, best_vv);
    }
  }
  std::copy(best, best + 4, lam);
}

// The sub-algorithm on the first `count` vertices of s (the last of them just added): the
// weights of the closest point to the origin, in lam. s itself is not changed.
inline void closestWeights(const Simplex& s, int count, double* lam) {
  clear(lam);
  switch (count) {
    case 1:
      lam[0] = 1.0;
      break;
    case 2:
      closestOnSegment(s.w, 0, 1, lam);
      break;
    case 3:
      closestOnTriangle(s.w, 0, 1, 2, lam, 2);
      break;
    default:
      closestOnTetrahedron(s.w, lam);
      break;
  }
}

// Keeps the vertices of s's first `count` with a positive weight in lam, with those weights.
inline void keepWeighted(Simplex& s, int count, const double* lam) {
  int n = 0;
  for (int x = 0; x < count; ++x) {
    if (lam[x] > 0.0) {
      s.w[n] = s.w[x];
      s.a[n] = s.a[x];
      s.b[n] = s.b[x];
      s.ka[n] = s.ka[x];
      s.kb[n] = s.kb[x];
      s.lambda[n] = lam[x];
      ++n;
    }
  }
  s.size = n;
}

/// What the support functions' sets look like to the descent: the largest absolute coordinate of
/// any of their points (the rounding scale) and a point of each (to start from).
struct SetsInfo {
  double scale_a = 0.0, scale_b = 0.0;
  Vec3 start_a = Vec3::Zero(), start_b = Vec3::Zero();
  /// The start points lie in their hulls (up to rounding: e.g. centroids of the points), so their
  /// difference bounds the distance from above before any support is taken (GjkOptions::stop_below).
  bool starts_in_hulls = false;
};

/// Distance between conv(A) + B(ra) and conv(B) + B(rb) where A and B are given by support
/// functions `sa(dir)`, `sb(dir)` returning a SupportHit for the (not normalised) direction dir.
template <class SupportA, class SupportB>
DistanceResult gjkDistance(const SupportA& sa, const SupportB& sb, double ra, double rb, const SetsInfo& info,
                           const GjkOptions& options) noexcept {
  DistanceResult result;
  const double scale_a = info.scale_a, scale_b = info.scale_b;
  const double radii = ra + rb;
  const double guard = detail::roundingGuard(scale_a + scale_b, 32) + detail::roundingGuard(radii, 4);
  const double overlap_tol = detail::roundingGuard(scale_a + scale_b, 16);
  const double overlap_vv = overlap_tol * overlap_tol;
  const double tol = std::max(options.relative_tolerance, 0.0);

  // Start from the given points' difference (e.g. the centroids: near the middle of the difference).
  Vec3 v = info.start_a - info.start_b;
  const bool warm =
      options.warm_start != nullptr && options.warm_start->allFinite() && options.warm_start->squaredNorm() > 0.0;
  if (warm) v = *options.warm_start;

  Simplex s;
  // v is a point of the hulls' difference once the simplex has one, or from the start when the
  // start points are the hulls' own and no warm start replaced them.
  const bool start_in_difference = info.starts_in_hulls && !warm;
  double lower = -std::numeric_limits<double>::infinity();
  GjkStatus status = GjkStatus::IterationLimit;
  int iter = 0;
  if (v.squaredNorm() <= overlap_vv) {
    status = GjkStatus::Overlap;  // the centroids (or the warm start) coincide: a common point
    lower = 0.0;
  } else {
    for (; iter < options.max_iterations; ++iter) {
      const double vv = v.squaredNorm();
      const double v_norm = std::sqrt(vv);  // one root per iteration, started before the supports
      // v is a point of the difference of the supports' hulls: |v| bounds the distance from above.
      if ((s.size > 0 || start_in_difference) && v_norm - radii + guard <= options.stop_below) {
        status = GjkStatus::StoppedEarly;
        break;
      }
      const SupportHit ha = sa(-v);
      const SupportHit hb = sb(v);
      const Vec3 w = ha.point - hb.point;
      const double vw = v.dot(w);
      lower = std::max(lower, vw / v_norm - ha.slack - hb.slack);
      if (lower - radii - guard >= options.stop_above) {
        status = GjkStatus::StoppedEarly;
        break;
      }

      if (s.size > 0 && vv - vw <= tol * vv) {
        status = GjkStatus::Converged;
        break;
      }
      bool duplicate = false;
      for (int x = 0; x < s.size; ++x) duplicate |= (s.ka[x] == ha.key && s.kb[x] == hb.key);
      if (duplicate) {  // no new support point: v is optimal up to rounding
        status = GjkStatus::Converged;
        break;
      }
      // The new vertex goes into the next free slot; s keeps its size (and v's weights) until the
      // sub-algorithm's point is known to be closer, so a stop here reports v's witnesses.
      const int previous_size = s.size;
      const int count = previous_size + 1;
      s.w[previous_size] = w;
      s.a[previous_size] = ha.point;
      s.b[previous_size] = hb.point;
      s.ka[previous_size] = ha.key;
      s.kb[previous_size] = hb.key;
      double lam[4];
      closestWeights(s, count, lam);
      const Vec3 next = combine(s.w, lam);
      const double next_vv = next.squaredNorm();
      const bool inside = count == 4 && lam[0] > 0.0 && lam[1] > 0.0 && lam[2] > 0.0 && lam[3] > 0.0;
      if (inside || next_vv <= overlap_vv) {
        keepWeighted(s, count, lam);
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
      keepWeighted(s, count, lam);
      v = next;
    }
  }

  result.iterations = iter;
  result.status = status;
  Vec3 pa = info.start_a;
  Vec3 pb = info.start_b;
  if (s.size > 0) {
    pa.setZero();
    pb.setZero();
    for (int x = 0; x < s.size; ++x) {
      pa += s.lambda[x] * s.a[x];
      pb += s.lambda[x] * s.b[x];
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
    result.witness_a = pa - ra * n;
    result.witness_b = pb + rb * n;
  } else {
    result.witness_a = pa;
    result.witness_b = pb;
  }
  return result;
}

}  // namespace kccd::detail
