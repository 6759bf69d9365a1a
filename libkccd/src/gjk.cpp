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
#include "point_scan.hpp"
#include "rounding.hpp"

namespace kccd {

using detail::summarize;
using detail::supportIndex;

bool allFinite(std::span<const Vec3> points) noexcept {
  return std::all_of(points.begin(), points.end(), [](const Vec3& p) { return p.allFinite(); });
}

DistanceResult distance(const SschView& a, const SschView& b, const GjkOptions& options) noexcept {
  DistanceResult result;
  if (a.points.empty() || b.points.empty() || !(a.radius >= 0.0) || !(b.radius >= 0.0) || !std::isfinite(a.radius) ||
      !std::isfinite(b.radius)) {
    return result;  // InvalidInput, distance 0
  }
  const detail::PointSummary sum_a = summarize(a.points);
  const detail::PointSummary sum_b = summarize(b.points);
  if (!sum_a.finite || !sum_b.finite) return result;
  detail::SetsInfo info;
  info.scale_a = sum_a.scale;
  info.scale_b = sum_b.scale;
  info.start_a = sum_a.centroid;
  info.start_b = sum_b.centroid;
  info.starts_in_hulls = true;
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
