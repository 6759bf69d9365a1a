#include "kccd/calib/silhouette.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/input_error.hpp"
#include "kccd/kinematics.hpp"

namespace kccd::calib {
namespace {

constexpr int kRimSamples = 32;      // per sphere; the polygon's radius is set between inscribed and circumscribed
constexpr int kSubpixel = 8;         // fill precision: 1/256 px (cv::fillConvexPoly's shift)
constexpr double kNearPlane = 0.01;  // m: a volume reaching closer to the camera is left out

// The 3-D rim of the sphere (centre c, radius r) seen from `eye`, appended to `rim` (nothing when
// the eye is inside the sphere).
bool appendRim(const Vec3& eye, const Vec3& c, double r, std::vector<Vec3>& rim) {
  const Vec3 d = c - eye;
  const double dist = d.norm();
  if (!(dist > r * 1.0001)) return false;
  const Vec3 n = d / dist;
  const Vec3 centre = c - (r * r / dist) * n;
  // The rim's radius, widened by half the chords' gap: the polygon then neither lies inside the
  // circle everywhere (a silhouette 0.5 % of r too small, which moves a fitted camera away) nor
  // outside it.
  const double rho = r * std::sqrt(1.0 - (r * r) / (dist * dist)) * 0.5 * (1.0 + 1.0 / std::cos(M_PI / kRimSamples));
  const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
  for (int k = 0; k < kRimSamples; ++k) {
    const double a = 2.0 * M_PI * k / kRimSamples;
    rim.push_back(centre + rho * (std::cos(a) * u + std::sin(a) * v));
  }
  return true;
}

}  // namespace

std::vector<PlacedVolume> placeVolumes(const Model& model, std::span<const double> state, std::span<const int> bodies) {
  std::vector<Pose> poses(model.joints.size());
  if (!framePoses(model, state, poses))
    throw InputError("state: " + std::to_string(state.size()) + " values for a model of " +
                     std::to_string(model.stateSize()) + " (or a value that is not finite)");
  std::vector<int> chosen(bodies.begin(), bodies.end());
  if (chosen.empty())
    for (std::size_t b = 0; b < model.bodies.size(); ++b) chosen.push_back(static_cast<int>(b));
  std::vector<PlacedVolume> out;
  for (const int b : chosen) {
    if (b < 0 || static_cast<std::size_t>(b) >= model.bodies.size())
      throw InputError("body index " + std::to_string(b) + " out of range");
    const Body& body = model.bodies[static_cast<std::size_t>(b)];
    const Pose& frame = framePose(poses, body.frame);
    PlacedVolume v;
    v.radius = body.radius;
    for (const Vec3& p : body.points) v.points.push_back(frame * p);
    out.push_back(std::move(v));
  }
  return out;
}

Silhouette drawSilhouette(const Camera& camera, std::span<const PlacedVolume> volumes, double spacing_px) {
  Silhouette s;
  s.mask = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
  const Pose w2c = camera.worldToCamera();
  const Vec3 eye = w2c.inverse().translation();
  const double fx = camera.camera_matrix(0, 0), fy = camera.camera_matrix(1, 1);
  struct Outline {
    std::vector<Vec3> world;         // per sample
    std::vector<cv::Point2d> pixel;  // per sample
  };
  std::vector<Outline> outlines;
  for (const PlacedVolume& vol : volumes) {
    std::vector<Vec3> rim;
    bool seen = true;
    for (const Vec3& p : vol.points) {
      if (vol.radius > 0.0) {
        seen = appendRim(eye, p, vol.radius, rim) && seen;
      } else {
        rim.push_back(p);
      }
    }
    if (!seen || rim.empty()) continue;
    // Undistorted normalised coordinates; a volume reaching behind the camera is left out.
    std::vector<cv::Point2f> flat;
    bool front = true;
    for (const Vec3& x : rim) {
      const Vec3 c = w2c * x;
      if (!(c.z() > kNearPlane)) front = false;
      flat.emplace_back(static_cast<float>(c.x() / c.z()), static_cast<float>(c.y() / c.z()));
    }
    if (!front) continue;
    std::vector<int> hull;
    cv::convexHull(flat, hull, false, false);
    if (hull.size() < 2) continue;
    // Along each hull edge, samples about spacing_px apart (in undistorted pixels); their 3-D
    // points interpolate the edge's ends (a straight edge's points project onto the edge).
    Outline o;
    std::vector<cv::Point3d> normalised;
    for (std::size_t i = 0; i < hull.size(); ++i) {
      const int a = hull[i], b = hull[(i + 1) % hull.size()];
      const double du = (flat[static_cast<std::size_t>(b)].x - flat[static_cast<std::size_t>(a)].x) * fx;
      const double dv = (flat[static_cast<std::size_t>(b)].y - flat[static_cast<std::size_t>(a)].y) * fy;
      // At most a few times the image's perimeter of samples per edge (an edge can reach far outside).
      const double cap = 4.0 * (camera.width + camera.height) / spacing_px;
      const int n = static_cast<int>(std::clamp(std::ceil(std::hypot(du, dv) / spacing_px), 1.0, cap));
      for (int k = 0; k < n; ++k) {
        const double t = static_cast<double>(k) / n;
        const Vec3 x = (1.0 - t) * rim[static_cast<std::size_t>(a)] + t * rim[static_cast<std::size_t>(b)];
        o.world.push_back(x);
        const Vec3 c = w2c * x;
        normalised.emplace_back(c.x() / c.z(), c.y() / c.z(), 1.0);
      }
    }
    cv::projectPoints(normalised, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.camera_matrix, camera.distortion,
                      o.pixel);
    std::vector<cv::Point> fixed;
    fixed.reserve(o.pixel.size());
    for (const cv::Point2d& p : o.pixel) {
      const double x = std::clamp(p.x, -1e5, 1e5), y = std::clamp(p.y, -1e5, 1e5);
      fixed.emplace_back(static_cast<int>(std::lround(x * (1 << kSubpixel))),
                         static_cast<int>(std::lround(y * (1 << kSubpixel))));
    }
    cv::fillPoly(s.mask, std::vector<std::vector<cv::Point>>{fixed}, cv::Scalar(255), cv::LINE_8, kSubpixel);
    outlines.push_back(std::move(o));
  }
  // The union's outer outline: a volume's outline sample that another volume covers is inside.
  for (const Outline& o : outlines) {
    const std::size_t n = o.pixel.size();
    // Orientation of the polygon (signed area) for the outward normals.
    double area = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Point2d& p = o.pixel[i];
      const cv::Point2d& q = o.pixel[(i + 1) % n];
      area += p.x * q.y - q.x * p.y;
    }
    const double sign = area > 0 ? 1.0 : -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Point2d t = o.pixel[(i + 1) % n] - o.pixel[(i + n - 1) % n];
      const double len = std::hypot(t.x, t.y);
      if (!(len > 1e-9)) continue;
      const cv::Point2d normal(sign * t.y / len, -sign * t.x / len);
      const cv::Point2d probe = o.pixel[i] + 1.5 * normal;
      const int px = static_cast<int>(std::lround(probe.x)), py = static_cast<int>(std::lround(probe.y));
      if (px >= 0 && py >= 0 && px < camera.width && py < camera.height && s.mask.at<unsigned char>(py, px) != 0)
        continue;
      s.outline.push_back({o.world[i], o.pixel[i], normal});
    }
  }
  return s;
}

