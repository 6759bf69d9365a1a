#include "kccd/render/ssch_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include "kccd/hull/qhull.hpp"
#include "kccd/hull/sphere_polytope.hpp"

namespace kccd::render {
namespace {

SpherePolytope makeSphere(int level) {
  const hull::Icosphere ico = hull::icosphere(level);
  const std::vector<Vec3>& v = ico.vertices;
  SpherePolytope s;
  double max_angle = 0.0;
  for (const auto& t3 : ico.triangles) {
    s.triangles.push_back({static_cast<std::uint32_t>(t3[0]), static_cast<std::uint32_t>(t3[1]),
                           static_cast<std::uint32_t>(t3[2])});
    const Vec3 n = (v[t3[1]] - v[t3[0]]).cross(v[t3[2]] - v[t3[0]]).normalized();
    for (int k = 0; k < 3; ++k) max_angle = std::max(max_angle, std::acos(std::clamp(std::abs(n.dot(v[t3[k]])), -1.0, 1.0)));
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> owner;  // directed edge -> triangle
  for (std::uint32_t t = 0; t < s.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) owner[{s.triangles[t][k], s.triangles[t][(k + 1) % 3]}] = t;
  for (const auto& tri : s.triangles) {
    std::array<std::uint32_t, 3> nb{};
    for (int k = 0; k < 3; ++k) nb[k] = owner.at({tri[(k + 1) % 3], tri[k]});
    s.neighbours.push_back(nb);
  }
  s.vertices = v;
  s.scale = hull::circumscribedScale(ico);
  s.cone_chord = 2.0 * std::sin(max_angle / 2.0) * (1.0 + 1e-9) + 1e-12;
  return s;
}

// Fills Mesh::edges from the triangles (sorted half-edges, paired up).
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

// The sphere polytope of radius r around a, swept along the segment to b: faces whose normal
// points along b - a are moved to b, the others stay at a, and every edge between the two
// kinds becomes a parallelogram. That is exactly the boundary of hull(S + a, S + b).
Mesh segmentMesh(const SpherePolytope& sphere, const Vec3& a, const Vec3& b, double r) {
  const Vec3 d = b - a;
  const auto nv = static_cast<std::uint32_t>(sphere.vertices.size());
  std::vector<char> front(sphere.triangles.size());
  std::vector<Vec3> normals(sphere.triangles.size());
  for (std::size_t t = 0; t < sphere.triangles.size(); ++t) {
    const auto& tri = sphere.triangles[t];
    normals[t] = (sphere.vertices[tri[1]] - sphere.vertices[tri[0]])
                     .cross(sphere.vertices[tri[2]] - sphere.vertices[tri[0]])
                     .normalized();
    front[t] = normals[t].dot(d) > 0.0;
  }
  Mesh raw;
  for (const Vec3& v : sphere.vertices) raw.vertices.push_back(a + r * v);
  for (const Vec3& v : sphere.vertices) raw.vertices.push_back(b + r * v);
  for (std::size_t t = 0; t < sphere.triangles.size(); ++t) {
    const std::uint32_t off = front[t] ? nv : 0;
    const auto& tri = sphere.triangles[t];
    raw.triangles.push_back({tri[0] + off, tri[1] + off, tri[2] + off});
    raw.normals.push_back(normals[t]);
  }
  // Silhouette edges of S seen along d: the front triangle holds the edge as u -> w.
  for (std::size_t t = 0; t < sphere.triangles.size(); ++t) {
    if (!front[t]) continue;
    const auto& tri = sphere.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], w = tri[(k + 1) % 3];
      if (front[sphere.neighbours[t][k]]) continue;  // not a silhouette edge
      const std::array<std::uint32_t, 3> t1{u, w, w + nv}, t2{u, w + nv, u + nv};
      Vec3 n = (raw.vertices[w] - raw.vertices[u]).cross(d);
      n = n.norm() > 0.0 ? n.normalized() : normals[t];
      raw.triangles.push_back(t1);
      raw.triangles.push_back(t2);
      raw.normals.push_back(n);
      raw.normals.push_back(n);
    }
  }
  // Keep only the vertices in use.
  Mesh mesh;
  std::vector<std::int64_t> index(raw.vertices.size(), -1);
  for (auto& tri : raw.triangles)
    for (auto& i : tri) {
      if (index[i] < 0) {
        index[i] = static_cast<std::int64_t>(mesh.vertices.size());
        mesh.vertices.push_back(raw.vertices[i]);
      }
      i = static_cast<std::uint32_t>(index[i]);
    }
  mesh.triangles = std::move(raw.triangles);
  mesh.normals = std::move(raw.normals);
  return mesh;
}

}  // namespace

const SpherePolytope& spherePolytope(int level) {
  static std::once_flag once;
  static std::vector<SpherePolytope> levels;
  std::call_once(once, [] {
    for (int l = 0; l <= 5; ++l) levels.push_back(makeSphere(l));
  });
  return levels.at(static_cast<std::size_t>(std::clamp(level, 0, 5)));
}

