#include "kccd/hull/sphere_polytope.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace kccd::hull {
namespace {

constexpr double kGuard = 1e-12;

}  // namespace

Icosphere icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Icosphere s;
  s.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& v : s.vertices) v.normalize();
  s.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      s.vertices.push_back((s.vertices[a] + s.vertices[b]).normalized());
      const int index = static_cast<int>(s.vertices.size()) - 1;
      mid.emplace(key, index);
      return index;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : s.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    s.triangles = std::move(next);
  }
  const std::vector<Vec3>& v = s.vertices;
  for (auto& f : s.triangles) {
    if ((v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).dot(v[f[0]]) < 0.0) std::swap(f[1], f[2]);
    const Vec3 n = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).normalized();
    s.min_plane = std::min(s.min_plane, std::abs(n.dot(v[f[0]])));
  }
  return s;
}

double circumscribedScale(const Icosphere& sphere) { return (1.0 / sphere.min_plane) * (1.0 + kGuard); }

std::vector<Vec3> circumscribedVertices(const Icosphere& sphere) {
  std::vector<Vec3> out;
  out.reserve(sphere.vertices.size());
  for (const Vec3& v : sphere.vertices) out.push_back(v * (1.0 / sphere.min_plane) * (1.0 + kGuard));
  return out;
}

}  // namespace kccd::hull
