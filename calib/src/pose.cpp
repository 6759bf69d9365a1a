#include "kccd/calib/pose.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <unordered_set>

#include <opencv2/calib3d.hpp>

#include "kccd/format_number.hpp"

namespace kccd::calib {
namespace {

constexpr std::size_t kMaxTriples = 2000;  // P3P samples; fewer triples than this are all tried
constexpr std::size_t kMinTriples = 200;   // sampled triples tried before the adaptive stop

// Singular values (descending, RMS-scaled) and the direction of the smallest of centred points.
struct Spread {
  cv::Vec3d s{0, 0, 0};
  cv::Vec3d normal{0, 0, 1};
  cv::Vec3d centroid{0, 0, 0};
};

Spread spread3(const std::vector<cv::Point3d>& p) {
  Spread out;
  const int n = static_cast<int>(p.size());
  for (const auto& q : p) out.centroid += cv::Vec3d(q.x, q.y, q.z) / n;
  cv::Mat a(n, 3, CV_64F);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j)
      a.at<double>(i, j) = (cv::Vec3d(p[i].x, p[i].y, p[i].z) - out.centroid)[j] / std::sqrt(n);
  cv::Mat w, u, vt;
  cv::SVD::compute(a, w, u, vt);
  for (int j = 0; j < std::min(3, w.rows); ++j) out.s[j] = w.at<double>(j);
  if (vt.rows == 3) out.normal = cv::Vec3d(vt.at<double>(2, 0), vt.at<double>(2, 1), vt.at<double>(2, 2));
  return out;
}

cv::Vec2d spread2(const std::vector<cv::Point2d>& p) {
  const int n = static_cast<int>(p.size());
  cv::Point2d c(0, 0);
  for (const auto& q : p) c += q / n;
  cv::Mat a(n, 2, CV_64F);
  for (int i = 0; i < n; ++i) a.at<double>(i, 0) = p[i].x - c.x, a.at<double>(i, 1) = p[i].y - c.y;
  cv::Mat w;
  cv::SVD::compute(a, w, cv::SVD::NO_UV);
  return {w.at<double>(0) / std::sqrt(n), w.rows > 1 ? w.at<double>(1) / std::sqrt(n) : 0.0};
}

template <class T>
std::vector<T> pick(const std::vector<T>& v, const std::vector<int>& idx) {
  std::vector<T> out;
  out.reserve(idx.size());
  for (int i : idx) out.push_back(v[i]);
  return out;
}

// Pixel residuals of all points under a pose (through the full lens model); infinite behind the camera.
std::vector<double> pixelResiduals(const Camera& cam, const cv::Vec3d& rvec, const cv::Vec3d& tvec,
                                   const std::vector<cv::Point3d>& world, const std::vector<cv::Point2d>& pixel) {
  std::vector<cv::Point2d> proj;
  cv::projectPoints(world, rvec, tvec, cam.camera_matrix, cam.distortion, proj);
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  std::vector<double> res(world.size());
  for (std::size_t i = 0; i < world.size(); ++i) {
    const cv::Vec3d x = r * cv::Vec3d(world[i].x, world[i].y, world[i].z) + tvec;
    res[i] =
        x[2] > 0 ? std::hypot(proj[i].x - pixel[i].x, proj[i].y - pixel[i].y) : std::numeric_limits<double>::infinity();
    if (!std::isfinite(res[i])) res[i] = std::numeric_limits<double>::infinity();
  }
  return res;
}

double sse(const std::vector<double>& res, const std::vector<int>& idx) {
  double s = 0;
  for (int i : idx) s += res[i] * res[i];
  return s;
}

double sumSquares(const std::vector<double>& res) {
  double s = 0;
  for (double v : res) s += v * v;
  return s;
}

// Axis-angle vector of a rotation matrix, accurate for small angles too (cv::Rodrigues returns
// zero below about 1e-5 rad).
cv::Vec3d logRotation(const cv::Matx33d& r) {
  const cv::Vec3d w(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const double s = 0.5 * cv::norm(w), c = 0.5 * (r(0, 0) + r(1, 1) + r(2, 2) - 1.0);
  if (s < 1e-3 && c > 0) return 0.5 * w * (1.0 + s * s / 6.0);  // theta / sin(theta) to second order
  if (s < 1e-12) {                                              // theta near pi: cv::Rodrigues handles it
    cv::Vec3d v;
    cv::Rodrigues(r, v);
    return v;
  }
  return 0.5 * w * (std::atan2(s, c) / s);
}

// Small rotation (axis-angle, applied on the left) of R(rvec + d) R(rvec)^T.
cv::Vec3d rotationDelta(const cv::Vec3d& rvec, const cv::Vec3d& d) {
  cv::Matx33d r0, r1;
  cv::Rodrigues(rvec, r0);
  cv::Rodrigues(rvec + d, r1);
  return logRotation(r1 * r0.t());
}

cv::Vec3d centre(const cv::Vec3d& rvec, const cv::Vec3d& tvec) {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  return -(r.t() * tvec);
}

double largestEigen(const cv::Matx33d& m) {
  cv::Matx33d sym = 0.5 * (m + m.t());
  cv::Mat values;
  cv::eigen(sym, values);
  return std::max(0.0, values.at<double>(0));
}

// Angle (degrees) of the rotation between two rvecs.
double rotationAngleDeg(const cv::Vec3d& a, const cv::Vec3d& b) {
  cv::Matx33d ra, rb;
  cv::Rodrigues(a, ra);
  cv::Rodrigues(b, rb);
  return cv::norm(logRotation(ra * rb.t())) * 180.0 / std::numbers::pi;
}

void refineLM(const Camera& cam, const std::vector<cv::Point3d>& world, const std::vector<cv::Point2d>& pixel,
              cv::Vec3d& rvec, cv::Vec3d& tvec) {
  cv::Mat r(rvec), t(tvec);
  cv::solvePnPRefineLM(world, pixel, cam.camera_matrix, cam.distortion, r, t,
                       cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  rvec = cv::Vec3d(r.ptr<double>());
  tvec = cv::Vec3d(t.ptr<double>());
}

std::string rejectedText(const std::vector<Correspondence>& pts, const std::vector<double>& res,
                         const std::vector<char>& inlier) {
  std::string s;
  int shown = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (inlier[i]) continue;
    if (shown == 8) {
      s += ", ...";
      break;
    }
    s += (shown++ ? ", " : "") + printable(pts[i].name, 40) + " (" +
         (std::isfinite(res[i]) ? formatNumber(res[i], 3) + " px" : std::string("behind the camera")) + ")";
  }
  return s;
}

// The options, the intrinsics (their pose cleared) and every correspondence checked: throws InputError.
Camera checkedPoseInput(const Camera& intrinsics, const std::vector<Correspondence>& points,
                        const PoseOptions& options) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(options.ransac_threshold_px) || options.min_inliers < 4 || !positive(options.min_spread_ratio) ||
      !(options.noise_floor_px >= 0) || !positive(options.max_rotation_sigma_deg) ||
      !positive(options.max_position_sigma_ratio) || !(options.min_mirror_separation >= 0) ||
      !std::isfinite(options.noise_floor_px) || !std::isfinite(options.min_mirror_separation))
    throw InputError("pose options: a threshold is not a positive finite number or min_inliers < 4");
  Camera cam = intrinsics;
  cam.rvec = cv::Vec3d(0, 0, 0);
  cam.tvec = cv::Vec3d(0, 0, 0);
  cam.reprojection_rms_px.reset();
  cam.rotation_sigma_deg.reset();
  cam.position_sigma_m.reset();
  cam.validate("intrinsics");

