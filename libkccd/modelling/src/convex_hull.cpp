#include "kccd/modelling/convex_hull.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "kccd/hull/principal.hpp"
#include "kccd/hull/qhull.hpp"

namespace kccd::modelling {
namespace {

// Principal frame of a point set: columns sorted by decreasing spread.
struct Principal {
  Vec3 centroid;
  Eigen::Matrix3d axes;
  Vec3 extent;  // max - min along each axis
};

Principal principal(std::span<const Vec3> points) {
  const hull::PrincipalFrame frame = hull::principalFrame(points);
  Principal p;
  p.centroid = frame.mean;
  for (int i = 0; i < 3; ++i) p.axes.col(i) = frame.axes.col(2 - i);
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& v : points) {
    const Vec3 c = p.axes.transpose() * (v - p.centroid);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  p.extent = hi - lo;
  return p;
}

// Andrew's monotone chain on 2-D coordinates; returns indices in counter-clockwise order.
std::vector<int> hull2d(const std::vector<Eigen::Vector2d>& q) {
  std::vector<int> idx(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) idx[i] = static_cast<int>(i);
  std::sort(idx.begin(), idx.end(),
            [&](int a, int b) { return q[a].x() < q[b].x() || (q[a].x() == q[b].x() && q[a].y() < q[b].y()); });
  auto cross = [&](int o, int a, int b) {
    return (q[a] - q[o]).x() * (q[b] - q[o]).y() - (q[a] - q[o]).y() * (q[b] - q[o]).x();
  };
  std::vector<int> h(2 * idx.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < idx.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], idx[i]) <= 0) --k;
    h[k++] = idx[i];
  }
  for (std::size_t i = idx.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], idx[i]) <= 0) --k;
    h[k++] = idx[i];
  }
  h.resize(k > 1 ? k - 1 : k);
  return h;
}

ConvexHull lowDimensional(std::span<const Vec3> points, const Principal& p, int dimension) {
  ConvexHull h;
  h.dimension = dimension;
  if (dimension == 0) {
    h.vertices = {0};
    return h;
  }
  if (dimension == 1) {
    int lo = 0, hi = 0;
    double tlo = INFINITY, thi = -INFINITY;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double t = p.axes.col(0).dot(points[i] - p.centroid);
      if (t < tlo) tlo = t, lo = static_cast<int>(i);
      if (t > thi) thi = t, hi = static_cast<int>(i);
    }
    h.vertices = {lo, hi};
    h.edge_term = std::numbers::pi * (points[hi] - points[lo]).norm();
    return h;
  }
  std::vector<Eigen::Vector2d> q;
  q.reserve(points.size());
  for (const Vec3& v : points) q.emplace_back(p.axes.col(0).dot(v - p.centroid), p.axes.col(1).dot(v - p.centroid));
  h.vertices = hull2d(q);
  double area = 0.0, perimeter = 0.0;
  for (std::size_t i = 0; i < h.vertices.size(); ++i) {
    const int a = h.vertices[i], b = h.vertices[(i + 1) % h.vertices.size()];
    area += q[a].x() * q[b].y() - q[b].x() * q[a].y();
    perimeter += (points[b] - points[a]).norm();
  }
  h.area = std::abs(area);  // 2 × polygon area: both sides
  h.edge_term = std::numbers::pi * perimeter / 2.0;
  return h;
}

bool solid(std::span<const Vec3> points, ConvexHull& h) {
  std::vector<double> coords;
  coords.reserve(points.size() * 3);
  for (const Vec3& v : points) coords.insert(coords.end(), {v.x(), v.y(), v.z()});
  const hull::QhullResult result = hull::convexHull3(coords);
  const bool ok = result.code == 0;
  if (ok) {
    h.vertices = result.vertices;
    for (const hull::QhullFacet& facet : result.facets) {
      if (facet.vertices.size() < 3) continue;
      std::array<int, 3> t{facet.vertices[0], facet.vertices[1], facet.vertices[2]};
      const Vec3 cross = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]);
      if (cross.dot(facet.normal) < 0) std::swap(t[1], t[2]);
      h.triangles.push_back(t);
    }
  }
  if (!ok || h.triangles.size() < 4) return false;
  // Volume, area and the edge term from the triangles (coplanar neighbours contribute 0).
  const Vec3 inside = points[h.triangles[0][0]];
  std::map<std::pair<int, int>, Vec3> edges;  // directed edge -> outward normal of its triangle
  for (const auto& t : h.triangles) {
    const Vec3 a = points[t[0]], b = points[t[1]], c = points[t[2]];
    const Vec3 cross = (b - a).cross(c - a);
    h.area += cross.norm() / 2.0;
    h.volume += (a - inside).dot((b - inside).cross(c - inside)) / 6.0;
    const Vec3 n = cross.normalized();
    for (int k = 0; k < 3; ++k) edges[{t[k], t[(k + 1) % 3]}] = n;
  }
  for (const auto& [e, n] : edges) {
    if (e.first > e.second) continue;
    auto it = edges.find({e.second, e.first});
    if (it == edges.end()) continue;
    const double c = std::clamp(n.dot(it->second), -1.0, 1.0);
    h.edge_term += 0.5 * (points[e.second] - points[e.first]).norm() * std::acos(c);
  }
  h.volume = std::abs(h.volume);
  return true;
}

}  // namespace

double ConvexHull::sschVolume(double r) const {
  return volume + area * r + edge_term * r * r + 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

ConvexHull convexHull(std::span<const Vec3> points) {
  if (points.empty()) throw std::invalid_argument("convexHull: no points");
  const Principal p = principal(points);
  const double size = p.extent.maxCoeff();
  const double tol = 1e-10 * std::max(size, 1e-300);
  int dimension = 0;
  for (int i = 0; i < 3; ++i)
    if (p.extent(i) > tol && size > 0) ++dimension;
  if (dimension == 3) {
    ConvexHull h;
    h.dimension = 3;
    if (solid(points, h)) return h;
    dimension = 2;  // too thin for qhull: treat as flat (a report-only underestimate)
  }
  return lowDimensional(points, p, dimension);
}

}  // namespace kccd::modelling
