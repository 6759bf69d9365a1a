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

#include "gjk_core.hpp"
#include "kccd/distance.hpp"
#include "rounding.hpp"

namespace kccd {
namespace {

using detail::pick;

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
  if (a.points.empty() || b.points.empty() || !(a.radius >= 0.0) || !(b.radius >= 0.0) || !std::isfinite(a.radius) ||
      !std::isfinite(b.radius)) {
    return result;  // InvalidInput, distance 0
  }
  const SetSummary sum_a = summarize(a.points);
  const SetSummary sum_b = summarize(b.points);
  if (!sum_a.finite || !sum_b.finite) return result;
  detail::SetsInfo info;
  info.scale_a = sum_a.scale;
  info.scale_b = sum_b.scale;
  info.start_a = sum_a.centroid;
  info.start_b = sum_b.centroid;
  const std::span<const Vec3> pa = a.points, pb = b.points;
  auto support_a = [pa](const Vec3& dir) {
    const int i = supportIndex(pa, dir);
    return detail::SupportHit{pa[static_cast<std::size_t>(i)], static_cast<std::uint64_t>(i), 0.0};
  };
  auto support_b = [pb](const Vec3& dir) {
    const int i = supportIndex(pb, dir);
    return detail::SupportHit{pb[static_cast<std::size_t>(i)], static_cast<std::uint64_t>(i), 0.0};
  };
  return detail::gjkDistance(support_a, support_b, a.radius, b.radius, info, options);
}

}  // namespace kccd
