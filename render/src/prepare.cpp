#include "kccd/render/prepare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <opencv2/core/utility.hpp>

#include "kccd/distance.hpp"
#include "kccd/render/ssch_outline.hpp"

namespace kccd::render {

const char* toString(Visibility visibility) {
  switch (visibility) {
    case Visibility::Drawn:
      return "drawn";
    case Visibility::FillsView:
      return "contains the camera";
    case Visibility::Empty:
      return "no volume";
    case Visibility::NotFinite:
      return "not finite";
    case Visibility::BehindCamera:
      return "behind the camera";
    case Visibility::BeyondFar:
      return "beyond far plane";
    case Visibility::NoMesh:
      return "no mesh";
  }
  return "?";
}

namespace {

// The silhouette of a convex mesh seen from the camera: the edges between a front and a back
// triangle, each directed as its front triangle runs along it, chained into one loop. Seen from
// a camera in front of every vertex, the front triangles cover exactly the convex polygon this
// loop bounds, so the polygon fills the same pixels with far fewer triangles. Leaves `loop`
// empty when the edges do not chain into one simple loop (near-degenerate views).
void silhouetteLoop(const Mesh& m, const std::vector<char>& front, const std::vector<std::uint32_t>& outline,
                    std::vector<std::uint32_t>& loop) {
  loop.clear();
  const std::size_t n = outline.size() / 2;
  if (n < 3) return;
  // Directed edges from -> to, sorted by `from` for the walk.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> next;
  next.reserve(n);
  for (const auto& e : m.edges) {
    if (front[e[2]] == front[e[3]]) continue;
    const auto& t = m.triangles[front[e[2]] ? e[2] : e[3]];
    const bool forward =
        (t[0] == e[0] && t[1] == e[1]) || (t[1] == e[0] && t[2] == e[1]) || (t[2] == e[0] && t[0] == e[1]);
    next.emplace_back(forward ? e[0] : e[1], forward ? e[1] : e[0]);
  }
  std::sort(next.begin(), next.end());
  for (std::size_t k = 1; k < next.size(); ++k)
    if (next[k].first == next[k - 1].first) return;  // a vertex with two outgoing edges
  const std::uint32_t start = next.front().first;
  std::uint32_t at = start;
  loop.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    loop.push_back(at);
    const auto it = std::lower_bound(next.begin(), next.end(), std::make_pair(at, std::uint32_t{0}));
    if (it == next.end() || it->first != at) {
      loop.clear();
      return;
    }
    at = it->second;
    if (at == start && k + 1 != n) {  // closed early: more than one loop
      loop.clear();
      return;
    }
  }
  if (at != start) loop.clear();
}

// A convex polygon (vertex indices in order) as triangles of about equal aspect: one triangle on
// three vertices a third of the way round each other, and each remaining arc split in the middle.
// The same pixels as a fan, but large triangles cover whole tiles of the rasteriser.
void polygonTriangles(const std::vector<std::uint32_t>& loop, std::vector<std::uint32_t>& out) {
  out.clear();
  const std::size_t n = loop.size();
  if (n < 3) return;
  auto arc = [&](auto&& self, std::size_t a, std::size_t b) -> void {  // vertices a..b (b may be n: vertex 0)
    if (b - a < 2) return;
    const std::size_t m = (a + b) / 2;
    out.insert(out.end(), {loop[a], loop[m], loop[b % n]});
    self(self, a, m);
    self(self, m, b);
  };
  const std::size_t i = n / 3, j = 2 * n / 3;
  out.insert(out.end(), {loop[0], loop[i], loop[j]});
  arc(arc, 0, i);
  arc(arc, i, j);
  arc(arc, j, n);
}

// Distance from the origin to the triangle abc (closest point by the triangle's Voronoi regions).
double originToTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = -a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a.norm();
  const Vec3 bp = -b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (a + d1 / (d1 - d3) * ab).norm();
  const Vec3 cp = -c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (a + d2 / (d2 - d6) * ac).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).norm();
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0.0)) return std::min({a.norm(), b.norm(), c.norm()});
  return (a + (vb / denom) * ab + (vc / denom) * ac).norm();
}

}  // namespace

