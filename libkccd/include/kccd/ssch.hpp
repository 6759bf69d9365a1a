// Sphere swept convex hull (SSCH): the volume representation of every KCCD body.
#pragma once

#include <span>
#include <vector>

#include "kccd/types.hpp"

namespace kccd {

/// A non-owning view of an SSCH: the set of points within `radius` of conv(points).
/// This is what the distance routines take; it never allocates.
struct SschView {
  std::span<const Vec3> points;
  double radius = 0.0;
};

/// A sphere that contains a volume (not necessarily the smallest one).
struct Sphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
};

/// An owning SSCH: a non-empty set of finite core points and a finite radius >= 0.
/// The hull is never built; every operation works on the points only.
class Ssch {
 public:
  /// Throws std::invalid_argument for an empty set, non-finite values or a negative radius.
  Ssch(std::vector<Vec3> points, double radius);

  std::span<const Vec3> points() const { return points_; }
  double radius() const { return radius_; }
  SschView view() const { return {points_, radius_}; }

  /// The same volume after the rigid motion `pose` (exact).
  Ssch transformed(const Pose& pose) const;
  /// The volume grown by `margin` >= 0 in every direction (exact).
  Ssch inflated(double margin) const;
  /// Minkowski sum with the segment [from, to]: the volume swept by a translation (exact).
  Ssch sweptAlong(const Vec3& from, const Vec3& to) const;
  /// Drops core points that lie within `tolerance` of the hull of the remaining ones. The radius
  /// grows by the sum of the dropped points' distances (plus a rounding guard), so the result
  /// always contains the original volume. With the default 0 only non-vertices are dropped.
  Ssch pruned(double tolerance = 0.0) const;
  /// A sphere containing the whole volume (centre of the points' bounding box).
  Sphere boundingSphere() const;

 private:
  std::vector<Vec3> points_;
  double radius_;
};

/// True when every coordinate of every point is finite.
bool allFinite(std::span<const Vec3> points) noexcept;

}  // namespace kccd
