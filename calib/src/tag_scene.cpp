// Synthetic AprilTag frames by ray casting (see tag_scene.hpp).
//
// Every pixel corner (OpenCV convention: pixel (i, j) covers i-0.5..i+0.5, j-0.5..j+0.5) gets its
// ray by inverting the lens model with Newton's method (continued along the row from the previous
// corner), cached per intrinsics. A ray is intersected with every front-facing tag plane; the
// nearest hit gives a (tag, cell) key. A pixel whose four corners share one key and that no tag
// outline crosses lies inside one cell (cells are convex) and takes its value; every other pixel
// is the mean of supersample^2 rays, each solved exactly at its sub-pixel position. Surfaces
// (floor, walls) are cast like tags, their checker tiles taking the place of the tag cells.
#include "kccd/calib/tag_scene.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/tag36h11.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace kccd::calib {
namespace {

using calib::Camera;
using calib::TagLayout;

// The OpenCV lens model: normalised (x, y) -> pixel, coefficients k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 tx ty.
struct Lens {
  double fx = 1, fy = 1, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0, k4 = 0, k5 = 0, k6 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0;
  bool tilted = false;
  cv::Matx33d tilt = cv::Matx33d::eye();

  explicit Lens(const Camera& c) {
    fx = c.camera_matrix(0, 0), fy = c.camera_matrix(1, 1), cx = c.camera_matrix(0, 2), cy = c.camera_matrix(1, 2);
    double d[14] = {};
    for (std::size_t i = 0; i < std::min<std::size_t>(14, c.distortion.size()); ++i) d[i] = c.distortion[i];
    k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4], k4 = d[5], k5 = d[6], k6 = d[7];
    s1 = d[8], s2 = d[9], s3 = d[10], s4 = d[11];
    if (d[12] != 0.0 || d[13] != 0.0) {
      // The sensor tilt of OpenCV's model: rotation about x by tx then about y by ty, projected back
      // onto the z = 1 plane along the tilted axis.
      const double ctx = std::cos(d[12]), stx = std::sin(d[12]), cty = std::cos(d[13]), sty = std::sin(d[13]);
      const cv::Matx33d rx(1, 0, 0, 0, ctx, stx, 0, -stx, ctx);
      const cv::Matx33d ry(cty, 0, -sty, 0, 1, 0, sty, 0, cty);
      const cv::Matx33d rxy = ry * rx;
      const cv::Matx33d proj(rxy(2, 2), 0, -rxy(0, 2), 0, rxy(2, 2), -rxy(1, 2), 0, 0, 1);
      tilt = proj * rxy;
      tilted = true;
    }
  }

  cv::Vec2d distort(double x, double y) const {
    const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
    const double radial = (1 + k1 * r2 + k2 * r4 + k3 * r6) / (1 + k4 * r2 + k5 * r4 + k6 * r6);
    double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + s1 * r2 + s2 * r4;
    double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + s3 * r2 + s4 * r4;
    if (tilted) {
      const cv::Vec3d v = tilt * cv::Vec3d(xd, yd, 1.0);
      const double inv = v[2] != 0.0 ? 1.0 / v[2] : 1.0;
      xd = v[0] * inv, yd = v[1] * inv;
    }
    return {fx * xd + cx, fy * yd + cy};
  }

  double jacobianDet(double x, double y) const {
    const double h = 1e-7 * std::max(1.0, std::abs(x) + std::abs(y));
    const cv::Vec2d f = distort(x, y), fxh = distort(x + h, y), fyh = distort(x, y + h);
    return (fxh[0] - f[0]) * (fyh[1] - f[1]) - (fyh[0] - f[0]) * (fxh[1] - f[1]);
  }