FramePreparer::FramePreparer(const Projection& colour, const Projection& mask, const RenderOptions& options)
    : colour_(colour),
      mask_(mask),
      options_(options),
      world_to_camera_(colour.camera().worldToCamera()),
      cache_(MeshCache::kDefaultCapacity, options.meshing) {}

PreparedFrame FramePreparer::prepare(std::span<const Volume> volumes, const PrepareNeeds& needs) {
  PreparedFrame prepared;
  std::vector<PreparedVolume>& out = prepared.volumes;
  Frame& frame = prepared.frame;
  const bool outlines = needs.outlines, need_meshes = needs.meshes;
  cache_.nextFrame();
  const std::uint64_t built_before = cache_.built();
  const Camera& cam = colour_.camera();
  const double focal = std::max(cam.camera_matrix(0, 0), cam.camera_matrix(1, 1));
  // Camera pixels per metre across the line of sight at depth 1, at most; and the tessellation's
  // tolerance, finer for a mask drawn finer.
  const double px_per_metre = focal * mask_.obliquity() * mask_.stretch() * mask_.supersample();
  const double tolerance = needs.mask ? options_.tolerance_px / mask_.supersample() : options_.tolerance_px;
  const int max_level = needs.mask ? std::max(options_.max_level, options_.mask_max_level) : options_.max_level;
  out.resize(volumes.size());
  frame.visibility.assign(volumes.size(), Visibility::Empty);
  std::vector<Vec3> cam_points;
  std::vector<MeshRequest> requests;
  std::vector<std::size_t> requested;  // the volume of each request
  const Vec3 origin = Vec3::Zero();
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    const Volume& v = volumes[i];
    PreparedVolume& p = out[i];
    p.index = static_cast<int>(i);
    p.status = v.status;
    p.colour = v.colour[0] >= 0 ? v.colour : statusColour(v.status);
    p.mesh.reset();
    p.vertices.clear();
    p.outline.clear();
    p.fills = false;
    p.silhouette.clear();
    p.fill.clear();
    p.outline_2d.clear();
    p.outline_vertices.clear();
    p.outline_lines.clear();
    p.outline_fill.clear();
    p.surface = false;
    p.label = v.mask_label >= 0 ? std::min(v.mask_label, 255) : static_cast<int>(i) + 1;
    Visibility& visibility = frame.visibility[i];
    if (v.surface) {
      prepareSurface(v, p, visibility);
      if (visibility == Visibility::Drawn) frame.triangles += static_cast<int>(p.mesh->triangles.size());
      continue;
    }
    if (v.points.empty()) continue;
    // Tessellation fine enough that the circumscribed sphere polytope lies at most
    // tolerance_px outside the true surface, as seen from the closest point of the volume.
    const Pose to_camera = world_to_camera_ * v.pose;
    p.rotation = to_camera.linear();
    cam_points.clear();
    double zmin = 1e300, zmax = -1e300;
    Vec3 centre = Vec3::Zero();
    for (const Vec3& w : v.points) {
      cam_points.push_back(to_camera * w);
      zmin = std::min(zmin, cam_points.back().z());
      zmax = std::max(zmax, cam_points.back().z());
      centre += cam_points.back();
    }
    centre /= static_cast<double>(cam_points.size());
    const double r = std::max(v.radius, options_.min_radius);
    double spread = 0.0;
    for (const Vec3& c : cam_points) spread = std::max(spread, (c - centre).norm());
    if (!allFinite(cam_points) || !std::isfinite(v.radius) || !std::isfinite(spread + r) ||
        !std::isfinite(centre.norm())) {
      visibility = Visibility::NotFinite;
      continue;
    }
    p.depth = centre.norm();
    if (zmax + r <= 0.0) {
      visibility = Visibility::BehindCamera;
      continue;
    }
    p.reach = p.depth + spread + r;
    if (p.reach * 1.01 > kMaxDrawDistance) {
      visibility = Visibility::BeyondFar;
      continue;
    }
    zmin -= r;
    // The radius in camera pixels where it is largest: nearest, at the image's most oblique
    // direction, through the lens's largest stretch.
    int level = max_level;
    const double r_px = zmin > 0.0 ? px_per_metre * r / zmin : std::numeric_limits<double>::infinity();
    if (zmin > options_.near)
      for (int l = 1; l < max_level; ++l)
        if ((spherePolytope(l).scale - 1.0) * r_px <= tolerance) {
          level = l;
          break;
        }
    p.mesh_error_px = (spherePolytope(level).scale - 1.0) * r_px;
    // How near the mesh comes to the camera: the volume's distance less the tessellation's
    // outward error. A volume (nearly) containing the camera covers the whole view.
    const DistanceResult d = distance(SschView{cam_points, r}, SschView{std::span<const Vec3>(&origin, 1), 0.0});
    p.clearance = d.status == GjkStatus::InvalidInput ? 0.0 : d.distance - (spherePolytope(level).scale - 1.0) * r;
    if (p.clearance <= 1e-4) {
      p.fills = true;
      visibility = Visibility::FillsView;
      continue;
    }
    p.level = level;
    // The outline straight from the core when the volume lies beyond the near plane; the mesh
    // when a mask or the shaded look needs it, or the outline cannot be had.
    if (outlines &&
        sschOutline(
            cam_points, r,
            OutlineOptions{.focal_px = focal, .tolerance_px = options_.tolerance_px, .min_depth = options_.near},
            p.outline_2d) &&
        p.outline_2d.size() >= 3) {  // (fewer corners: an image thinner than the tolerance, drawn from the mesh)
      visibility = Visibility::Drawn;
      ++frame.outlines;
      if (!need_meshes) continue;
    } else {
      p.outline_2d.clear();
    }
    requests.push_back(MeshRequest{v.points, v.radius, level, options_.min_radius});
    requested.push_back(i);
  }
  // The meshes (those not cached built in parallel), then per volume in parallel: the vertices
  // in camera coordinates, the silhouette edges and their loop.
  const std::vector<MeshCache::Found> meshes = cache_.getAll(requests);
  for (std::size_t k = 0; k < requested.size(); ++k) {
    PreparedVolume& p = out[requested[k]];
    if (!meshes[k].mesh) {  // qhull on extreme coordinates
      if (!p.outlined() || need_meshes) frame.visibility[requested[k]] = Visibility::NoMesh;  // (not in the mask)
      continue;
    }
    p.mesh = meshes[k].mesh;
    frame.visibility[requested[k]] = Visibility::Drawn;
    if (meshes[k].built) frame.hull_input += p.mesh->hull_input;
    frame.max_level = std::max(frame.max_level, p.level);
    frame.triangles += static_cast<int>(p.mesh->triangles.size());
  }
  cv::parallel_for_(cv::Range(0, static_cast<int>(requested.size())), [&](const cv::Range& range) {
    std::vector<char> front;
    for (int k = range.start; k < range.end; ++k) {
      PreparedVolume& p = out[requested[static_cast<std::size_t>(k)]];
      if (!p.mesh) continue;
      const Mesh& m = *p.mesh;
      const Pose to_camera = world_to_camera_ * volumes[static_cast<std::size_t>(p.index)].pose;
      p.vertices.resize(m.vertices.size() * 3);
      for (std::size_t j = 0; j < m.vertices.size(); ++j) {
        const Vec3 c = to_camera * m.vertices[j];
        p.vertices[3 * j] = static_cast<float>(c.x());
        p.vertices[3 * j + 1] = static_cast<float>(c.y());
        p.vertices[3 * j + 2] = static_cast<float>(c.z());
      }
      if (p.outlined()) continue;  // drawn from its outline: the mesh is for the labels only
      // Silhouette edges: one neighbouring triangle faces the camera (at the origin), the other not.
      front.resize(m.triangles.size());
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const Vec3 n = to_camera.linear() * m.normals[t];
        const Vec3 a = to_camera * m.vertices[m.triangles[t][0]];
        front[t] = n.dot(a) < 0.0;
      }
      for (const auto& e : m.edges)
        if (front[e[2]] != front[e[3]]) p.outline.insert(p.outline.end(), {e[0], e[1]});
      silhouetteLoop(m, front, p.outline, p.silhouette);
      polygonTriangles(p.silhouette, p.fill);
    }
  });
  frame.meshes_built = static_cast<int>(cache_.built() - built_before);
  // Clipping planes that clip no drawn mesh: the near plane closer than the nearest mesh
  // anywhere in the view frustum, the far plane beyond the farthest one.
  frame.near = options_.near;
  frame.far = options_.far;
  for (const Projection* pr : {&colour_, &mask_}) {
    const Pinhole& ph = pr->pinhole();
    const double tx = std::max(ph.cx + 0.5, ph.width - ph.cx - 0.5) / ph.fx;
    const double ty = std::max(ph.cy + 0.5, ph.height - ph.cy - 0.5) / ph.fy;
    const double corner = std::sqrt(1.0 + tx * tx + ty * ty);  // frustum corner at unit depth
    for (const PreparedVolume& p : out)
      if (p.drawn()) frame.near = std::min(frame.near, 0.5 * p.clearance / corner);
  }
  for (const PreparedVolume& p : out)
    if (p.drawn()) frame.far = std::max(frame.far, 1.01 * p.reach);
  // Outlines on a plane between the clipping planes (drawn without depth test, so only their
  // rays matter).
  const double z = std::sqrt(frame.near * frame.far);
  for (PreparedVolume& p : out) {
    if (!p.outlined()) continue;
    const std::size_t n = p.outline_2d.size();
    p.outline_vertices.resize(3 * n);
    for (std::size_t k = 0; k < n; ++k) {
      p.outline_vertices[3 * k] = static_cast<float>(p.outline_2d[k].x() * z);
      p.outline_vertices[3 * k + 1] = static_cast<float>(p.outline_2d[k].y() * z);
      p.outline_vertices[3 * k + 2] = static_cast<float>(z);
    }
    std::vector<std::uint32_t> loop(n);
    for (std::size_t k = 0; k < n; ++k) {
      loop[k] = static_cast<std::uint32_t>(k);
      p.outline_lines.insert(p.outline_lines.end(),
                             {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>((k + 1) % n)});
    }
    polygonTriangles(loop, p.outline_fill);
    frame.triangles += static_cast<int>(p.outline_fill.size() / 3);
  }
  return prepared;
}

