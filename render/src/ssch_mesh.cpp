#include "kccd/render/ssch_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>

#include <Eigen/Geometry>

#include "kccd/hull/qhull.hpp"
#include "kccd/hull/sphere_polytope.hpp"
#include "kccd/ssch.hpp"
#include "mesh_edges.hpp"

namespace kccd::render {
namespace {

SpherePolytope makeSphere(int level) {
  const hull::Icosphere ico = hull::icosphere(level);
  const std::vector<Vec3>& v = ico.vertices;
  SpherePolytope s;
  double max_angle = 0.0;
  for (const auto& t3 : ico.triangles) {
    s.triangles.push_back(
        {static_cast<std::uint32_t>(t3[0]), static_cast<std::uint32_t>(t3[1]), static_cast<std::uint32_t>(t3[2])});
    const Vec3 n = (v[t3[1]] - v[t3[0]]).cross(v[t3[2]] - v[t3[0]]).normalized();
    for (int k = 0; k < 3; ++k)
      max_angle = std::max(max_angle, std::acos(std::clamp(std::abs(n.dot(v[t3[k]])), -1.0, 1.0)));
  }
  // Directed edge u -> w to its triangle, listed under u (each vertex starts 5 or 6 edges).
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> owner(v.size());
  for (std::uint32_t t = 0; t < s.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) owner[s.triangles[t][k]].emplace_back(s.triangles[t][(k + 1) % 3], t);
  const auto triangleOf = [&owner](std::uint32_t u, std::uint32_t w) {
    for (const auto& [to, t] : owner[u])
      if (to == w) return t;
    throw std::logic_error("spherePolytope: an edge without its twin");
  };
  for (const auto& tri : s.triangles) {
    std::array<std::uint32_t, 3> nb{};
    for (int k = 0; k < 3; ++k) nb[k] = triangleOf(tri[(k + 1) % 3], tri[k]);
    s.neighbours.push_back(nb);
  }
  s.vertices = v;
  s.scale = hull::circumscribedScale(ico);
  s.cone_chord = 2.0 * std::sin(max_angle / 2.0) * (1.0 + 1e-9) + 1e-12;
  return s;
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
  // Each level made the first time it is asked for (level 5's 20,480 faces take most of the time,
  // and a frame rarely needs it).
  constexpr int kLevels = 6;
  static std::array<std::once_flag, kLevels> once;
  static std::array<std::optional<SpherePolytope>, kLevels> levels;
  const auto l = static_cast<std::size_t>(std::clamp(level, 0, kLevels - 1));
  std::call_once(once[l], [l] { levels[l].emplace(makeSphere(static_cast<int>(l))); });
  return *levels[l];
}

namespace {

// The previous construction, kept as the fallback of the direct one: the hull (qhull) of the
// circumscribed sphere polytope around every core point that can give a vertex of the sum.
Mesh hullMesh(std::span<const Vec3> points, double radius, int level, double min_radius) {
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
    detail::buildEdges(mesh);
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
        const Vec3 n3 = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
        if (n3.dot(normal) < 0.0) std::swap(t[1], t[2]);
        mesh.triangles.push_back(t);
        mesh.normals.push_back(normal);
      }
    }
  }
  if (code != 0 || mesh.triangles.empty())
    throw std::runtime_error("buildSschMesh: qhull failed (code " + std::to_string(code) + ")");

  detail::buildEdges(mesh);
  return mesh;
}

// The sphere polytope of a level turned by a fixed rotation, so that its face normals and the
// boundaries of its vertices' normal cones do not fall exactly on the axis-aligned directions
// common in robot models (a tie there would make the direct construction fall back).
struct TurnedSphere {
  std::vector<Vec3> vertices;                           // on the unit sphere
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
  std::vector<Vec3> normals;                            // outward unit face normals
  std::vector<std::array<std::uint32_t, 4>> edges;      // u1, u2, triangle holding u1 -> u2, the other
  std::vector<std::vector<std::uint32_t>> adjacent;     // vertices joined to each by an edge
};