Mesh buildSschMesh(std::span<const Vec3> points, double radius, int level, double min_radius) {
  if (points.empty()) throw std::invalid_argument("buildSschMesh: no core points");
  if (!allFinite(points) || !std::isfinite(radius) || radius < 0.0 || !(min_radius > 0.0))
    throw std::invalid_argument("buildSschMesh: non-finite point or bad radius");
  const SpherePolytope& sphere = spherePolytope(level);
  double extent = 0.0;
  for (const Vec3& p : points) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  // Guard for the float conversion of vertices when drawing (a micrometre at 1 m).
  const double pad = 1e-6 * (1.0 + extent);
  const double big_r = (std::max(radius, min_radius) + pad) * sphere.scale;

  const bool one_point = std::all_of(points.begin(), points.end(), [&](const Vec3& p) { return p == points[0]; });
  if (one_point || points.size() == 2) {
    Mesh mesh = segmentMesh(sphere, points[0], points.back(), big_r);
    mesh.level = level;
    mesh.mesh_radius = big_r;
    buildEdges(mesh);
    return mesh;
  }

  // Only p_i + R v_j that can be vertices of the Minkowski sum: p_i must then be a support
  // point of the core set for some direction d in the normal cone of v_j, and |d - v_j| <= c
  // (cone_chord), so v_j·(p_i - p_k) >= d·(p_i - p_k) - c |p_i - p_k| >= -c |p_i - p_k| for
  // every core point p_k. Points failing that for some p_k are left out.
  const std::size_t k = points.size();
  std::vector<double> dist(k * k), dots(k);
  for (std::size_t i = 0; i < k; ++i)
    for (std::size_t j = 0; j < k; ++j) dist[i * k + j] = (points[i] - points[j]).norm();
  const double slack = 1e-12 * (1.0 + extent);
  std::vector<double> coords;
  coords.reserve(sphere.vertices.size() * 3 * 2);
  for (const Vec3& v : sphere.vertices) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < k; ++i) {
      dots[i] = v.dot(points[i]);
      if (dots[i] > dots[best]) best = i;
    }
    for (std::size_t i = 0; i < k; ++i) {
      bool keep = dots[i] - dots[best] >= -sphere.cone_chord * dist[i * k + best] - slack;
      for (std::size_t o = 0; keep && o < k; ++o)
        keep = dots[i] - dots[o] >= -sphere.cone_chord * dist[i * k + o] - slack;
      if (!keep) continue;
      const Vec3 q = points[i] + big_r * v;
      coords.insert(coords.end(), {q.x(), q.y(), q.z()});
    }
  }
  const int n = static_cast<int>(coords.size() / 3);

  Mesh mesh;
  mesh.level = level;
  mesh.mesh_radius = big_r;
  mesh.hull_input = n;
  const hull::QhullResult result = hull::convexHull3(coords);
  const int code = result.code;
  if (code == 0) {
    std::vector<int> index(static_cast<std::size_t>(n), -1);
    auto vertexIndex = [&](int id) {
      if (index[id] < 0) {
        index[id] = static_cast<int>(mesh.vertices.size());
        mesh.vertices.emplace_back(coords[3 * id], coords[3 * id + 1], coords[3 * id + 2]);
      }
      return static_cast<std::uint32_t>(index[id]);
    };
    for (const hull::QhullFacet& facet : result.facets) {
      std::vector<std::uint32_t> ids;
      for (const int id : facet.vertices) ids.push_back(vertexIndex(id));
      const Vec3& normal = facet.normal;
      for (std::size_t k = 1; k + 1 < ids.size(); ++k) {
        std::array<std::uint32_t, 3> t{ids[0], ids[k], ids[k + 1]};
        const Vec3 n3 =
            (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
        if (n3.dot(normal) < 0.0) std::swap(t[1], t[2]);
        mesh.triangles.push_back(t);
        mesh.normals.push_back(normal);
      }
    }
  }
  if (code != 0 || mesh.triangles.empty())
    throw std::runtime_error("buildSschMesh: qhull failed (code " + std::to_string(code) + ")");

  buildEdges(mesh);
  return mesh;
}

std::shared_ptr<const Mesh> MeshCache::get(std::span<const Vec3> points, double radius, int level,
                                           double min_radius) {
  std::string key(points.size() * sizeof(Vec3) + 2 * sizeof(double) + sizeof(int), '\0');
  std::memcpy(key.data(), points.data(), points.size() * sizeof(Vec3));
  std::memcpy(key.data() + points.size() * sizeof(Vec3), &radius, sizeof(double));
  std::memcpy(key.data() + points.size() * sizeof(Vec3) + sizeof(double), &level, sizeof(int));
  std::memcpy(key.data() + points.size() * sizeof(Vec3) + sizeof(double) + sizeof(int), &min_radius, sizeof(double));
  auto it = entries_.find(key);
  if (it != entries_.end()) {
    it->second.used = frame_;
    ++reused_;
    return it->second.mesh;
  }
  if (entries_.size() >= capacity_) {
    std::erase_if(entries_, [&](const auto& e) { return e.second.used + 2 < frame_; });
    if (entries_.size() >= capacity_) entries_.clear();
  }
  auto mesh = std::make_shared<const Mesh>(buildSschMesh(points, radius, level, min_radius));
  ++built_;
  entries_.emplace(std::move(key), Entry{mesh, frame_});
  return mesh;
}

}  // namespace kccd::render