  std::unordered_set<std::string> names;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Correspondence& c = points[i];
    const std::string where = "correspondence " + std::to_string(i + 1);
    if (c.name.empty()) throw InputError(where + ": name: empty");
    if (!names.insert(c.name).second) throw InputError(where + ": name: '" + printable(c.name) + "' given twice");
    if (!std::isfinite(c.pixel.x) || !std::isfinite(c.pixel.y))
      throw InputError(where + " (" + printable(c.name) + "): pixel: not a finite number");
    if (!std::isfinite(c.world.x) || !std::isfinite(c.world.y) || !std::isfinite(c.world.z))
      throw InputError(where + " (" + printable(c.name) + "): world: not a finite number");
  }
  return cam;
}

// The best pose of P3P on triples of `candidates` (all of them, or kMaxTriples drawn with an early
// stop), scored by the count within `thr_n` (normalised units), then by the truncated squared error.
struct P3PBest {
  int count = -1;  // -1: no triple gave a pose
  double cost = std::numeric_limits<double>::infinity();
  cv::Vec3d r, t;
};
P3PBest ransacP3P(const std::vector<cv::Point3d>& world, const std::vector<cv::Point2d>& norm,
                  const std::vector<int>& candidates, double thr_n) {
  const int m = static_cast<int>(candidates.size());
  std::vector<std::array<int, 3>> triples;
  const double total = static_cast<double>(m) * (m - 1) * (m - 2) / 6.0;
  const bool sampled = total > kMaxTriples;
  if (!sampled) {
    for (int a = 0; a < m; ++a)
      for (int b = a + 1; b < m; ++b)
        for (int c = b + 1; c < m; ++c) triples.push_back({a, b, c});
  } else {
    std::mt19937_64 rng(12345);
    std::uniform_int_distribution<int> u(0, m - 1);
    while (triples.size() < kMaxTriples) {
      const int a = u(rng), b = u(rng), c = u(rng);
      if (a != b && b != c && a != c) triples.push_back({a, b, c});
    }
  }
  P3PBest best;
  for (std::size_t tried = 0; tried < triples.size(); ++tried) {
    // Sampled triples stop early once, at the best inlier ratio w so far, a triple of inliers
    // would have been drawn with probability 1 - 1e-6 (at least kMinTriples are always tried).
    if (sampled && tried >= kMinTriples && best.count > 0) {
      const double w = static_cast<double>(best.count) / m;
      const double p = w * w * w;
      if (p >= 1.0 || static_cast<double>(tried) >= std::log(1e-6) / std::log1p(-p)) break;
    }
    const auto& tri = triples[tried];
    std::vector<cv::Point3d> w3;
    std::vector<cv::Point2d> i3;
    for (int k : tri) w3.push_back(world[candidates[k]]), i3.push_back(norm[candidates[k]]);
    std::vector<cv::Mat> rs, ts;
    try {
      cv::solveP3P(w3, i3, cv::Matx33d::eye(), cv::noArray(), rs, ts, cv::SOLVEPNP_AP3P);
    } catch (const cv::Exception&) {
      continue;
    }
    for (std::size_t s = 0; s < rs.size(); ++s) {
      const cv::Vec3d rv(rs[s].ptr<double>()), tv(ts[s].ptr<double>());
      if (!std::isfinite(cv::norm(rv)) || !std::isfinite(cv::norm(tv))) continue;
      cv::Matx33d r;
      cv::Rodrigues(rv, r);
      int count = 0;
      double cost = 0;
      for (int i : candidates) {
        const cv::Vec3d x = r * cv::Vec3d(world[i].x, world[i].y, world[i].z) + tv;
        double e2 = thr_n * thr_n;
        if (x[2] > 0) {
          const double dx = x[0] / x[2] - norm[i].x, dy = x[1] / x[2] - norm[i].y;
          e2 = std::min(e2, dx * dx + dy * dy);
          if (dx * dx + dy * dy <= thr_n * thr_n) ++count;
        }
        cost += e2;
      }
      if (count > best.count || (count == best.count && cost < best.cost)) best = {count, cost, rv, tv};
    }
  }
  return best;
}