const TurnedSphere& turnedSphere(int level) {
  static std::once_flag once;
  static std::vector<TurnedSphere> levels;
  std::call_once(once, [] {
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(0.6180339887498949, Vec3(0.2718281828, 0.5772156649, 0.7071067812).normalized())
            .toRotationMatrix();
    for (int l = 0; l <= 5; ++l) {
      const SpherePolytope& s = spherePolytope(l);
      TurnedSphere q;
      for (const Vec3& v : s.vertices) q.vertices.push_back((turn * v).normalized());
      q.triangles = s.triangles;
      for (std::uint32_t t = 0; t < q.triangles.size(); ++t) {
        const auto& tri = q.triangles[t];
        q.normals.push_back(
            (q.vertices[tri[1]] - q.vertices[tri[0]]).cross(q.vertices[tri[2]] - q.vertices[tri[0]]).normalized());
        for (int k = 0; k < 3; ++k)
          if (tri[k] < tri[(k + 1) % 3])  // each edge once, from the triangle holding it low -> high
            q.edges.push_back({tri[k], tri[(k + 1) % 3], t, s.neighbours[t][k]});
      }
      q.adjacent.resize(q.vertices.size());
      for (const auto& e : q.edges) {
        q.adjacent[e[0]].push_back(e[1]);
        q.adjacent[e[1]].push_back(e[0]);
      }
      levels.push_back(std::move(q));
    }
  });
  return levels.at(static_cast<std::size_t>(std::clamp(level, 0, 5)));
}

// The convex hull of the core points as the direct construction needs it: its vertices, the
// vertices joined to each by a hull edge, and its facets (vertex loops counter-clockwise seen
// from outside, with outward unit normals). A flat set has two facets (both sides), a collinear
// set two vertices and one edge, a single point one vertex. Points within `tol` of a line or
// plane are projected onto it and `inflate` is the largest distance moved.
struct CoreHull {
  std::vector<Vec3> vertices;
  std::vector<std::vector<std::uint32_t>> neighbours;
  std::vector<std::vector<std::uint32_t>> facets;
  std::vector<Vec3> normals;
  double inflate = 0.0;
  int qhull_points = 0;
};

void link(CoreHull& h, std::uint32_t a, std::uint32_t b) {
  auto add = [&](std::uint32_t x, std::uint32_t y) {
    auto& n = h.neighbours[x];
    if (std::find(n.begin(), n.end(), y) == n.end()) n.push_back(y);
  };
  add(a, b);
  add(b, a);
}