  // Newton's method from (x, y) for the normalised point that distorts to pixel (u, v); true when
  // it lands within `tol` px with a non-folding (positive determinant) Jacobian.
  bool undistort(double u, double v, double& x, double& y, int max_iter = 30, double tol = 1e-8,
                 bool check_fold = true) const {
    for (int it = 0; it <= max_iter; ++it) {
      const cv::Vec2d f = distort(x, y);
      const double eu = f[0] - u, ev = f[1] - v;
      if (!std::isfinite(eu) || !std::isfinite(ev)) return false;
      if (std::abs(eu) < tol && std::abs(ev) < tol) return it > 0 || !check_fold || jacobianDet(x, y) > 0;
      if (it == max_iter) break;
      const double h = 1e-7 * std::max(1.0, std::abs(x) + std::abs(y));
      const cv::Vec2d fxh = distort(x + h, y), fyh = distort(x, y + h);
      const double a = (fxh[0] - f[0]) / h, c = (fxh[1] - f[1]) / h, b = (fyh[0] - f[0]) / h, d = (fyh[1] - f[1]) / h;
      const double det = a * d - b * c;
      if (!(det > 0)) return false;
      double dx = (d * eu - b * ev) / det, dy = (a * ev - c * eu) / det;
      // Damping: never move more than a quarter of the distance from the axis (plus a little) at once.
      const double lim = 0.25 * std::sqrt(x * x + y * y) + 0.05, len = std::sqrt(dx * dx + dy * dy);
      if (len > lim) dx *= lim / len, dy *= lim / len;
      x -= dx, y -= dy;
    }
    return false;
  }
};

// The rays of every pixel corner of a camera (intrinsics only).
struct RayGrid {
  int width = 0, height = 0;
  cv::Matx33d k;
  std::vector<double> distortion;
  std::vector<cv::Vec2d> ray;  // (width + 1) x (height + 1), corner (i - 0.5, j - 0.5) at j * (width + 1) + i
  std::vector<unsigned char> valid;
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;  // the field the inversion is trusted in (normalised)

  bool sameIntrinsics(const Camera& c) const {
    return width == c.width && height == c.height && k == c.camera_matrix && distortion == c.distortion;
  }
};

std::shared_ptr<const RayGrid> buildRayGrid(const Camera& camera) {
  auto grid = std::make_shared<RayGrid>();
  grid->width = camera.width, grid->height = camera.height, grid->k = camera.camera_matrix,
  grid->distortion = camera.distortion;
  const Lens lens(camera);
  const int w1 = camera.width + 1, h1 = camera.height + 1;
  // As calib::undistortPixels: at most one image size of extra field beyond the image on each side.
  grid->x_lo = -(lens.cx + 0.5) / lens.fx - camera.width / lens.fx;
  grid->x_hi = (camera.width - lens.cx - 0.5) / lens.fx + camera.width / lens.fx;
  grid->y_lo = -(lens.cy + 0.5) / lens.fy - camera.height / lens.fy;
  grid->y_hi = (camera.height - lens.cy - 0.5) / lens.fy + camera.height / lens.fy;
  grid->ray.assign(static_cast<std::size_t>(w1) * h1, cv::Vec2d(0, 0));
  grid->valid.assign(static_cast<std::size_t>(w1) * h1, 0);

  // Start of every row: OpenCV's iterative inverse as the first guess.
  cv::Mat first(h1, 1, CV_64FC2), first_n;
  for (int j = 0; j < h1; ++j) first.at<cv::Vec2d>(j) = cv::Vec2d(-0.5, j - 0.5);
  cv::undistortPoints(first, first_n, camera.camera_matrix, camera.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  RayGrid& g = *grid;
  const auto inField = [&g](double x, double y) { return x >= g.x_lo && x <= g.x_hi && y >= g.y_lo && y <= g.y_hi; };
  cv::parallel_for_(cv::Range(0, h1), [&](const cv::Range& rows) {
    for (int j = rows.start; j < rows.end; ++j) {
      const double v = j - 0.5;
      double px = first_n.at<cv::Vec2d>(j)[0], py = first_n.at<cv::Vec2d>(j)[1];
      bool have_prev = false;
      double ppx = 0, ppy = 0;  // the corner before the previous one (for extrapolation)
      for (int i = 0; i < w1; ++i) {
        const double u = i - 0.5;
        double x = px, y = py;
        if (have_prev) x = 2 * px - ppx, y = 2 * py - ppy;
        bool ok = lens.undistort(u, v, x, y);
        if (!ok) {  // restart from the pinhole guess
          x = (u - lens.cx) / lens.fx, y = (v - lens.cy) / lens.fy;
          ok = lens.undistort(u, v, x, y, 100);
        }
        ok = ok && inField(x, y);
        const std::size_t at = static_cast<std::size_t>(j) * w1 + i;
        g.valid[at] = ok ? 1 : 0;
        if (ok) {
          g.ray[at] = cv::Vec2d(x, y);
          if (i > 0 && g.valid[at - 1])
            ppx = px, ppy = py, have_prev = true;
          else
            have_prev = false;
          px = x, py = y;
        } else {
          have_prev = false;
        }
      }
    }
  });
  return grid;
}

// One cache entry: tests render many frames through one camera's intrinsics.
std::shared_ptr<const RayGrid> rayGrid(const Camera& camera) {
  static std::mutex mutex;
  static std::shared_ptr<const RayGrid> cached;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (cached && cached->sameIntrinsics(camera)) return cached;
  }
  std::shared_ptr<const RayGrid> grid = buildRayGrid(camera);
  const std::lock_guard<std::mutex> lock(mutex);
  cached = grid;
  return grid;
}

