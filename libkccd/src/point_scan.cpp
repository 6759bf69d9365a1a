// The AVX2 paths of the point scans (the scalar paths are inline in the header). libkccd is
// compiled with -ffp-contract=off: no multiply-add is fused, so both paths round alike.
#include "point_scan.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define KCCD_SUPPORT_AVX2 1
#include <immintrin.h>
#endif

namespace kccd::detail {

#ifdef KCCD_SUPPORT_AVX2

namespace {

// Four consecutive points (12 doubles) as their x, y and z columns.
__attribute__((target("avx2"))) inline void loadColumns(const double* p, __m256d& x, __m256d& y, __m256d& z) {
  const __m256d r0 = _mm256_loadu_pd(p);                    // x0 y0 z0 x1
  const __m256d r1 = _mm256_loadu_pd(p + 4);                // y1 z1 x2 y2
  const __m256d r2 = _mm256_loadu_pd(p + 8);                // z2 x3 y3 z3
  const __m256d m0 = _mm256_blend_pd(r0, r1, 0b1100);       // x0 y0 x2 y2
  const __m256d m1 = _mm256_permute2f128_pd(r0, r2, 0x21);  // z0 x1 z2 x3
  const __m256d m2 = _mm256_blend_pd(r1, r2, 0b1100);       // y1 z1 y3 z3
  x = _mm256_shuffle_pd(m0, m1, 0b1010);
  y = _mm256_shuffle_pd(m0, m2, 0b0101);
  z = _mm256_shuffle_pd(m1, m2, 0b1010);
}

__attribute__((target("avx2"))) inline __m256d dots(const double* p, __m256d dx, __m256d dy, __m256d dz) {
  __m256d x, y, z;
  loadColumns(p, x, y, z);
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, dx), _mm256_mul_pd(y, dy)), _mm256_mul_pd(z, dz));
}

}  // namespace

__attribute__((target("avx2"))) int supportIndexAvx2(std::span<const Vec3> pts, const Vec3& d) noexcept {
  const int n = static_cast<int>(pts.size());
  if (n < 4) return supportIndexScalar(pts, d);  // the first step reads four points
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "points are packed x, y, z");
  const double* base = pts.data()->data();
  const __m256d dx = _mm256_set1_pd(d.x()), dy = _mm256_set1_pd(d.y()), dz = _mm256_set1_pd(d.z());
  __m256d best_dot = dots(base, dx, dy, dz);
  __m256d best = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);  // indices, exact as doubles
  __m256d index = best;
  const __m256d four = _mm256_set1_pd(4.0);
  int k = 4;
  for (; k + 4 <= n; k += 4) {
    index = _mm256_add_pd(index, four);
    const __m256d value = dots(base + 3 * k, dx, dy, dz);
    // value > best (false for NaN), and max as std::max(value, best): best unless value is not less.
    best = _mm256_blendv_pd(best, index, _mm256_cmp_pd(value, best_dot, _CMP_GT_OQ));
    best_dot = _mm256_max_pd(best_dot, value);
  }
  alignas(32) double lane_dot[4];
  alignas(32) double lane_index[4];
  _mm256_store_pd(lane_dot, best_dot);
  _mm256_store_pd(lane_index, best);
  int lane_best[4];
  for (int lane = 0; lane < 4; ++lane) lane_best[lane] = static_cast<int>(lane_index[lane]);
  scan::tail(pts, d, k, lane_dot, lane_best);
  return scan::reduceLanes(lane_dot, lane_best);
}

__attribute__((target("avx2"))) PointSummary summarizeAvx2(std::span<const Vec3> pts) noexcept {
  const std::size_t n = pts.size();
  if (n < 4) return summarizeScalar(pts);  // each step reads four points
  const double* base = pts.data()->data();
  const __m256d no_sign = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffff));
  __m256d sx = _mm256_setzero_pd(), sy = sx, sz = sx, m = sx;
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    __m256d x, y, z;
    loadColumns(base + 3 * k, x, y, z);
    sx = _mm256_add_pd(sx, x);
    sy = _mm256_add_pd(sy, y);
    sz = _mm256_add_pd(sz, z);
    const __m256d a =
        _mm256_max_pd(_mm256_and_pd(x, no_sign), _mm256_max_pd(_mm256_and_pd(y, no_sign), _mm256_and_pd(z, no_sign)));
    m = _mm256_max_pd(m, a);
  }
  alignas(32) double sum[3][4];
  alignas(32) double lm[4];
  _mm256_store_pd(sum[0], sx);
  _mm256_store_pd(sum[1], sy);
  _mm256_store_pd(sum[2], sz);
  _mm256_store_pd(lm, m);
  // The maximum is exact whatever the order (a NaN coordinate is caught by its sum instead).
  double mm = std::max(std::max(lm[0], lm[1]), std::max(lm[2], lm[3]));
  scan::summaryTail(pts, k, sum, mm);
  return scan::finish(sum, mm, n);
}

bool detectAvx2() noexcept {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0;
}

#else

int supportIndexAvx2(std::span<const Vec3> pts, const Vec3& d) noexcept { return supportIndexScalar(pts, d); }
PointSummary summarizeAvx2(std::span<const Vec3> pts) noexcept { return summarizeScalar(pts); }
bool detectAvx2() noexcept { return false; }

#endif

}  // namespace kccd::detail