std::optional<CoreHull> coreHull(std::span<const Vec3> input, double tol) {
  std::vector<Vec3> pts(input.begin(), input.end());
  std::sort(pts.begin(), pts.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  CoreHull h;
  const Vec3 p0 = pts[0];
  auto farthest = [&](auto&& dist) {
    std::size_t best = 0;
    double d = -1.0;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (const double x = dist(pts[i]); x > d) d = x, best = i;
    return std::pair{best, d};
  };
  const auto [i1, len] = farthest([&](const Vec3& p) { return (p - p0).norm(); });
  if (len <= tol) {  // a single point
    h.vertices = {p0};
    h.neighbours.resize(1);
    h.inflate = len;
    return h;
  }
  const Vec3 e1 = (pts[i1] - p0) / len;
  const auto [i2, off_line] = farthest([&](const Vec3& p) { return (p - p0 - e1 * e1.dot(p - p0)).norm(); });
  if (off_line <= tol) {  // collinear: the segment between the extreme projections
    double lo = 0.0, hi = 0.0;
    for (const Vec3& p : pts) lo = std::min(lo, e1.dot(p - p0)), hi = std::max(hi, e1.dot(p - p0));
    h.vertices = {p0 + lo * e1, p0 + hi * e1};
    h.neighbours.resize(2);
    link(h, 0, 1);
    h.inflate = off_line;
    return h;
  }
  const Vec3 n = e1.cross(pts[i2] - p0).normalized();
  const auto [i3, off_plane] = farthest([&](const Vec3& p) { return std::abs(n.dot(p - p0)); });
  if (off_plane <= tol) {  // flat: the polygon (monotone chain in the plane), seen from both sides
    const Vec3 e2 = n.cross(e1);
    std::vector<std::pair<double, double>> xy;
    for (const Vec3& p : pts) xy.emplace_back(e1.dot(p - p0), e2.dot(p - p0));
    std::sort(xy.begin(), xy.end());
    xy.erase(std::unique(xy.begin(), xy.end()), xy.end());
    auto turn = [](const auto& o, const auto& a, const auto& b) {
      return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
    };
    std::vector<std::pair<double, double>> ring(2 * xy.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < xy.size(); ++i) {
      while (k >= 2 && turn(ring[k - 2], ring[k - 1], xy[i]) <= 0.0) --k;
      ring[k++] = xy[i];
    }
    for (std::size_t i = xy.size() - 1, lower = k + 1; i-- > 0;) {
      while (k >= lower && turn(ring[k - 2], ring[k - 1], xy[i]) <= 0.0) --k;
      ring[k++] = xy[i];
    }
    ring.resize(k - 1);  // counter-clockwise about n (e1 x e2 = n)
    if (ring.size() < 3) return std::nullopt;
    const auto m = static_cast<std::uint32_t>(ring.size());
    h.neighbours.resize(m);
    std::vector<std::uint32_t> up, down;
    for (std::uint32_t i = 0; i < m; ++i) {
      h.vertices.push_back(p0 + ring[i].first * e1 + ring[i].second * e2);
      link(h, i, (i + 1) % m);
      up.push_back(i);
      down.push_back(m - 1 - i);
    }
    h.facets = {up, down};
    h.normals = {n, -n};
    h.inflate = off_plane;
    return h;
  }
  // Solid: qhull on the (few) distinct core points.
  std::vector<double> coords;
  for (const Vec3& p : pts) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  h.qhull_points = static_cast<int>(pts.size());
  const hull::QhullResult res = hull::convexHull3(coords);
  if (res.code != 0 || res.facets.size() < 4) return std::nullopt;
  std::vector<std::int64_t> index(pts.size(), -1);
  auto vertex = [&](int id) {
    if (index[id] < 0) {
      index[id] = static_cast<std::int64_t>(h.vertices.size());
      h.vertices.push_back(pts[id]);
      h.neighbours.emplace_back();
    }
    return static_cast<std::uint32_t>(index[id]);
  };
  for (const hull::QhullFacet& f : res.facets) {
    if (f.vertices.size() != 3) return std::nullopt;
    std::vector<std::uint32_t> loop = {vertex(f.vertices[0]), vertex(f.vertices[1]), vertex(f.vertices[2])};
    const Vec3& a = h.vertices[loop[0]];
    if ((h.vertices[loop[1]] - a).cross(h.vertices[loop[2]] - a).dot(f.normal) < 0.0) std::swap(loop[1], loop[2]);
    for (int k = 0; k < 3; ++k) link(h, loop[k], loop[(k + 1) % 3]);
    h.facets.push_back(std::move(loop));
    h.normals.push_back(f.normal);
  }
  // Every core point must lie (to rounding) under every facet plane.
  double excess = 0.0;
  for (std::size_t f = 0; f < h.facets.size(); ++f) {
    const double offset = h.normals[f].dot(h.vertices[h.facets[f][0]]);
    for (const Vec3& p : pts) excess = std::max(excess, h.normals[f].dot(p) - offset);
  }
  if (excess > tol) return std::nullopt;
  return h;
}

// The Minkowski sum of the core hull P and the circumscribed sphere polytope Q (vertices
// q_j = big_r u_j), built from the overlay of the two normal fans instead of a hull of all
// p_i + q_j. Every face of P + Q is one of:
//  - a spherical patch triangle v + t, for each triangle t of Q, v the vertex of P supporting
//    the normal of t;
//  - a strip parallelogram e + g, for each edge g of Q and each hull edge e = (v, w) of P whose
//    arc of normals crosses g's arc of normals (from one neighbouring triangle's normal to the
//    other's): found by following the support of P along that arc from vertex to vertex;
//  - an offset facet f + q, for each facet f of P, q the vertex of Q supporting its normal.
// Each face's plane has the normal it is built for, and its offset is the support of P plus
// the support of Q (at least big_r / scale) in that normal, so the closed mesh contains
// P + B(big_r / scale) and no vertex is farther than big_r from P. Returns nothing when
// rounding makes the pieces disagree (the caller then takes the hull construction).
std::optional<Mesh> directMesh(const CoreHull& core, const TurnedSphere& q, double big_r) {
  const auto np = static_cast<std::uint32_t>(core.vertices.size());
  const auto nq = static_cast<std::uint32_t>(q.vertices.size());
  const std::size_t nt = q.triangles.size();
  // The vertex of P supporting each triangle's normal, by climbing P's edges from the previous
  // triangle's (a vertex no neighbour beats supports a convex polytope; consecutive triangles
  // of a level are mostly neighbours, so the climb is short).
  std::vector<std::uint32_t> support(nt);
  std::uint32_t v = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    const Vec3& c = q.normals[t];
    double best = c.dot(core.vertices[v]);
    for (bool moved = true; moved;) {
      moved = false;
      for (const std::uint32_t w : core.neighbours[v])
        if (const double d = c.dot(core.vertices[w]); d > best) best = d, v = w, moved = true;
    }
    support[t] = v;
  }
  Mesh mesh;
  std::vector<std::int32_t> id(static_cast<std::size_t>(np) * nq, -1);
  auto vertex = [&](std::uint32_t p, std::uint32_t u) {
    std::int32_t& i = id[static_cast<std::size_t>(p) * nq + u];
    if (i < 0) {
      i = static_cast<std::int32_t>(mesh.vertices.size());
      mesh.vertices.push_back(core.vertices[p] + big_r * q.vertices[u]);
    }
    return static_cast<std::uint32_t>(i);
  };
  auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& n) {
    mesh.triangles.push_back({a, b, c});
    mesh.normals.push_back(n);
  };
  mesh.triangles.reserve(nt + 2 * q.edges.size());
  mesh.normals.reserve(nt + 2 * q.edges.size());
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = q.triangles[t];
    const std::uint32_t v = support[t];
    triangle(vertex(v, tri[0]), vertex(v, tri[1]), vertex(v, tri[2]), q.normals[t]);
  }
  for (const auto& [u1, u2, left, right] : q.edges) {
    // The support of P along d(s) = (1 - s) n_left + s n_right, s from 0 to 1: from the current
    // vertex v, the next is the neighbour w whose advantage d(s)·(w - v) (linear in s) turns
    // positive first.
    // The normal cone of a vertex is convex: when both ends have the same support, the whole
    // arc does and the two patch triangles share the edge.
    if (support[left] == support[right]) continue;
    const Vec3 &cl = q.normals[left], &cr = q.normals[right];
    std::uint32_t v = support[left];
    double s = 0.0;
    for (std::uint32_t steps = 0;; ++steps) {
      std::int64_t next = -1;
      double at = 2.0;
      for (const std::uint32_t w : core.neighbours[v]) {
        const double a = cl.dot(core.vertices[w]) - cl.dot(core.vertices[v]);
        const double b = cr.dot(core.vertices[w]) - cr.dot(core.vertices[v]);
        if (!(b > a)) continue;
        const double sw = std::max(s, a >= 0.0 ? 0.0 : -a / (b - a));
        if (sw <= 1.0 && sw < at) at = sw, next = w;
      }
      if (next < 0) break;
      if (steps > np) return std::nullopt;
      const auto w = static_cast<std::uint32_t>(next);
      const Vec3 n = ((1.0 - at) * q.normals[left] + at * q.normals[right]).normalized();
      const std::uint32_t v2 = vertex(v, u2), v1 = vertex(v, u1), w1 = vertex(w, u1), w2 = vertex(w, u2);
      triangle(v2, v1, w1, n);
      triangle(v2, w1, w2, n);
      v = w;
      s = at;
    }
    if (v != support[right]) return std::nullopt;
  }
  std::uint32_t u = 0;
  for (std::size_t f = 0; f < core.facets.size(); ++f) {
    const Vec3& n = core.normals[f];
    // The vertex of Q supporting n, by climbing Q's edges (a vertex no neighbour beats is the
    // support of a convex polytope), from the previous facet's (neighbouring facets are close).
    double best = n.dot(q.vertices[u]);
    for (bool moved = true; moved;) {
      moved = false;
      for (const std::uint32_t j : q.adjacent[u])
        if (const double d = n.dot(q.vertices[j]); d > best) best = d, u = j, moved = true;
    }
    const auto& loop = core.facets[f];
    for (std::size_t k = 1; k + 1 < loop.size(); ++k)
      triangle(vertex(loop[0], u), vertex(loop[k], u), vertex(loop[k + 1], u), n);
  }
  if (!detail::closeUp(mesh)) return std::nullopt;
  return mesh;
}

}  // namespace