// A tag in the camera frame, ready for ray intersection.
struct PlacedTag {
  cv::Vec3d origin, ex, ey, n;  // centre and axes in the camera frame
  double n_o = 0, ex_o = 0, ey_o = 0;
  double inv_cell = 0;           // cells per metre
  double half = 5;               // half the bitmap's width in cells
  int cells = 10;                // bitmap width in cells
  std::vector<cv::Vec3f> value;  // cells x cells colours, row 0 at the top of the printed tag (tag +y)
  // Surfaces: a rectangle of half extents half_x, half_y (metres) with checker tiles.
  bool surface = false;
  double half_x = 0, half_y = 0, inv_tile = 0;
  cv::Vec3f colour, tile_colour;
  std::array<cv::Vec3d, 4> outline;  // the bitmap's outer corners in the camera frame
  // Pixel box holding the tag's whole image (every pixel when its outline leaves the trusted field).
  double u_lo = -1e300, u_hi = 1e300, v_lo = -1e300, v_hi = 1e300;
};

constexpr int kBackground = -1;
constexpr int kInvalid = -2;

struct Hit {
  int key = kBackground;  // tag * 1024 + cell, or kBackground
  cv::Vec3f value;
};

// The light in the camera frame.
struct Light {
  bool on = false;
  cv::Vec3d position;
  double ambient = 1, diffuse = 0, reference2 = 1;
};

// The nearest front-facing tag cell or surface tile on the ray (x, y, 1) of pixel position (u, v).
inline Hit castRay(const std::vector<PlacedTag>& tags, const Light& light, double u, double v, double x, double y) {
  Hit hit;
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_t = 0;
  for (std::size_t t = 0; t < tags.size(); ++t) {
    const PlacedTag& p = tags[t];
    if (u < p.u_lo || u > p.u_hi || v < p.v_lo || v > p.v_hi) continue;
    const double nd = p.n[0] * x + p.n[1] * y + p.n[2];
    if (!(nd < 0)) continue;          // parallel to the plane or reaching its back
    const double depth = p.n_o / nd;  // n_o < 0 for a front-facing tag: depth > 0
    if (!(depth < best)) continue;
    const double a = depth * (p.ex[0] * x + p.ex[1] * y + p.ex[2]) - p.ex_o;
    const double b = depth * (p.ey[0] * x + p.ey[1] * y + p.ey[2]) - p.ey_o;
    if (p.surface) {
      if (!(std::abs(a) <= p.half_x && std::abs(b) <= p.half_y)) continue;
      best = depth;
      best_t = t;
      if (p.inv_tile > 0) {
        const long ia = static_cast<long>(std::floor(a * p.inv_tile)),
                   ib = static_cast<long>(std::floor(b * p.inv_tile));
        const bool odd = ((ia + ib) & 1) != 0;
        hit.key = static_cast<int>(t) * 1024 + static_cast<int>(((ia & 31) << 5) | (ib & 31));
        hit.value = odd ? p.tile_colour : p.colour;
      } else {
        hit.key = static_cast<int>(t) * 1024;
        hit.value = p.colour;
      }
      continue;
    }
    const double gx = a * p.inv_cell + p.half, gy = p.half - b * p.inv_cell;
    if (!(gx >= 0 && gx < p.cells && gy >= 0 && gy < p.cells)) continue;
    const int col = static_cast<int>(gx), row = static_cast<int>(gy);
    best = depth;
    best_t = t;
    hit.key = static_cast<int>(t) * 1024 + row * p.cells + col;
    hit.value = p.value[static_cast<std::size_t>(row * p.cells + col)];
  }
  if (light.on && hit.key != kBackground) {
    const PlacedTag& p = tags[best_t];
    const cv::Vec3d point(best * x, best * y, best);
    const cv::Vec3d to_light = light.position - point;
    const double d2 = to_light.dot(to_light);
    const double cosine = std::max(0.0, -p.n.dot(to_light)) / std::sqrt(d2);  // n points away from the camera side
    const double shade = light.ambient + light.diffuse * cosine * light.reference2 / d2;
    hit.value *= static_cast<float>(shade);
  }
  return hit;
}

