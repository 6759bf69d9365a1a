// Seeds of the SSCH fit (fit.cpp): spread-out points, offset clouds of a rounded part, a greedy
// largest hull, k-means; internal to the modelling part.
#pragma once

#include <vector>

#include "kccd/modelling/convex_hull.hpp"
#include "kccd/types.hpp"

namespace kccd::modelling::detail {

/// Farthest-point selection of k points of `pool` (not empty), the first the farthest from
/// `center`; repeated (or `center`) when the pool has fewer.
std::vector<Vec3> farthestPoints(const std::vector<Vec3>& pool, const Vec3& center, int k);
/// The mean of a non-empty point set.
Vec3 centroid(const std::vector<Vec3>& points);
/// Per point of `points` (the input of the solid hull `h`), the sum of its hull triangles' unit
/// normals weighted by each triangle's angle at it: zero for a point on no triangle.
std::vector<Vec3> vertexNormals(const std::vector<Vec3>& points, const ConvexHull& h);
/// The hull's vertices moved inwards by each r of `radii` along their normals, one cloud per r.
std::vector<std::vector<Vec3>> offsetClouds(const std::vector<Vec3>& points, const std::vector<double>& radii);
/// k points of `all` (not empty) whose hull is as large as a greedy choice makes it.
std::vector<Vec3> greatestHull(const std::vector<Vec3>& all, int k);
/// Lloyd's k-means of `pool` from `seeds` (12 rounds); a seed with no point stays.
std::vector<Vec3> kMeans(const std::vector<Vec3>& pool, std::vector<Vec3> seeds);

}  // namespace kccd::modelling::detail
