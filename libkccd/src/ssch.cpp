#include "kccd/ssch.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bounding_sphere.hpp"
#include "kccd/distance.hpp"
#include "rounding.hpp"

namespace kccd {

Ssch::Ssch(std::vector<Vec3> points, double radius) : points_(std::move(points)), radius_(radius) {
  if (points_.empty()) throw std::invalid_argument("SSCH needs at least one point");
  if (!allFinite(points_)) throw std::invalid_argument("SSCH point is not finite");
  if (!std::isfinite(radius_) || radius_ < 0.0)
    throw std::invalid_argument("SSCH radius must be finite and >= 0, got " + std::to_string(radius_));
}

Ssch Ssch::transformed(const Pose& pose) const {
  std::vector<Vec3> out;
  out.reserve(points_.size());
  for (const Vec3& p : points_) out.push_back(pose * p);
  return Ssch(std::move(out), radius_);
}

Ssch Ssch::inflated(double margin) const {
  if (!(margin >= 0.0)) throw std::invalid_argument("inflation must be >= 0");
  return Ssch(points_, radius_ + margin);
}

Ssch Ssch::sweptAlong(const Vec3& from, const Vec3& to) const {
  std::vector<Vec3> out;
  out.reserve(2 * points_.size());
  for (const Vec3& p : points_) out.push_back(p + from);
  if (to != from)
    for (const Vec3& p : points_) out.push_back(p + to);
  return Ssch(std::move(out), radius_);
}

Ssch Ssch::pruned(double tolerance) const {
  if (!(tolerance >= 0.0)) throw std::invalid_argument("pruning tolerance must be >= 0");
  std::vector<Vec3> kept = points_;
  double scale = 0.0;
  for (const Vec3& p : kept) scale = std::max(scale, p.cwiseAbs().maxCoeff());
  const double guard = detail::roundingGuard(scale, 64);
  double growth = 0.0;
  // A point is dropped when the hull of the remaining points comes within tolerance of it; the
  // upper bound of that distance (GJK's |v|) is added to the radius, so nothing is lost.
  for (std::size_t i = kept.size(); i-- > 0 && kept.size() > 1;) {
    std::swap(kept[i], kept.back());
    const SschView rest{std::span<const Vec3>(kept.data(), kept.size() - 1), 0.0};
    const SschView candidate{std::span<const Vec3>(&kept.back(), 1), 0.0};
    const DistanceResult d = distance(candidate, rest);
    if (d.hull_upper <= tolerance + guard) {
      growth += d.hull_upper + guard;
      kept.pop_back();
    } else {
      std::swap(kept[i], kept.back());
    }
  }
  return Ssch(std::move(kept), radius_ + growth);
}

Sphere Ssch::boundingSphere() const { return detail::boundingSphere(points_, radius_); }

namespace detail {

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
  s.radius = roundedUp(std::sqrt(r), 4) + radius;
  return s;
}

}  // namespace detail

}  // namespace kccd