cv::Matx33d rotation(const cv::Vec3d& rvec) {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  return r;
}

std::vector<PlacedTag> placeTags(const Camera& camera, const TagLayout& layout, const TagSceneOptions& o) {
  const std::unique_ptr<apriltag_family_t, void (*)(apriltag_family_t*)> family(tag36h11_create(), tag36h11_destroy);
  if (!family) throw std::bad_alloc();
  const cv::Matx33d r_cw = rotation(camera.rvec);
  std::vector<PlacedTag> out;
  for (const calib::Tag& tag : layout.tags) {
    if (tag.id < 0 || static_cast<std::uint32_t>(tag.id) >= family->ncodes)
      throw std::invalid_argument("renderTagScene: tag id " + std::to_string(tag.id) + " is not in tag36h11");
    if (!(tag.size > 0) || !std::isfinite(tag.size))
      throw std::invalid_argument("renderTagScene: tag " + std::to_string(tag.id) + " has no positive size");
    const Pose pose = tag.pose();
    cv::Matx33d r_wt;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r_wt(i, j) = pose.linear()(i, j);
    const cv::Vec3d t_wt(pose.translation().x(), pose.translation().y(), pose.translation().z());
    const cv::Matx33d r_ct = r_cw * r_wt;
    PlacedTag p;
    p.origin = r_cw * t_wt + camera.tvec;
    p.ex = cv::Vec3d(r_ct(0, 0), r_ct(1, 0), r_ct(2, 0));
    p.ey = cv::Vec3d(r_ct(0, 1), r_ct(1, 1), r_ct(2, 1));
    p.n = cv::Vec3d(r_ct(0, 2), r_ct(1, 2), r_ct(2, 2));
    p.n_o = p.n.dot(p.origin);
    if (!(p.n_o < 0)) continue;  // the camera is behind (or in) the tag's plane: its back is not drawn
    p.ex_o = p.ex.dot(p.origin);
    p.ey_o = p.ey.dot(p.origin);
    image_u8_t* bitmap = apriltag_to_image(family.get(), static_cast<std::uint32_t>(tag.id));
    if (!bitmap) throw std::bad_alloc();
    p.cells = bitmap->width;
    p.half = 0.5 * p.cells;
    // The black square (edge `size`) is width_at_border cells: one white cell around it for tag36h11.
    p.inv_cell = family->width_at_border / tag.size;
    p.value.resize(static_cast<std::size_t>(p.cells) * p.cells);
    for (int row = 0; row < p.cells; ++row)
      for (int col = 0; col < p.cells; ++col)
        p.value[static_cast<std::size_t>(row * p.cells + col)] =
            cv::Vec3f::all(static_cast<float>(bitmap->buf[row * bitmap->stride + col] >= 128 ? o.white : o.black));
    image_u8_destroy(bitmap);
    const double e = p.half / p.inv_cell;  // half the bitmap's edge, metres
    const double corner[4][2] = {{-e, -e}, {e, -e}, {e, e}, {-e, e}};
    for (int c = 0; c < 4; ++c)
      p.outline[static_cast<std::size_t>(c)] = p.origin + corner[c][0] * p.ex + corner[c][1] * p.ey;
    out.push_back(std::move(p));
  }
  for (const SceneSurface& s : o.surfaces) {
    if (!(s.half_x > 0 && s.half_y > 0 && std::isfinite(s.half_x) && std::isfinite(s.half_y) && s.tile >= 0 &&
          std::isfinite(s.tile)))
      throw std::invalid_argument("renderTagScene: a surface needs positive finite extents and a tile size >= 0");
    PlacedTag p;
    p.surface = true;
    cv::Matx33d r_ws;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r_ws(i, j) = s.pose.linear()(i, j);
    const cv::Vec3d t_ws(s.pose.translation().x(), s.pose.translation().y(), s.pose.translation().z());
    const cv::Matx33d r_cs = r_cw * r_ws;
    p.origin = r_cw * t_ws + camera.tvec;
    p.ex = cv::Vec3d(r_cs(0, 0), r_cs(1, 0), r_cs(2, 0));
    p.ey = cv::Vec3d(r_cs(0, 1), r_cs(1, 1), r_cs(2, 1));
    p.n = cv::Vec3d(r_cs(0, 2), r_cs(1, 2), r_cs(2, 2));
    p.n_o = p.n.dot(p.origin);
    if (p.n_o == 0) continue;                   // seen edge-on
    if (p.n_o > 0) p.n = -p.n, p.n_o = -p.n_o;  // seen from its back: drawn all the same
    p.ex_o = p.ex.dot(p.origin);
    p.ey_o = p.ey.dot(p.origin);
    p.half_x = s.half_x, p.half_y = s.half_y;
    p.inv_tile = s.tile > 0 ? 1.0 / s.tile : 0.0;
    p.colour =
        cv::Vec3f(static_cast<float>(s.colour[0]), static_cast<float>(s.colour[1]), static_cast<float>(s.colour[2]));
    p.tile_colour = cv::Vec3f(static_cast<float>(s.tile_colour[0]), static_cast<float>(s.tile_colour[1]),
                              static_cast<float>(s.tile_colour[2]));
    out.push_back(std::move(p));
  }
  return out;
}