Mesh buildSschMesh(std::span<const Vec3> points, double radius, int level, double min_radius, SschMeshing meshing) {
  if (points.empty()) throw std::invalid_argument("buildSschMesh: no core points");
  if (!allFinite(points) || !std::isfinite(radius) || radius < 0.0 || !(min_radius > 0.0))
    throw std::invalid_argument("buildSschMesh: non-finite point or bad radius");
  if (meshing == SschMeshing::Hull) return hullMesh(points, radius, level, min_radius);
  double extent = 0.0;
  for (const Vec3& p : points) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  // Guard for the float conversion of vertices when drawing (a micrometre at 1 m), as before;
  // sets within 1e-9 (1 + extent) of a point, line or plane are projected onto it.
  const double pad = 1e-6 * (1.0 + extent);
  const std::optional<CoreHull> core = coreHull(points, 1e-9 * (1.0 + extent));
  int qhull_points = 0;
  if (core) {
    qhull_points = core->qhull_points;
    const double big_r = (std::max(radius, min_radius) + pad + core->inflate) * spherePolytope(level).scale;
    if (std::optional<Mesh> mesh = directMesh(*core, turnedSphere(level), big_r)) {
      mesh->level = level;
      mesh->mesh_radius = big_r;
      mesh->hull_input = qhull_points;
      mesh->direct = true;
      return std::move(*mesh);
    }
  }
  Mesh mesh = hullMesh(points, radius, level, min_radius);
  mesh.hull_input += qhull_points;
  return mesh;
}

}  // namespace kccd::render
