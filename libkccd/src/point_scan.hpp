// Linear scans over a point set: the index of the point farthest along a direction (a support
// point), and the set's summary (largest absolute coordinate, finiteness, centroid). Internal.
//
// Every path computes each dot product as (x * dx + y * dy) + z * dz without a fused multiply-add
// (libkccd is compiled with -ffp-contract=off) and keeps four lanes, point k in lane k % 4 and
// the remaining n % 4 points in lane 0, reduced in one fixed order; the summary's coordinate sums
// are kept in the same lanes. So the scalar and the AVX2 path return the same index and the same
// summary, bit for bit, for every input, ties and NaN included.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include "kccd/ssch.hpp"

namespace kccd::detail {

/// One pass over a point set: its largest absolute coordinate (the rounding scale), whether every
/// coordinate is finite (and their sums do not overflow), and its centroid (a point of the hull,
/// up to rounding).
struct PointSummary {
  double scale = 0.0;
  bool finite = true;
  Vec3 centroid = Vec3::Zero();
};

/// The support scan with AVX2 (four points per step). Call only when avx2Available().
int supportIndexAvx2(std::span<const Vec3> pts, const Vec3& d) noexcept;
/// The summary with AVX2. Call only when avx2Available().
PointSummary summarizeAvx2(std::span<const Vec3> pts) noexcept;
/// Whether this CPU runs AVX2 instructions (asks the CPU; avx2Available() keeps the answer).
bool detectAvx2() noexcept;

/// True when this CPU runs AVX2 instructions (checked once).
inline bool avx2Available() noexcept {
  static const bool available = detectAvx2();
  return available;
}

// The scalar paths' parts, shared with the AVX2 paths' tails.
namespace scan {

// Branch-free select of an index.
inline int pick(bool condition, int if_true, int if_false) {
  return if_false ^ ((if_true ^ if_false) & -static_cast<int>(condition));
}

// The four lanes' maxima reduced in the scalar path's order: (0, 1), (2, 3), then the two.
inline int reduceLanes(const double* best_dot, const int* best) {
  const int ab = pick(best_dot[1] > best_dot[0], 1, 0);
  const int cd = pick(best_dot[3] > best_dot[2], 3, 2);
  return best[pick(best_dot[cd] > best_dot[ab], cd, ab)];
}

// Points [k, n) into lane 0, as the scalar path's tail does.
inline void tail(std::span<const Vec3> pts, const Vec3& d, int k, double* best_dot, int* best) {
  const int n = static_cast<int>(pts.size());
  for (; k < n; ++k) {
    const double value = pts[k].x() * d.x() + pts[k].y() * d.y() + pts[k].z() * d.z();
    best[0] = pick(value > best_dot[0], k, best[0]);
    best_dot[0] = std::max(value, best_dot[0]);
  }
}

}  // namespace scan

/// The support scan in plain C++ (every CPU): the index of the point of `pts` (not empty)
/// farthest along `d`.
inline int supportIndexScalar(std::span<const Vec3> pts, const Vec3& d) noexcept {
  const double dx = d.x(), dy = d.y(), dz = d.z();
  const int n = static_cast<int>(pts.size());
  auto dot = [&](int k) { return pts[k].x() * dx + pts[k].y() * dy + pts[k].z() * dz; };
  // Four independent running maxima with branch-free selects: the winner changes unpredictably,
  // and one serial compare chain would bound the speed.
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
      best[lane] = scan::pick(value > best_dot[lane], k + lane, best[lane]);
      best_dot[lane] = std::max(value, best_dot[lane]);
    }
  }
  scan::tail(pts, d, k, best_dot, best);
  return scan::reduceLanes(best_dot, best);
}

namespace scan {

// The summary from the lanes' coordinate sums (sum[coordinate][lane]) and the largest absolute
// coordinate.
inline PointSummary finish(const double (*sum)[4], double m, std::size_t n) {
  PointSummary out;
  const Vec3 total((sum[0][0] + sum[0][1]) + (sum[0][2] + sum[0][3]), (sum[1][0] + sum[1][1]) + (sum[1][2] + sum[1][3]),
                   (sum[2][0] + sum[2][1]) + (sum[2][2] + sum[2][3]));
  out.centroid = total / static_cast<double>(n);
  // A NaN or infinite coordinate makes its sum NaN or infinite (so does an overflowing sum, which
  // is rejected as well); an infinity also shows in the maximum.
  out.finite = out.centroid.allFinite() && m <= std::numeric_limits<double>::max();
  out.scale = m;
  return out;
}

// Points [k, n) into lane 0's sums and the maximum, as every path's tail does.
inline void summaryTail(std::span<const Vec3> pts, std::size_t k, double (*sum)[4], double& m) {
  for (; k < pts.size(); ++k) {
    const Vec3& p = pts[k];
    sum[0][0] += p.x();
    sum[1][0] += p.y();
    sum[2][0] += p.z();
    m = std::max(m, std::max(std::abs(p.x()), std::max(std::abs(p.y()), std::abs(p.z()))));
  }
}

}  // namespace scan

/// The summary of `pts` (not empty) in plain C++ (every CPU).
inline PointSummary summarizeScalar(std::span<const Vec3> pts) noexcept {
  double sum[3][4] = {};
  double m = 0.0;
  std::size_t k = 0;
  for (; k + 4 <= pts.size(); k += 4) {
    for (int lane = 0; lane < 4; ++lane) {
      const Vec3& p = pts[k + static_cast<std::size_t>(lane)];
      sum[0][lane] += p.x();
      sum[1][lane] += p.y();
      sum[2][lane] += p.z();
      m = std::max(m, std::max(std::abs(p.x()), std::max(std::abs(p.y()), std::abs(p.z()))));
    }
  }
  scan::summaryTail(pts, k, sum, m);
  return scan::finish(sum, m, pts.size());
}

/// The support scan of a short run of points (`pts` not empty), in order: the first point of the
/// largest dot product, each computed as the other paths do. Over finite dot products the largest
/// value is theirs bit for bit (a maximum does not depend on the order); on a tie the point named
/// may be another of that value.
inline int supportIndexInOrder(std::span<const Vec3> pts, const Vec3& d) noexcept {
  // Lane 0 alone: the first point, then the others as the lanes' tail takes them.
  double best_dot[1] = {pts[0].x() * d.x() + pts[0].y() * d.y() + pts[0].z() * d.z()};
  int best[1] = {0};
  scan::tail(pts, d, 1, best_dot, best);
  return best[0];
}

/// Sets smaller than this take the scalar paths, inlined where they are called: for them the AVX2
/// paths' set-up costs more than they save.
inline constexpr std::size_t kAvx2MinPoints = 8;

/// Index of the point of `pts` (not empty) farthest along `d`, by the fastest path for this set
/// and CPU.
inline int supportIndex(std::span<const Vec3> pts, const Vec3& d) noexcept {
  if (pts.size() >= kAvx2MinPoints && avx2Available()) return supportIndexAvx2(pts, d);
  return supportIndexScalar(pts, d);
}

/// The summary of `pts` (not empty), by the fastest path for this set and CPU.
inline PointSummary summarize(std::span<const Vec3> pts) noexcept {
  if (pts.size() >= kAvx2MinPoints && avx2Available()) return summarizeAvx2(pts);
  return summarizeScalar(pts);
}

}  // namespace kccd::detail