// SQPnP and LM on the inliers `in`, re-selected among `candidates` by their true pixel residual
// (within `threshold_px`) until stable (at most 6 rounds, or until fewer than `need` agree):
// `rvec`, `tvec`, every point's residual `res` and `in` as they end.
void settleInliers(const Camera& cam, const std::vector<cv::Point3d>& world, const std::vector<cv::Point2d>& pixel,
                   const std::vector<cv::Point2d>& norm, const std::vector<int>& candidates, double threshold_px,
                   int need, cv::Vec3d& rvec, cv::Vec3d& tvec, std::vector<double>& res, std::vector<char>& in) {
  std::vector<int> idx;
  const int n = static_cast<int>(world.size());
  for (int iter = 0; iter < 6; ++iter) {
    idx.clear();
    for (int i = 0; i < n; ++i)
      if (in[i]) idx.push_back(i);
    if (static_cast<int>(idx.size()) < need) return;  // the caller finds too few
    const auto wi = pick(world, idx);
    const auto pi = pick(pixel, idx);
    // SQPnP start (global minimum of the algebraic error) vs the current pose: keep the better after LM.
    cv::Vec3d r1 = rvec, t1 = tvec;
    refineLM(cam, wi, pi, r1, t1);
    double e1 = sumSquares(pixelResiduals(cam, r1, t1, wi, pi));
    try {
      cv::Mat r2m, t2m;
      if (cv::solvePnP(wi, pick(norm, idx), cv::Matx33d::eye(), cv::noArray(), r2m, t2m, false, cv::SOLVEPNP_SQPNP)) {
        cv::Vec3d r2(r2m.ptr<double>()), t2(t2m.ptr<double>());
        refineLM(cam, wi, pi, r2, t2);
        const double e2 = sumSquares(pixelResiduals(cam, r2, t2, wi, pi));
        if (e2 < e1) r1 = r2, t1 = t2, e1 = e2;
      }
    } catch (const cv::Exception&) {
    }
    rvec = r1, tvec = t1;
    res = pixelResiduals(cam, rvec, tvec, world, pixel);
    std::vector<char> next(n, 0);
    for (int i : candidates) next[i] = res[i] <= threshold_px;
    if (next == in) break;
    in = next;
  }
}