// Marks (in `mixed`, width x height) every pixel that a tag outline edge may cross: the 3 x 3
// pixels around samples at most 0.25 px apart along the edge's image. The edge's pinhole image is
// the straight segment between its projected ends (clipped to z > 0 and to the trusted field).
// Sets each tag's pixel box from the same samples when no edge needed clipping.
void markOutlines(std::vector<PlacedTag>& tags, const RayGrid& g, const Lens& lens, std::vector<unsigned char>& mixed) {
  const int w = g.width, h = g.height;
  const double eps = 1e-6;
  // Largest pixels-per-normalised-unit of the lens over the field, bounded from the corner grid.
  double scale = std::max(lens.fx, lens.fy);
  for (int j = 0; j < h; j += std::max(1, h / 32))
    for (int i = 0; i < w; i += std::max(1, w / 32)) {
      const std::size_t a = static_cast<std::size_t>(j) * (w + 1) + i;
      if (!g.valid[a] || !g.valid[a + 1] || !g.valid[a + w + 1]) continue;
      const double dx = cv::norm(g.ray[a + 1] - g.ray[a]), dy = cv::norm(g.ray[a + w + 1] - g.ray[a]);
      if (dx > 0) scale = std::max(scale, 1.0 / dx);
      if (dy > 0) scale = std::max(scale, 1.0 / dy);
    }
  scale *= 2;  // margin for the parts of the field between grid samples and beyond the image
  for (PlacedTag& p : tags) {
    if (p.surface) continue;  // large: their edges are found by the corner keys
    bool whole = true;        // every edge in front of the camera and in the trusted field
    double u_lo = 1e300, u_hi = -1e300, v_lo = 1e300, v_hi = -1e300;
    for (std::size_t c = 0; c < 4; ++c) {
      cv::Vec3d a = p.outline[c], b = p.outline[(c + 1) % 4];
      if (a[2] < eps || b[2] < eps) whole = false;
      if (a[2] < eps && b[2] < eps) continue;
      if (a[2] < eps) std::swap(a, b);
      if (b[2] < eps) b = a + (b - a) * ((a[2] - eps) / (a[2] - b[2]));
      // Normalised segment, clipped to the trusted field (Liang-Barsky).
      double x0 = a[0] / a[2], y0 = a[1] / a[2], x1 = b[0] / b[2], y1 = b[1] / b[2];
      double t0 = 0, t1 = 1;
      const double dx = x1 - x0, dy = y1 - y0;
      const double pq[4][2] = {{-dx, x0 - g.x_lo}, {dx, g.x_hi - x0}, {-dy, y0 - g.y_lo}, {dy, g.y_hi - y0}};
      bool visible = true;
      for (const auto& [pp, qq] : pq) {
        if (pp == 0) {
          if (qq < 0) visible = false;
          continue;
        }
        const double r = qq / pp;
        if (pp < 0)
          t0 = std::max(t0, r);
        else
          t1 = std::min(t1, r);
      }
      if (t0 > 0 || t1 < 1) whole = false;
      if (!visible || t0 > t1) {
        whole = false;
        continue;
      }
      const double len = std::hypot(dx, dy) * (t1 - t0);
      const double steps = std::ceil(len * scale / 0.25) + 1;
      if (!(steps >= 1)) continue;
      const long n = static_cast<long>(std::min(4194304.0, steps));
      for (long s = 0; s <= n; ++s) {
        const double t = t0 + (t1 - t0) * static_cast<double>(s) / static_cast<double>(n);
        const cv::Vec2d q = lens.distort(x0 + t * dx, y0 + t * dy);
        u_lo = std::min(u_lo, q[0]), u_hi = std::max(u_hi, q[0]), v_lo = std::min(v_lo, q[1]),
        v_hi = std::max(v_hi, q[1]);
        if (!(std::abs(q[0]) < 1e9 && std::abs(q[1]) < 1e9)) continue;
        const long ui = std::lround(q[0]), vi = std::lround(q[1]);
        for (long vv = vi - 1; vv <= vi + 1; ++vv)
          for (long uu = ui - 1; uu <= ui + 1; ++uu)
            if (uu >= 0 && vv >= 0 && uu < w && vv < h) mixed[static_cast<std::size_t>(vv) * w + uu] = 1;
      }
    }
    if (whole) p.u_lo = u_lo - 2, p.u_hi = u_hi + 2, p.v_lo = v_lo - 2, p.v_hi = v_hi + 2;
  }
}

