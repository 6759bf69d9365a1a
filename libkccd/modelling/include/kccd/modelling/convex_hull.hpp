// Convex hulls of point sets (qhull for solids, own code for flat and lower-dimensional sets)
// and the closed-form volume of an SSCH built on them.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "kccd/types.hpp"

namespace kccd::modelling {

/// The hull of a point set with the coefficients of its Steiner polynomial:
/// volume(hull ⊕ ball(r)) = volume + area·r + edge_term·r² + (4/3)π r³.
struct ConvexHull {
  int dimension = 0;                          ///< 0 point, 1 segment, 2 polygon, 3 solid
  std::vector<int> vertices;                  ///< indices of the input points on the hull
  std::vector<std::array<int, 3>> triangles;  ///< outward triangles (input indices), solids only
  double volume = 0.0;
  double area = 0.0;       ///< both sides for a polygon
  double edge_term = 0.0;  ///< ½ Σ edge length × exterior dihedral angle

  double sschVolume(double radius) const;
};

/// Hull of `points` (at least one). Sets thinner than 1e-10 of their extent count as flat.
ConvexHull convexHull(std::span<const Vec3> points);

}  // namespace kccd::modelling