// A surface (appearance mesh): its vertices in camera coordinates and how near it comes to the
// camera (for the near plane).
void FramePreparer::prepareSurface(const Volume& v, PreparedVolume& p, Visibility& visibility) const {
  const Mesh& m = *v.surface;
  if (m.triangles.empty()) return;  // Empty
  const Pose to_camera = world_to_camera_ * v.pose;
  p.rotation = to_camera.linear();
  p.vertices.resize(m.vertices.size() * 3);
  Vec3 centre = Vec3::Zero();
  double zmax = -1e300, nearest = 1e300, farthest = 0.0;
  for (std::size_t k = 0; k < m.vertices.size(); ++k) {
    const Vec3 c = to_camera * m.vertices[k];
    if (!c.allFinite()) {
      visibility = Visibility::NotFinite;
      return;
    }
    p.vertices[3 * k] = static_cast<float>(c.x());
    p.vertices[3 * k + 1] = static_cast<float>(c.y());
    p.vertices[3 * k + 2] = static_cast<float>(c.z());
    centre += c;
    zmax = std::max(zmax, c.z());
    nearest = std::min(nearest, c.norm());
    farthest = std::max(farthest, c.norm());
  }
  // The nearest point of the surface: a triangle comes no nearer than its nearest vertex less
  // its longest edge; only triangles that could beat the best distance so far are measured.
  double clearance = nearest;
  auto camera_point = [&](std::uint32_t k) {
    return Vec3(p.vertices[3 * k], p.vertices[3 * k + 1], p.vertices[3 * k + 2]);
  };
  for (const auto& t : m.triangles) {
    const Vec3 a = camera_point(t[0]), b = camera_point(t[1]), c = camera_point(t[2]);
    const double edge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (std::min({a.norm(), b.norm(), c.norm()}) - edge < clearance)
      clearance = std::min(clearance, originToTriangle(a, b, c));
  }
  if (zmax <= 0.0) {
    visibility = Visibility::BehindCamera;
    return;
  }
  if (farthest * 1.01 > kMaxDrawDistance) {
    visibility = Visibility::BeyondFar;
    return;
  }
  p.depth = (centre / static_cast<double>(m.vertices.size())).norm();
  p.reach = farthest;
  p.clearance = std::max(0.999 * clearance, 1e-4);  // appearance only: a mesh reaching the camera is clipped
  p.mesh = v.surface;
  p.surface = true;
  visibility = Visibility::Drawn;
}

}  // namespace kccd::render
