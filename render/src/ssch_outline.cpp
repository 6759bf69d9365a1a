#include "kccd/render/ssch_outline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace kccd::render {

namespace {

using Vec2 = Eigen::Vector2d;

// One support line of the image: direction angle, unit direction w, support h (the image lies
// in w . x <= h) and the point q of the image on the line; not finite: overflow or NaN.
struct Support {
  double theta = 0.0;
  Vec2 w = Vec2::Zero();
  double h = 0.0;
  Vec2 q = Vec2::Zero();
  bool finite = false;
};

// The image of a sphere (centre c, radius r, c.z > r) is the set of x = (x, y) whose ray
// (x, y, 1) meets the sphere. The line w . x = s bounds it when the plane through the camera
// with normal n = (w, -s) has the whole sphere on its negative side: w . c.xy - s c.z +
// r sqrt(1 + s^2) <= 0. The left side falls with s (c.z > r), so the support is its root:
// s = (A c.z + r sqrt(A^2 + c.z^2 - r^2)) / (c.z^2 - r^2), A = w . c.xy, evaluated scale-free
// (everything over c.z, so huge and tiny coordinates neither overflow nor lose digits); the plane
// touches the sphere at c + r n / |n|, whose image is the touching point.
Support support(std::span<const Vec3> points, double r, double theta) {
  Support s;
  s.theta = theta;
  s.w = Vec2(std::cos(theta), std::sin(theta));
  s.h = -std::numeric_limits<double>::infinity();
  std::size_t best = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& c = points[i];
    const double a = (s.w.x() * c.x() + s.w.y() * c.y()) / c.z(), rho = r / c.z();
    const double e = (1.0 - rho) * (1.0 + rho);
    const double h = (a + rho * std::sqrt(a * a + e)) / e;
    if (!std::isfinite(h)) return s;  // finite == false
    if (h > s.h) {
      s.h = h;
      best = i;
    }
  }
  const Vec3& c = points[best];
  const double rho = r / c.z(), len = std::sqrt(1.0 + s.h * s.h);
  const double z = 1.0 - rho * s.h / len;  // the touching point's depth over c.z (> 0)
  s.q = Vec2((c.x() / c.z() + rho * s.w.x() / len) / z, (c.y() / c.z() + rho * s.w.y() / len) / z);
  // Rounding must not move the line inwards: a margin far below a pixel.
  s.h += 1e-12 * (1.0 + std::abs(s.h));
  s.finite = s.q.allFinite() && std::isfinite(s.h);
  return s;
}

// Where the lines of two supports (less than pi apart) meet.
Vec2 corner(const Support& a, const Support& b) {
  const double det = a.w.x() * b.w.y() - a.w.y() * b.w.x();
  return Vec2((a.h * b.w.y() - b.h * a.w.y()) / det, (a.w.x() * b.h - b.w.x() * a.h) / det);
}

double segmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

struct Refiner {
  std::span<const Vec3> points;
  double r;
  double tolerance;  // normalised image units
  int max_vertices;
  std::vector<Support>& out;
  int computed = 0;  // supports computed (bounds the work whatever the recursion does)

  // Appends the supports strictly between a and b that bring the corner between each pair of
  // neighbours within tolerance of the image: the chord between their touching points lies in
  // the (convex) image, and the corner is within tolerance of the chord. False when it cannot
  // (rounding keeps a corner out, angles stop splitting, too many supports).
  bool refine(const Support& a, const Support& b) {
    const Vec2 v = corner(a, b);
    if (!v.allFinite()) return false;
    if (segmentDistance(v, a.q, b.q) <= tolerance) return true;
    if (++computed > max_vertices || !(b.theta - a.theta > 1e-9)) return false;
    const Support m = support(points, r, 0.5 * (a.theta + b.theta));
    if (!m.finite) return false;
    if (!refine(a, m)) return false;
    out.push_back(m);
    return refine(m, b);
  }
};

}  // namespace

bool sschOutline(std::span<const Vec3> points, double radius, const OutlineOptions& options,
                 std::vector<Eigen::Vector2d>& polygon) {
  polygon.clear();
  if (points.empty() || !std::isfinite(radius) || radius < 0.0 || !(options.focal_px > 0.0) ||
      !(options.tolerance_px > 0.0) || !std::isfinite(options.focal_px))
    return false;
  for (const Vec3& c : points) {
    if (!c.allFinite()) return false;
    if (!(c.z() - radius > 0.0) || !(c.z() - radius >= options.min_depth)) return false;
  }
  const double tolerance = options.tolerance_px / options.focal_px;
  std::vector<Support> supports;
  supports.reserve(64);
  Refiner refiner{points, radius, tolerance, options.max_vertices, supports};
  // Eight directions to start with (neighbours less than pi apart), refined between each pair.
  constexpr int kStart = 8;
  std::array<Support, kStart + 1> start;
  for (int k = 0; k <= kStart; ++k) {
    start[static_cast<std::size_t>(k)] = support(points, radius, 2.0 * std::numbers::pi * k / kStart);
    if (!start[static_cast<std::size_t>(k)].finite) return false;
  }
  for (int k = 0; k < kStart; ++k) {
    supports.push_back(start[static_cast<std::size_t>(k)]);
    if (!refiner.refine(start[static_cast<std::size_t>(k)], start[static_cast<std::size_t>(k) + 1])) return false;
  }
  // The corners; where several lines meet at one point of the image (a sphere's image smaller
  // than the tolerance, the ends of a thin core), that corner once.
  polygon.reserve(supports.size());
  double extent = 0.0;
  for (std::size_t k = 0; k < supports.size(); ++k) {
    const Vec2 v = corner(supports[k], supports[(k + 1) % supports.size()]);
    if (!v.allFinite()) {
      polygon.clear();
      return false;
    }
    extent = std::max(extent, v.cwiseAbs().maxCoeff());
    polygon.push_back(v);
  }
  const double same = 1e-12 * (1.0 + extent);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < polygon.size(); ++k)
    if (kept == 0 || (polygon[k] - polygon[kept - 1]).norm() > same) polygon[kept++] = polygon[k];
  while (kept > 1 && (polygon[kept - 1] - polygon[0]).norm() <= same) --kept;
  polygon.resize(kept);
  return true;
}

}  // namespace kccd::render