cv::Mat backgroundImage(const Camera& camera, const TagSceneOptions& o) {
  cv::Mat bg(camera.height, camera.width, CV_32F, cv::Scalar(o.background));
  if (!o.texture) return bg;
  cv::RNG rng(o.seed * 0x9E3779B97F4A7C15ull + 17);
  // Smooth random grey variation, then clutter: filled shapes and lines of random grey.
  cv::Mat coarse(camera.height / 24 + 2, camera.width / 24 + 2, CV_32F), smooth;
  rng.fill(coarse, cv::RNG::UNIFORM, -1.0, 1.0);
  cv::resize(coarse, smooth, bg.size(), 0, 0, cv::INTER_CUBIC);
  bg += 35.0 * smooth;
  cv::Mat clutter(bg.size(), CV_8U);
  bg.convertTo(clutter, CV_8U);
  const int shapes = 12 + static_cast<int>(camera.width * static_cast<double>(camera.height) / 40000.0);
  for (int s = 0; s < shapes; ++s) {
    const cv::Point c(rng.uniform(0, camera.width), rng.uniform(0, camera.height));
    const int size = rng.uniform(4, std::max(5, std::min(camera.width, camera.height) / 8));
    const cv::Scalar grey(rng.uniform(40, 250));
    switch (rng.uniform(0, 4)) {
      case 0:
        cv::rectangle(clutter, c, c + cv::Point(size, rng.uniform(2, size + 2)), grey, cv::FILLED, cv::LINE_AA);
        break;
      case 1:
        cv::circle(clutter, c, size / 2, grey, cv::FILLED, cv::LINE_AA);
        break;
      case 2:
        cv::line(clutter, c, c + cv::Point(rng.uniform(-3 * size, 3 * size), rng.uniform(-3 * size, 3 * size)), grey,
                 rng.uniform(1, 5), cv::LINE_AA);
        break;
      default:
        cv::rectangle(clutter, c, c + cv::Point(size, size), grey, rng.uniform(1, 4), cv::LINE_AA);
        break;
    }
  }
  clutter.convertTo(bg, CV_32F);
  return bg;
}

}  // namespace