Silhouette drawMeshSilhouette(const Camera& camera, std::span<const PlacedMesh> meshes, double spacing_px) {
  Silhouette s;
  // Each pixel's covering triangle (an index over all meshes' triangles; -1: none).
  cv::Mat id(camera.height, camera.width, CV_32S, cv::Scalar(-1));
  const Pose w2c = camera.worldToCamera();
  struct Projected {
    const PlacedMesh* mesh;
    std::vector<cv::Point2d> pixel;  // per vertex
    std::vector<char> front;         // per vertex
    int first = 0;                   // the index of its first triangle
  };
  std::vector<Projected> projected;
  int next = 0;
  for (const PlacedMesh& m : meshes) {
    Projected p{&m, {}, std::vector<char>(m.vertices.size(), 0), next};
    std::vector<cv::Point3d> normalised(m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      const Vec3 c = w2c * m.vertices[i];
      p.front[i] = c.z() > kNearPlane;
      normalised[i] = p.front[i] ? cv::Point3d(c.x() / c.z(), c.y() / c.z(), 1.0) : cv::Point3d(0, 0, 1);
    }
    if (!normalised.empty())
      cv::projectPoints(normalised, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.camera_matrix, camera.distortion,
                        p.pixel);
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto& tri = m.triangles[t];
      if (!p.front[tri[0]] || !p.front[tri[1]] || !p.front[tri[2]]) continue;
      cv::Point corners[3];
      bool inside = true;
      for (int k = 0; k < 3; ++k) {
        const cv::Point2d& q = p.pixel[tri[static_cast<std::size_t>(k)]];
        if (!(std::abs(q.x) < 1e5 && std::abs(q.y) < 1e5)) inside = false;
        corners[k] = cv::Point(static_cast<int>(std::lround(q.x * (1 << kSubpixel))),
                               static_cast<int>(std::lround(q.y * (1 << kSubpixel))));
      }
      if (inside) cv::fillConvexPoly(id, corners, 3, cv::Scalar(next + static_cast<int>(t)), cv::LINE_8, kSubpixel);
    }
    next += static_cast<int>(m.triangles.size());
    projected.push_back(std::move(p));
  }
  s.mask = id >= 0;
  // The outer outline, sampled every spacing_px along it; each sample is moved half a pixel
  // outward on its triangle's plane (barycentric coordinates extend beyond the triangle).
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(s.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  const int step = std::max(1, static_cast<int>(std::lround(spacing_px)));
  for (const std::vector<cv::Point>& c : contours) {
    const int n = static_cast<int>(c.size());
    if (n < 3) continue;
    for (int i = 0; i < n; i += step) {
      const cv::Point2d t =
          cv::Point2d(c[static_cast<std::size_t>((i + 2) % n)] - c[static_cast<std::size_t>((i + n - 2) % n)]);
      const double len = std::hypot(t.x, t.y);
      if (!(len > 0)) continue;
      cv::Point2d normal(t.y / len, -t.x / len);
      const cv::Point at = c[static_cast<std::size_t>(i)];
      const cv::Point probe(static_cast<int>(std::lround(at.x + 1.5 * normal.x)),
                            static_cast<int>(std::lround(at.y + 1.5 * normal.y)));
      if (probe.x >= 0 && probe.y >= 0 && probe.x < camera.width && probe.y < camera.height &&
          s.mask.at<unsigned char>(probe) != 0)
        normal = -normal;  // pointed inward
      const int tri = id.at<int>(at);
      if (tri < 0) continue;
      const auto owner = std::upper_bound(projected.begin(), projected.end(), tri,
                                          [](int v, const Projected& p) { return v < p.first; }) -
                         1;
      const auto& corners = owner->mesh->triangles[static_cast<std::size_t>(tri - owner->first)];
      const cv::Point2d a = owner->pixel[corners[0]], b = owner->pixel[corners[1]], d = owner->pixel[corners[2]];
      // Where the ray from the pixel's centre along the normal leaves the triangle: the outline
      // (not the fill's rounding), half a pixel out when that cannot be found.
      const cv::Point2d q0(at.x, at.y);
      double exit = 0.5;
      {
        double best = -HUGE_VAL;  // the exit: the farthest crossing along the normal
        const cv::Point2d corner[3] = {a, b, d};
        for (int k = 0; k < 3; ++k) {
          const cv::Point2d e0 = corner[k], e = corner[(k + 1) % 3] - corner[k];
          const double den = normal.x * e.y - normal.y * e.x;
          if (std::abs(den) < 1e-12) continue;
          const double t = ((e0.x - q0.x) * e.y - (e0.y - q0.y) * e.x) / den;            // along the normal
          const double u = ((e0.x - q0.x) * normal.y - (e0.y - q0.y) * normal.x) / den;  // along the edge
          if (t > -1.0 && t < 1.5 && u >= -0.01 && u <= 1.01 && t > best) best = t;
        }
        if (std::isfinite(best)) exit = best;
      }
      const cv::Point2d q = q0 + exit * normal;
      const double det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
      if (!(std::abs(det) > 1e-12)) continue;
      const double u = ((q.x - a.x) * (d.y - a.y) - (d.x - a.x) * (q.y - a.y)) / det;
      const double v = ((b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y)) / det;
      const Vec3& A = owner->mesh->vertices[corners[0]];
      const Vec3& B = owner->mesh->vertices[corners[1]];
      const Vec3& D = owner->mesh->vertices[corners[2]];
      s.outline.push_back({A + std::clamp(u, -2.0, 3.0) * (B - A) + std::clamp(v, -2.0, 3.0) * (D - A), q, normal});
    }
  }
  return s;
}

double maskIou(const cv::Mat& a, const cv::Mat& b) {
  CV_Assert(a.size() == b.size() && a.type() == CV_8UC1 && b.type() == CV_8UC1);
  cv::Mat both, either;
  cv::bitwise_and(a != 0, b != 0, both);
  cv::bitwise_or(a != 0, b != 0, either);
  const int u = cv::countNonZero(either);
  return u == 0 ? 1.0 : static_cast<double>(cv::countNonZero(both)) / u;
}

}  // namespace kccd::calib
