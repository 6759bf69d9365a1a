#include "kccd/render/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>

#include "mesh_edges.hpp"

namespace kccd::render {
namespace detail {

void buildEdges(Mesh& mesh) {
  std::vector<std::array<std::uint32_t, 3>> half;  // low vertex, high vertex, triangle
  half.reserve(mesh.triangles.size() * 3);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto [lo, hi] = std::minmax(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]);
      half.push_back({lo, hi, t});
    }
  std::sort(half.begin(), half.end());
  mesh.edges.clear();
  mesh.edges.reserve(half.size() / 2);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i + 1;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    mesh.edges.push_back({half[i][0], half[i][1], half[i][2], half[j - 1][2]});
    i = j;
  }
}

// Linear time: the half-edges are bucketed by their lower vertex and paired within each (small) bucket.
bool closeUp(Mesh& mesh) {
  const std::size_t nv = mesh.vertices.size();
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (const auto& tri : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      if (a == b) return false;
      ++start[std::min(a, b) + 1];
    }
  for (std::size_t i = 0; i < nv; ++i) start[i + 1] += start[i];
  struct Half {
    std::uint32_t hi, triangle;
    bool forward;
  };
  std::vector<Half> half(start[nv]);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      half[fill[std::min(a, b)]++] = Half{std::max(a, b), t, a < b};
    }
  mesh.edges.clear();
  mesh.edges.reserve(half.size() / 2);
  for (std::uint32_t lo = 0; lo < nv; ++lo) {
    const std::uint32_t begin = start[lo], end = start[lo + 1];
    for (std::uint32_t i = begin; i < end; ++i) {
      if (half[i].hi == UINT32_MAX) continue;  // already paired
      std::uint32_t match = UINT32_MAX;
      for (std::uint32_t j = i + 1; j < end; ++j)
        if (half[j].hi == half[i].hi) {
          if (match != UINT32_MAX || half[j].forward == half[i].forward) return false;
          match = j;
        }
      if (match == UINT32_MAX) return false;
      mesh.edges.push_back({lo, half[i].hi, half[i].triangle, half[match].triangle});
      half[match].hi = UINT32_MAX;
    }
  }
  return static_cast<long>(nv) - static_cast<long>(mesh.edges.size()) + static_cast<long>(mesh.triangles.size()) == 2;
}

}  // namespace detail

Mesh surfaceMesh(std::span<const Vec3> triangle_points) {
  if (triangle_points.size() % 3 != 0) throw std::invalid_argument("surfaceMesh: not whole triangles");
  Mesh mesh;
  // Equal points share a vertex (smooth shading) when their triangles' normals are within 40
  // degrees of the first triangle that made the vertex; across sharper creases (and between
  // faces turned the opposite way) they do not: a box stays a box.
  std::map<std::array<double, 3>, std::vector<std::uint32_t>> index;
  std::vector<Vec3> first_normal;
  const double crease = std::cos(40.0 * 3.141592653589793 / 180.0);
  auto vertex = [&](const Vec3& p, const Vec3& n) {
    if (!p.allFinite()) throw std::invalid_argument("surfaceMesh: non-finite point");
    std::vector<std::uint32_t>& at = index[{p.x(), p.y(), p.z()}];
    for (const std::uint32_t k : at)
      if (first_normal[k].dot(n) >= crease) return k;
    at.push_back(static_cast<std::uint32_t>(mesh.vertices.size()));
    mesh.vertices.push_back(p);
    first_normal.push_back(n);
    return at.back();
  };
  for (std::size_t t = 0; t < triangle_points.size(); t += 3) {
    const Vec3& a = triangle_points[t];
    const Vec3 n = (triangle_points[t + 1] - a).cross(triangle_points[t + 2] - a);
    if (!(n.norm() > 0.0) || !n.allFinite()) {
      if (!a.allFinite() || !triangle_points[t + 1].allFinite() || !triangle_points[t + 2].allFinite())
        throw std::invalid_argument("surfaceMesh: non-finite point");
      continue;
    }
    const Vec3 u = n.normalized();
    mesh.triangles.push_back({vertex(a, u), vertex(triangle_points[t + 1], u), vertex(triangle_points[t + 2], u)});
    mesh.normals.push_back(u);
  }
  return mesh;
}

}  // namespace kccd::render