// Nearly planar points (`wi` at `pi`, `wn` normalised) have two poses that fit: the angle of the
// other one, IPPE's second solution refined, when it is more than `same_deg` from `rvec` and fits
// with a squared error below `worst_sse`; else none.
std::optional<double> mirroredPose(const Camera& cam, const std::vector<cv::Point3d>& wi,
                                   const std::vector<cv::Point2d>& pi, const std::vector<cv::Point2d>& wn,
                                   const cv::Vec3d& rvec, double same_deg, double worst_sse) {
  const Spread sp = spread3(wi);
  if (!(sp.s[2] < 0.1 * sp.s[0])) return std::nullopt;
  std::vector<cv::Point3d> flat;
  for (const auto& p : wi) {
    const cv::Vec3d v(p.x, p.y, p.z);
    const cv::Vec3d q = v - sp.normal * (v - sp.centroid).dot(sp.normal);
    flat.emplace_back(q[0], q[1], q[2]);
  }
  std::vector<cv::Mat> rs, ts;
  try {
    cv::solvePnPGeneric(flat, wn, cv::Matx33d::eye(), cv::noArray(), rs, ts, false, cv::SOLVEPNP_IPPE);
  } catch (const cv::Exception&) {
    rs.clear();
  }
  for (std::size_t s = 0; s < rs.size(); ++s) {
    cv::Vec3d r2(rs[s].ptr<double>()), t2(ts[s].ptr<double>());
    refineLM(cam, wi, pi, r2, t2);
    const double ang = rotationAngleDeg(r2, rvec);
    if (ang < same_deg) continue;  // the same pose
    if (sumSquares(pixelResiduals(cam, r2, t2, wi, pi)) < worst_sse) return ang;
  }
  return std::nullopt;
}

}  // namespace

const char* toString(PoseStatus status) {
  switch (status) {
    case PoseStatus::Solved:
      return "solved";
    case PoseStatus::TooFewPoints:
      return "too few points";
    case PoseStatus::Collinear:
      return "collinear points";
    case PoseStatus::PoorGeometry:
      return "poor geometry";
    case PoseStatus::TooFewInliers:
      return "too few inliers";
  }
  return "unknown";
}