cv::Point2d distortNormalised(const calib::Camera& camera, const cv::Point2d& normalised) {
  const cv::Vec2d p = Lens(camera).distort(normalised.x, normalised.y);
  return {p[0], p[1]};
}

std::vector<std::array<cv::Point2d, 4>> projectTagCorners(const calib::Camera& camera, const calib::TagLayout& layout) {
  std::vector<std::array<cv::Point2d, 4>> out;
  for (const calib::Tag& tag : layout.tags) {
    const auto c = tag.corners();
    std::vector<cv::Point2d> px;
    cv::projectPoints(std::vector<cv::Point3d>(c.begin(), c.end()), camera.rvec, camera.tvec, camera.camera_matrix,
                      camera.distortion, px);
    out.push_back({px[0], px[1], px[2], px[3]});
  }
  return out;
}

namespace {

// The scene as 3-channel floats, blurred and with noise.
cv::Mat renderScene(const calib::Camera& camera, const calib::TagLayout& layout, const TagSceneOptions& o) {
  camera.validate("renderTagScene camera");
  if (o.supersample < 1 || o.supersample > 16 || !(o.blur_sigma >= 0) || !(o.noise_sigma >= 0) ||
      !std::isfinite(o.blur_sigma) || !std::isfinite(o.noise_sigma))
    throw std::invalid_argument("renderTagScene: supersample must be in 1..16, blur and noise sigmas finite and >= 0");
  const std::shared_ptr<const RayGrid> grid_ptr = rayGrid(camera);
  const RayGrid& g = *grid_ptr;
  const Lens lens(camera);
  std::vector<PlacedTag> tags = placeTags(camera, layout, o);
  cv::Mat bg;
  {
    const cv::Mat grey = backgroundImage(camera, o);
    cv::merge(std::vector<cv::Mat>{grey, grey, grey}, bg);
  }
  Light light;
  if (o.light.on) {
    const Pose w2c = camera.worldToCamera();
    const Vec3 l = w2c * o.light.position;
    light.on = true;
    light.position = cv::Vec3d(l.x(), l.y(), l.z());
    light.ambient = o.light.ambient;
    light.diffuse = o.light.diffuse;
    light.reference2 = o.light.reference * o.light.reference;
  }
  const int w = camera.width, h = camera.height, w1 = w + 1, h1 = h + 1;

  std::vector<unsigned char> mixed(static_cast<std::size_t>(w) * h, 0);
  markOutlines(tags, g, lens, mixed);

  // Keys of the corner rays.
  std::vector<int> key(static_cast<std::size_t>(w1) * h1, kBackground);
  std::vector<cv::Vec3f> corner_value(key.size());
  cv::parallel_for_(cv::Range(0, h1), [&](const cv::Range& rows) {
    for (int j = rows.start; j < rows.end; ++j)
      for (int i = 0; i < w1; ++i) {
        const std::size_t at = static_cast<std::size_t>(j) * w1 + i;
        if (!g.valid[at]) {
          key[at] = kInvalid;
          continue;
        }
        const Hit hit = castRay(tags, light, i - 0.5, j - 0.5, g.ray[at][0], g.ray[at][1]);
        key[at] = hit.key;
        corner_value[at] = hit.value;
      }
  });
  cv::Mat image(h, w, CV_32FC3);
  const int s = o.supersample;
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int j = rows.start; j < rows.end; ++j) {
      cv::Vec3f* out = image.ptr<cv::Vec3f>(j);
      const cv::Vec3f* back = bg.ptr<cv::Vec3f>(j);
      for (int i = 0; i < w; ++i) {
        const std::size_t a = static_cast<std::size_t>(j) * w1 + i, b = a + 1, c = a + w1, d = c + 1;
        const int k = key[a];
        if (k == kInvalid || key[b] == kInvalid || key[c] == kInvalid || key[d] == kInvalid) {
          out[i] = back[i];  // the lens model cannot be inverted here
          continue;
        }
        if (k == key[b] && k == key[c] && k == key[d] && !mixed[static_cast<std::size_t>(j) * w + i]) {
          out[i] = k == kBackground ? back[i] : corner_value[a];
          continue;
        }
        // Sub-pixel rays: bilinear start from the corner rays, then solved exactly.
        cv::Vec3d sum(0, 0, 0);
        for (int sy = 0; sy < s; ++sy)
          for (int sx = 0; sx < s; ++sx) {
            // Stratified in s x s cells and in s^2 columns and rows ("n-rooks"): an edge along a
            // pixel axis is resolved to 1 / s^2 of a pixel, not 1 / s.
            const double fu = (sx + (sy + 0.5) / s) / s, fv = (sy + (sx + 0.5) / s) / s;
            const cv::Vec2d top = g.ray[a] * (1 - fu) + g.ray[b] * fu, bottom = g.ray[c] * (1 - fu) + g.ray[d] * fu;
            const cv::Vec2d guess = top * (1 - fv) + bottom * fv;
            double x = guess[0], y = guess[1];
            const double su = i - 0.5 + fu, sv = j - 0.5 + fv;
            if (!lens.undistort(su, sv, x, y, 10, 1e-8, false)) x = guess[0], y = guess[1];
            const Hit hit = castRay(tags, light, su, sv, x, y);
            const cv::Vec3f& add = hit.key == kBackground ? back[i] : hit.value;
            sum += cv::Vec3d(add[0], add[1], add[2]);
          }
        sum *= 1.0 / (s * s);
        out[i] = cv::Vec3f(static_cast<float>(sum[0]), static_cast<float>(sum[1]), static_cast<float>(sum[2]));
      }
    }
  });

  if (o.blur_sigma > 0) cv::GaussianBlur(image, image, cv::Size(0, 0), o.blur_sigma, o.blur_sigma, cv::BORDER_REFLECT);
  return image;
}

