#include "fit_seeds.hpp"

#include <algorithm>
#include <cmath>

namespace kccd::modelling::detail {

// Farthest-point selection of k seeds among the constraint points (and ball centres).
std::vector<Vec3> farthestPoints(const std::vector<Vec3>& pool, const Vec3& center, int k) {
  std::vector<Vec3> out;
  std::vector<double> d(pool.size(), INFINITY);
  std::size_t next = 0;
  for (std::size_t i = 0; i < pool.size(); ++i)
    if ((pool[i] - center).squaredNorm() > (pool[next] - center).squaredNorm()) next = i;
  for (int j = 0; j < k && j < static_cast<int>(pool.size()); ++j) {
    out.push_back(pool[next]);
    for (std::size_t i = 0; i < pool.size(); ++i) d[i] = std::min(d[i], (pool[i] - pool[next]).squaredNorm());
    next = static_cast<std::size_t>(std::max_element(d.begin(), d.end()) - d.begin());
  }
  while (static_cast<int>(out.size()) < k) out.push_back(out.empty() ? center : out.back());
  return out;
}

// The mean of a non-empty point set.
Vec3 centroid(const std::vector<Vec3>& points) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

// Per point of `points` (the input of the solid hull `h`), the sum of its hull triangles' unit
// normals weighted by each triangle's angle at it: zero for a point on no triangle.
std::vector<Vec3> vertexNormals(const std::vector<Vec3>& points, const ConvexHull& h) {
  std::vector<Vec3> normal(points.size(), Vec3::Zero());
  for (const auto& t : h.triangles) {
    const Vec3 n = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]);
    if (!(n.norm() > 0.0)) continue;
    for (int k = 0; k < 3; ++k) {  // weighted by the triangle's angle at the vertex
      const Vec3 e1 = points[t[(k + 1) % 3]] - points[t[k]], e2 = points[t[(k + 2) % 3]] - points[t[k]];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      normal[t[k]] += angle * n.normalized();
    }
  }
  return normal;
}

// The hull's vertices moved inwards by r along their (angle-weighted) normals: each stays within
// r of its vertex, so any core whose SSCH of radius r holds these points' hull covers the part.
// On rounded parts the moved vertices gather (a cylinder's rim moved by its radius lands on its
// axis), and a few of them describe the part: seeds for every scale of rounding.
std::vector<std::vector<Vec3>> offsetClouds(const std::vector<Vec3>& points, const std::vector<double>& radii) {
  std::vector<std::vector<Vec3>> out;
  const ConvexHull h = convexHull(points);
  if (h.dimension < 3) return out;
  const std::vector<Vec3> normal = vertexNormals(points, h);
  for (const double r : radii) {
    std::vector<Vec3> cloud;
    for (int i : h.vertices)
      if (normal[i].norm() > 0.0) cloud.push_back(points[i] - r * normal[i].normalized());
    if (!cloud.empty()) out.push_back(std::move(cloud));
  }
  return out;
}

// k points of `cloud` (not empty) whose hull is as large as a greedy choice makes it: three
// spread out, then each time the point that grows the hull most.
std::vector<Vec3> greatestHull(const std::vector<Vec3>& all, int k) {
  // Chosen among 48 points spread over the cloud (each step builds one hull per candidate).
  const std::vector<Vec3> cloud = all.size() > 48 ? farthestPoints(all, centroid(all), 48) : all;
  std::vector<Vec3> out = farthestPoints(cloud, centroid(cloud), std::min(k, 3));
  while (static_cast<int>(out.size()) < k) {
    double best = -1.0;
    std::size_t pick = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      std::vector<Vec3> trial = out;
      trial.push_back(cloud[i]);
      const ConvexHull h = convexHull(trial);
      const double size = h.dimension == 3 ? h.volume : h.dimension == 2 ? 1e-9 * h.area : 0.0;
      if (size > best) best = size, pick = i;
    }
    out.push_back(cloud[pick]);
  }
  return out;
}

std::vector<Vec3> kMeans(const std::vector<Vec3>& pool, std::vector<Vec3> seeds) {
  for (int iter = 0; iter < 12; ++iter) {
    std::vector<Vec3> sum(seeds.size(), Vec3::Zero());
    std::vector<int> count(seeds.size(), 0);
    for (const Vec3& p : pool) {
      std::size_t best = 0;
      for (std::size_t j = 1; j < seeds.size(); ++j)
        if ((p - seeds[j]).squaredNorm() < (p - seeds[best]).squaredNorm()) best = j;
      sum[best] += p;
      ++count[best];
    }
    for (std::size_t j = 0; j < seeds.size(); ++j)
      if (count[j] > 0) seeds[j] = sum[j] / count[j];
  }
  return seeds;
}

}  // namespace kccd::modelling::detail