std::pair<double, double> poseSigmas(const cv::Vec3d& rvec, const cv::Vec3d& tvec, const cv::Matx66d& covariance) {
  // Jacobians of the rotation increment and of the centre with respect to (rvec, tvec), by central differences.
  cv::Matx<double, 3, 6> a = cv::Matx<double, 3, 6>::zeros(), g = cv::Matx<double, 3, 6>::zeros();
  const double h = 1e-6;
  for (int c = 0; c < 3; ++c) {
    cv::Vec3d d(0, 0, 0);
    d[c] = h;
    const cv::Vec3d da = (rotationDelta(rvec, d) - rotationDelta(rvec, -d)) / (2 * h);
    const cv::Vec3d dg = (centre(rvec + d, tvec) - centre(rvec - d, tvec)) / (2 * h);
    for (int r = 0; r < 3; ++r) a(r, c) = da[r], g(r, c) = dg[r];
  }
  cv::Matx33d rmat;
  cv::Rodrigues(rvec, rmat);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g(r, 3 + c) = -rmat(c, r);
  return {std::sqrt(largestEigen(a * covariance * a.t())) * 180.0 / std::numbers::pi,
          std::sqrt(largestEigen(g * covariance * g.t()))};
}

PoseResult solvePose(const Camera& intrinsics, const std::vector<Correspondence>& points, const PoseOptions& options) {
  const Camera cam = checkedPoseInput(intrinsics, points, options);
  PoseResult result;
  result.camera = cam;
  const int n = static_cast<int>(points.size());
  const int need = options.min_inliers;
  if (n < need) {
    result.status = PoseStatus::TooFewPoints;
    result.message = std::to_string(n) + " point" + (n == 1 ? "" : "s") + " given, at least " + std::to_string(need) +
                     " needed: add labelled points or tags";
    return result;
  }

  std::vector<cv::Point3d> world(n);
  std::vector<cv::Point2d> pixel(n);
  for (int i = 0; i < n; ++i) world[i] = points[i].world, pixel[i] = points[i].pixel;

  const auto collinear = [&](const std::vector<cv::Point3d>& w) {
    const Spread s = spread3(w);
    return !(s.s[0] > 0) || s.s[1] < options.min_spread_ratio * s.s[0];
  };
  if (collinear(world)) {
    result.status = PoseStatus::Collinear;
    result.message =
        "the " + std::to_string(n) + " world points lie (nearly) on one line: add at least two points off that line";
    return result;
  }

  // ---- undistorted image points (normalised coordinates); points the lens model cannot invert are left out
  cv::Mat px(n, 1, CV_64FC2), normal;
  for (int i = 0; i < n; ++i) px.at<cv::Vec2d>(i) = cv::Vec2d(pixel[i].x, pixel[i].y);
  std::vector<unsigned char> valid;
  undistortPixels(cam, px, normal, valid);
  std::vector<cv::Point2d> norm(n);
  std::vector<int> candidates;
  for (int i = 0; i < n; ++i) {
    norm[i] = cv::Point2d(normal.at<cv::Vec2d>(i)[0], normal.at<cv::Vec2d>(i)[1]);
    if (valid[i]) candidates.push_back(i);
  }
  const double fx = cam.camera_matrix(0, 0), fy = cam.camera_matrix(1, 1), f = std::sqrt(fx * fy);
  {
    const cv::Vec2d s = spread2(pick(norm, candidates));
    if (candidates.size() >= 3 && s[1] < options.min_spread_ratio * s[0]) {
      result.status = PoseStatus::PoorGeometry;
      result.message =
          "the points appear on one line in the image (the camera is nearly in their plane): "
          "add points off that line or view them from another side";
      return result;
    }
  }

  // ---- RANSAC: P3P on triples of undistorted points, scored by inliers then truncated squared error
  const P3PBest best = ransacP3P(world, norm, candidates, options.ransac_threshold_px / f);
  const int best_count = best.count;
  const cv::Vec3d best_r = best.r, best_t = best.t;

  const auto fillResiduals = [&](const std::vector<double>& res, const std::vector<char>& in) {
    result.residuals.clear();
    result.rejected.clear();
    for (int i = 0; i < n; ++i) {
      result.residuals.push_back({points[i].name, res[i], in[i] != 0});
      if (!in[i]) result.rejected.push_back(points[i].name);
    }
  };
  const auto tooFewInliers = [&](int count, const std::vector<double>& res, const std::vector<char>& in) {
    result.status = PoseStatus::TooFewInliers;
    result.message = "only " + std::to_string(count) + " of " + std::to_string(n) +
                     " points agree on one pose within " + formatNumber(options.ransac_threshold_px, 3) +
                     " px, at least " + std::to_string(need) + " needed: check the labels or add points";
    if (!res.empty()) {
      fillResiduals(res, in);
      result.message += " (outside: " + rejectedText(points, res, in) + ")";
    }
    return result;
  };
  if (best_count < need) {
    if (best_count < 0) return tooFewInliers(0, {}, {});
    const std::vector<double> res = pixelResiduals(cam, best_r, best_t, world, pixel);
    std::vector<char> in(n, 0);
    for (int i : candidates) in[i] = res[i] <= options.ransac_threshold_px;
    return tooFewInliers(static_cast<int>(std::count(in.begin(), in.end(), 1)), res, in);
  }

  // ---- SQPnP + LM on the inliers, re-selecting inliers by their true pixel residual until stable
  cv::Vec3d rvec = best_r, tvec = best_t;
  std::vector<double> res = pixelResiduals(cam, rvec, tvec, world, pixel);
  std::vector<char> in(n, 0);
  for (int i : candidates) in[i] = res[i] <= options.ransac_threshold_px;
  settleInliers(cam, world, pixel, norm, candidates, options.ransac_threshold_px, need, rvec, tvec, res, in);
  std::vector<int> idx;
  idx.clear();
  for (int i = 0; i < n; ++i)
    if (in[i]) idx.push_back(i);
  const int k = static_cast<int>(idx.size());
  if (k < need) return tooFewInliers(k, res, in);
  fillResiduals(res, in);
  result.inliers = k;
  const std::string rejected = k < n ? "; rejected: " + rejectedText(points, res, in) : "";

  const auto wi = pick(world, idx);
  const auto pi = pick(pixel, idx);
  // Every degree of freedom must rest on more than one point: the agreeing points must stay off
  // one line with any one of them removed (else that single point alone sets the roll about the line).
  bool one_off_line = false;
  for (int leave = 0; leave < k && !one_off_line; ++leave) {
    std::vector<cv::Point3d> rest;
    for (int q = 0; q < k; ++q)
      if (q != leave) rest.push_back(wi[q]);
    one_off_line = collinear(rest);
  }
  if (collinear(wi) || one_off_line) {
    result.status = PoseStatus::Collinear;
    result.message = "the " + std::to_string(k) + " agreeing points lie (nearly) on one line" +
                     (collinear(wi) ? std::string() : std::string(" but for one")) +
                     ": add at least two points off that line" + rejected;
    return result;
  }

  // ---- covariance of (rvec, tvec), then of the rotation and of the camera centre
  const double sse_in = sse(res, idx);
  const double sigma2 = sse_in / std::max(1, 2 * k - 6);
  const double rms = std::sqrt(sse_in / k);
  cv::Mat proj, jac;
  cv::projectPoints(wi, rvec, tvec, cam.camera_matrix, cam.distortion, proj, jac);
  const cv::Mat j6 = jac.colRange(0, 6);
  const cv::Mat jtj = j6.t() * j6;
  cv::Mat w, u, vt;
  cv::SVD::compute(jtj, w, u, vt);
  const bool cond_ok = w.at<double>(5) > 1e-12 * w.at<double>(0);
  const std::string at_noise =
      " at " + formatNumber(std::max(std::sqrt(sigma2), options.noise_floor_px), 3) + " px noise";
  if (!cond_ok) {
    result.status = PoseStatus::PoorGeometry;
    result.message =
        "the pose is not determined by these points: add points spread over the view and in depth" + rejected;
    return result;
  }
  cv::Matx66d inv;
  cv::Mat(jtj.inv(cv::DECOMP_SVD)).copyTo(inv);
  const cv::Matx66d cov = sigma2 * inv;

  const auto sigmas = [&](const cv::Matx66d& s) { return poseSigmas(rvec, tvec, s); };
  const auto [rot_sigma, pos_sigma] = sigmas(cov);
  const double gate2 = std::max(sigma2, options.noise_floor_px * options.noise_floor_px);
  const auto [rot_gate, pos_gate] = sigmas(gate2 * inv);
  const cv::Vec3d cam_centre = centre(rvec, tvec);
  const double distance = cv::norm(cam_centre - spread3(wi).centroid);
  double extent = 0;  // largest angle between two inlier rays, degrees
  for (int p = 0; p < k; ++p)
    for (int q = p + 1; q < k; ++q) {
      const cv::Vec3d x(norm[idx[p]].x, norm[idx[p]].y, 1), y(norm[idx[q]].x, norm[idx[q]].y, 1);
      extent = std::max(
          extent, std::acos(std::clamp(x.dot(y) / (cv::norm(x) * cv::norm(y)), -1.0, 1.0)) * 180.0 / std::numbers::pi);
    }
  if (rot_gate > options.max_rotation_sigma_deg || pos_gate > options.max_position_sigma_ratio * distance) {
    result.status = PoseStatus::PoorGeometry;
    result.message = "the points span only " + formatNumber(extent, 3) + " deg of the view at " +
                     formatNumber(distance, 3) + " m: the pose is uncertain to " + formatNumber(rot_gate, 3) +
                     " deg and " + formatNumber(pos_gate, 3) + " m" + at_noise +
                     "; add points spread wider (or closer to the camera)" + rejected;
    return result;
  }

  // ---- mirror (Necker) ambiguity of a nearly planar set: the other IPPE solution, refined
  if (const std::optional<double> ang = mirroredPose(cam, wi, pi, pick(norm, idx), rvec, 3 * rot_gate + 0.5,
                                                     sse_in + options.min_mirror_separation * gate2)) {
    result.status = PoseStatus::PoorGeometry;
    result.message = "a mirrored pose " + formatNumber(*ang, 3) +
                     " deg away fits these nearly planar points almost as well" + at_noise +
                     ": add points off their plane or spread wider across the view" + rejected;
    return result;
  }

  result.status = PoseStatus::Solved;
  result.camera.rvec = rvec;
  result.camera.tvec = tvec;
  result.camera.reprojection_rms_px = rms;
  result.camera.rotation_sigma_deg = rot_sigma;
  result.camera.position_sigma_m = pos_sigma;
  result.covariance = cov;
  result.message = "solved with " + std::to_string(k) + " of " + std::to_string(n) + " points: RMS " +
                   formatNumber(rms, 3) + " px, rotation +-" + formatNumber(rot_sigma, 3) + " deg, position +-" +
                   formatNumber(pos_sigma, 3) + " m" + rejected;
  return result;
}