cv::Mat addNoise(cv::Mat image, const TagSceneOptions& o) {
  if (o.noise_sigma > 0) {
    cv::Mat noise(image.size(), image.type());
    cv::RNG rng(o.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
    image += noise;
  }
  cv::Mat out;
  image.convertTo(out, image.channels() == 1 ? CV_8U : CV_8UC3);  // rounds and clips
  return out;
}

bool allGrey(const TagSceneOptions& o) {
  for (const SceneSurface& s : o.surfaces)
    if (s.colour[0] != s.colour[1] || s.colour[1] != s.colour[2] || s.tile_colour[0] != s.tile_colour[1] ||
        s.tile_colour[1] != s.tile_colour[2])
      return false;
  return true;
}

}  // namespace

cv::Mat renderTagScene(const calib::Camera& camera, const calib::TagLayout& layout, const TagSceneOptions& o) {
  const cv::Mat bgr = renderScene(camera, layout, o);
  cv::Mat grey;
  if (allGrey(o))
    cv::extractChannel(bgr, grey, 0);
  else
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  return addNoise(grey, o);
}

cv::Mat renderTagSceneBgr(const calib::Camera& camera, const calib::TagLayout& layout, const TagSceneOptions& o) {
  return addNoise(renderScene(camera, layout, o), o);
}

}  // namespace kccd::calib