double projectedSigmaPx(const Camera& camera, const cv::Matx66d& covariance, const std::vector<cv::Point3d>& world) {
  double worst = 0.0;
  const cv::Matx33d r = [&] {
    cv::Matx33d m;
    cv::Rodrigues(camera.rvec, m);
    return m;
  }();
  std::vector<cv::Point3d> front;
  for (const cv::Point3d& p : world) {
    const cv::Vec3d c = r * cv::Vec3d(p.x, p.y, p.z) + camera.tvec;
    if (std::isfinite(c[2]) && c[2] > 1e-9) front.push_back(p);
  }
  if (front.empty()) return 0.0;
  std::vector<cv::Point2d> image;
  cv::Mat jacobian;
  cv::projectPoints(front, camera.rvec, camera.tvec, camera.camera_matrix, camera.distortion, image, jacobian);
  const cv::Matx66d& c = covariance;
  for (std::size_t i = 0; i < front.size(); ++i) {
    cv::Matx<double, 2, 6> j;
    for (int row = 0; row < 2; ++row)
      for (int col = 0; col < 6; ++col) j(row, col) = jacobian.at<double>(static_cast<int>(2 * i) + row, col);
    const cv::Matx22d m = j * c * j.t();
    // Largest eigenvalue of a symmetric 2x2 matrix, in closed form.
    const double mean = 0.5 * (m(0, 0) + m(1, 1));
    const double half = std::hypot(0.5 * (m(0, 0) - m(1, 1)), m(0, 1));
    worst = std::max(worst, std::sqrt(std::max(0.0, mean + half)));
  }
  return worst;
}

}  // namespace kccd::calib
