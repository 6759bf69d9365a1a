#include "kccd/calib/intrinsics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <unordered_set>

#include <opencv2/calib3d.hpp>

#include "kccd/format_number.hpp"

namespace kccd::calib {
namespace {

constexpr double kPlaneTolerance = 1e-3;  // of the board's extent

std::string plural(std::size_t n, const char* word) { return std::to_string(n) + " " + word + (n == 1 ? "" : "s"); }

// The plane through points: centroid, in-plane axes, normal (the direction of least spread), the
// largest distance of a point from it (and which point) and the extent (bounding-box diagonal).
struct Plane {
  cv::Vec3d origin{0, 0, 0}, ex{1, 0, 0}, ey{0, 1, 0}, normal{0, 0, 1};
  double max_offset = 0.0;
  std::size_t worst = 0;
  double extent = 0.0;
};

Plane fitPlane(const std::vector<cv::Vec3d>& p) {
  Plane out;
  const int n = static_cast<int>(p.size());
  if (n == 0) return out;
  cv::Vec3d lo = p[0], hi = p[0];
  for (const auto& q : p) {
    out.origin += q / n;
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
  }
  out.extent = cv::norm(hi - lo);
  cv::Mat a(n, 3, CV_64F);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) a.at<double>(i, k) = p[static_cast<std::size_t>(i)][k] - out.origin[k];
  cv::Mat w, u, vt;
  cv::SVD::compute(a, w, u, vt, cv::SVD::FULL_UV);
  if (vt.rows == 3) {
    out.ex = cv::Vec3d(vt.at<double>(0, 0), vt.at<double>(0, 1), vt.at<double>(0, 2));
    out.normal = cv::Vec3d(vt.at<double>(2, 0), vt.at<double>(2, 1), vt.at<double>(2, 2));
    out.ey = out.normal.cross(out.ex);
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double d = std::abs((p[i] - out.origin).dot(out.normal));
    if (d > out.max_offset) out.max_offset = d, out.worst = i;
  }
  return out;
}

cv::Vec3d vec(const cv::Point3d& p) { return {p.x, p.y, p.z}; }

// Tilt (deg) of the board plane from a homography board (x, y) -> pixel, for a camera with focal
// length f and principal point c: the angle between the board normal and the optical axis.
double tiltFromHomography(const cv::Matx33d& h, double f, cv::Point2d c) {
  const cv::Matx33d kinv(1 / f, 0, -c.x / f, 0, 1 / f, -c.y / f, 0, 0, 1);
  const cv::Matx33d m = kinv * h;
  cv::Vec3d r1(m(0, 0), m(1, 0), m(2, 0)), r2(m(0, 1), m(1, 1), m(2, 1));
  const double n1 = cv::norm(r1), n2 = cv::norm(r2);
  if (!(n1 > 0) || !(n2 > 0)) return std::numeric_limits<double>::quiet_NaN();
  const cv::Vec3d r3 = (r1 / n1).cross(r2 / n2);
  const double nz = std::abs(r3[2]) / std::max(cv::norm(r3), 1e-300);
  return std::acos(std::clamp(nz, 0.0, 1.0)) * 180.0 / std::numbers::pi;
}

// A focal length for the homographies (Zhang's constraints with square pixels and the principal
// point at the image centre, least squares over all views); `fallback` when they do not give one.
double focalGuess(const std::vector<cv::Matx33d>& hs, cv::Point2d c, double fallback) {
  double saa = 0, sab = 0;
  const cv::Matx33d t(1, 0, -c.x, 0, 1, -c.y, 0, 0, 1);
  for (const auto& h0 : hs) {
    cv::Matx33d h = t * h0;
    const double s = cv::norm(cv::Vec3d(h(0, 0), h(1, 0), h(2, 0))) + cv::norm(cv::Vec3d(h(0, 1), h(1, 1), h(2, 1)));
    if (!(s > 0)) continue;
    h *= 1.0 / s;
    // (h1x h2x + h1y h2y) u + h1z h2z = 0 and (|h1xy|^2 - |h2xy|^2) u + (h1z^2 - h2z^2) = 0, u = 1/f^2
    const double a1 = h(0, 0) * h(0, 1) + h(1, 0) * h(1, 1), b1 = h(2, 0) * h(2, 1);
    const double a2 = h(0, 0) * h(0, 0) + h(1, 0) * h(1, 0) - h(0, 1) * h(0, 1) - h(1, 1) * h(1, 1);
    const double b2 = h(2, 0) * h(2, 0) - h(2, 1) * h(2, 1);
    saa += a1 * a1 + a2 * a2;
    sab += a1 * b1 + a2 * b2;
  }
  if (!(saa > 0)) return fallback;
  const double u = -sab / saa;
  if (!(u > 0) || !std::isfinite(u)) return fallback;
  const double f = 1.0 / std::sqrt(u);
  // Nearly face-on views make the estimate meaningless: keep it within a plausible lens range.
  return std::clamp(f, 0.2 * fallback, 10.0 * fallback);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

const char* const kAddViews =
    "add images of the whole board from different angles (tilted 20-45 deg about different axes, some near the image "
    "corners)";

}  // namespace

Board Board::grid(const TagGrid& g) {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw InputError(InputLocation{"grid", 0, 0, field}, problem);
  };
  if (g.cols < 1 || g.cols > kMaxTagId + 1)
    fail("cols", std::to_string(g.cols) + " is not in 1.." + std::to_string(kMaxTagId + 1));
  if (g.rows < 1 || g.rows > kMaxTagId + 1)
    fail("rows", std::to_string(g.rows) + " is not in 1.." + std::to_string(kMaxTagId + 1));
  if (g.cols * g.rows < 2) fail("size", "a board needs at least 2 tags (a view needs 8 corners)");
  if (!std::isfinite(g.tag_size) || !(g.tag_size > 0) || g.tag_size > kMaxTagSize)
    fail("tag size", formatNumber(g.tag_size, 3) + " m is not in (0, " + formatNumber(kMaxTagSize, 3) + "]");
  if (!std::isfinite(g.spacing) || g.spacing < 0 || g.spacing > kMaxTagSize)
    fail("spacing", formatNumber(g.spacing, 3) + " m is not in [0, " + formatNumber(kMaxTagSize, 3) + "]");
  if (g.first_id < 0 || g.first_id > kMaxTagId)
    fail("first id", std::to_string(g.first_id) + " is not in 0.." + std::to_string(kMaxTagId));
  const int last = g.first_id + g.cols * g.rows - 1;
  if (last > kMaxTagId)
    fail("first id", "the ids " + std::to_string(g.first_id) + ".." + std::to_string(last) +
                         " go beyond tag36h11's last id " + std::to_string(kMaxTagId));
  Board b;
  const double pitch = g.tag_size + g.spacing;
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      Tag t;
      t.id = g.first_id + r * g.cols + c;
      t.size = g.tag_size;
      t.xyz = Vec3(c * pitch, -r * pitch, 0.0);
      b.layout.tags.push_back(t);
    }
  return b;
}

Board Board::fromLayout(const TagLayout& layout, const std::string& source) {
  if (layout.tags.size() < 2)
    throw TagLayoutError(source + ": tags: a board needs at least 2 tags (a view needs 8 corners), the layout has " +
                         plural(layout.tags.size(), "tag"));
  std::vector<cv::Vec3d> corners;
  for (const Tag& t : layout.tags)
    for (const auto& c : t.corners()) corners.push_back(vec(c));
  Plane plane = fitPlane(corners);
  if (plane.max_offset > kPlaneTolerance * plane.extent) {
    const Tag& t = layout.tags[plane.worst / 4];
    throw TagLayoutError(
        source + ": tags: tag " + std::to_string(t.id) + " is " + formatNumber(plane.max_offset, 3) +
        " m off the plane of the other tags: a calibration board must be flat (all tags in one plane)");
  }
  const Vec3 z0 = layout.tags.front().pose().linear().col(2);
  for (const Tag& t : layout.tags) {
    const Vec3 z = t.pose().linear().col(2);
    if (z.dot(z0) < 0)
      throw TagLayoutError(source + ": tags: tag " + std::to_string(t.id) + " faces the other way than tag " +
                           std::to_string(layout.tags.front().id) + ": all tags of a board must face the camera side");
  }
  Board b;
  b.layout = layout;
  return b;
}

std::vector<Correspondence> Board::correspondences(const std::vector<TagDetection>& detections,
                                                   const std::string& image) const {
  return tagCorrespondences(detections, layout, image).points;
}

const char* toString(IntrinsicsStatus status) {
  switch (status) {
    case IntrinsicsStatus::Solved:
      return "solved";
    case IntrinsicsStatus::TooFewViews:
      return "too few views";
    case IntrinsicsStatus::NotPlanar:
      return "not planar";
    case IntrinsicsStatus::FrontoParallel:
      return "fronto-parallel";
    case IntrinsicsStatus::IllConditioned:
      return "ill-conditioned";
  }
  return "unknown";
}

IntrinsicsResult calibrateIntrinsics(const std::vector<IntrinsicsView>& views, cv::Size image_size,
                                     const IntrinsicsOptions& options) {
  // ---- input
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (options.min_views < 3 || options.min_points_per_view < 6 || !(options.min_tilt_deg >= 0) ||
      !(options.min_tilt_deg < 90) || !positive(options.outlier_ratio) || !(options.outlier_floor_px >= 0) ||
      !std::isfinite(options.outlier_floor_px) || !(options.noise_floor_px >= 0) ||
      !std::isfinite(options.noise_floor_px) || !positive(options.max_focal_sigma_ratio) ||
      !positive(options.max_principal_sigma_ratio) || (options.fix_k3 && options.rational))
    throw InputError(
        "intrinsics options: a threshold is out of range, min_views < 3, min_points_per_view < 6, or fix_k3 with "
        "rational");
  const int width = image_size.width, height = image_size.height;
  if (width < 1 || width > kMaxImageSide || height < 1 || height > kMaxImageSide ||
      static_cast<long>(width) * height > kMaxImagePixels)
    throw InputError("image size: " + std::to_string(width) + "x" + std::to_string(height) + " is not in 1.." +
                     std::to_string(kMaxImageSide) + " a side with at most " + std::to_string(kMaxImagePixels) +
                     " pixels");
  std::unordered_set<std::string> view_names;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const IntrinsicsView& v = views[i];
    const std::string where = "view " + std::to_string(i + 1);
    if (v.name.empty()) throw InputError(where + ": name: empty");
    if (!view_names.insert(v.name).second) throw InputError(where + ": name: '" + printable(v.name) + "' given twice");
    std::unordered_set<std::string> names;
    for (const Correspondence& c : v.points) {
      const std::string at = printable(v.name) + ": point '" + printable(c.name) + "'";
      if (c.name.empty()) throw InputError(printable(v.name) + ": a point has an empty name");
      if (!names.insert(c.name).second) throw InputError(at + ": given twice");
      if (!std::isfinite(c.pixel.x) || !std::isfinite(c.pixel.y)) throw InputError(at + ": pixel: not a finite number");
      if (!std::isfinite(c.world.x) || !std::isfinite(c.world.y) || !std::isfinite(c.world.z))
        throw InputError(at + ": world: not a finite number");
    }
  }

  IntrinsicsResult result;
  result.camera.width = width;
  result.camera.height = height;
  const std::size_t n = views.size();
  std::vector<std::size_t> usable;
  for (std::size_t i = 0; i < n; ++i) {
    IntrinsicsViewReport r;
    r.name = views[i].name;
    r.points = static_cast<int>(views[i].points.size());
    if (r.points < options.min_points_per_view)
      r.note = "only " + plural(views[i].points.size(), "board corner") + " (at least " +
               std::to_string(options.min_points_per_view) + ": two whole tags)";
    else
      usable.push_back(i);
    result.views.push_back(r);
  }
  const auto reject_unused = [&] {
    result.rejected.clear();
    result.used.clear();
    for (const auto& r : result.views) {
      if (r.used)
        result.used.push_back(r.name);
      else if (!r.note.empty())
        result.rejected.push_back(r.name);
    }
  };
  const auto too_few = [&](const std::string& why) {
    result.status = IntrinsicsStatus::TooFewViews;
    result.message = why + ", at least " + std::to_string(options.min_views) + " needed: " + kAddViews;
    reject_unused();
    return result;
  };
  const auto need = static_cast<std::size_t>(options.min_views);
  if (usable.size() < need)
    return too_few(plural(usable.size(), "usable view") + " of " + plural(n, "image") + " (a view needs " +
                   std::to_string(options.min_points_per_view) + " board corners)");

  // ---- the board plane, and board coordinates with z = 0
  std::vector<cv::Vec3d> all;
  for (std::size_t i : usable)
    for (const Correspondence& c : views[i].points) all.push_back(vec(c.world));
  const Plane plane = fitPlane(all);
  if (plane.max_offset > kPlaneTolerance * plane.extent) {
    result.status = IntrinsicsStatus::NotPlanar;
    result.message = "the board points lie up to " + formatNumber(plane.max_offset, 3) +
                     " m off one plane (board extent " + formatNumber(plane.extent, 3) +
                     " m): intrinsics need a flat board with all tags in one plane";
    reject_unused();
    return result;
  }
  std::vector<std::vector<cv::Point3f>> object(n);
  std::vector<std::vector<cv::Point2f>> image(n);
  std::vector<cv::Matx33d> homography(n);
  const cv::Point2d centre((width - 1) / 2.0, (height - 1) / 2.0);
  std::vector<std::size_t> with_h;
  for (std::size_t i : usable) {
    std::vector<cv::Point2d> board2, pix;
    for (const Correspondence& c : views[i].points) {
      const cv::Vec3d d = vec(c.world) - plane.origin;
      board2.emplace_back(d.dot(plane.ex), d.dot(plane.ey));
      pix.push_back(c.pixel);
      object[i].emplace_back(static_cast<float>(board2.back().x), static_cast<float>(board2.back().y), 0.0f);
      image[i].emplace_back(static_cast<float>(c.pixel.x), static_cast<float>(c.pixel.y));
    }
    cv::Mat h;
    try {
      h = cv::findHomography(board2, pix, 0);
    } catch (const cv::Exception&) {
      h.release();
    }
    if (h.empty() || !cv::checkRange(h)) {
      result.views[i].note = "its corners do not determine a homography (on one line?)";
      continue;
    }
    homography[i] = cv::Matx33d(h);
    with_h.push_back(i);
  }
  usable = with_h;
  if (usable.size() < need) return too_few(plural(usable.size(), "usable view") + " of " + plural(n, "image"));

  // ---- board tilt: the focal length is not observable from face-on views
  std::vector<cv::Matx33d> hs;
  for (std::size_t i : usable) hs.push_back(homography[i]);
  const double f_guess = focalGuess(hs, centre, std::max(width, height));
  double max_tilt = 0.0;
  for (std::size_t i : usable) {
    result.views[i].tilt_deg = tiltFromHomography(homography[i], f_guess, centre);
    if (std::isfinite(result.views[i].tilt_deg)) max_tilt = std::max(max_tilt, result.views[i].tilt_deg);
  }
  const auto fronto = [&](double largest) {
    result.status = IntrinsicsStatus::FrontoParallel;
    result.message =
        "every view sees the board nearly face-on (largest tilt " + formatNumber(largest, 2) + " deg, at least " +
        formatNumber(options.min_tilt_deg, 3) +
        " needed): tilt the board 20-45 deg towards the camera about different axes (left/right and up/down) in "
        "several views";
    reject_unused();
    return result;
  };
  if (max_tilt < options.min_tilt_deg) return fronto(max_tilt);

  // ---- solve, leaving out outlier views one by one
  int flags = 0;
  if (options.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (options.rational) flags |= cv::CALIB_RATIONAL_MODEL;
  const std::size_t n_dist = options.rational ? 8 : 5;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12);
  std::vector<std::size_t> in = usable;
  cv::Mat k, d, std_int, std_ext, per_view;
  std::vector<cv::Mat> rvecs, tvecs;
  double rms = 0.0;
  for (;;) {
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> img;
    for (std::size_t i : in) obj.push_back(object[i]), img.push_back(image[i]);
    k = cv::Mat();
    d = cv::Mat::zeros(1, static_cast<int>(n_dist), CV_64F);
    try {
      rms = cv::calibrateCamera(obj, img, image_size, k, d, rvecs, tvecs, std_int, std_ext, per_view, flags, criteria);
    } catch (const cv::Exception& e) {
      result.status = IntrinsicsStatus::IllConditioned;
      result.message = "the solve failed (" + printable(e.err, 80) + "): " + kAddViews;
      reject_unused();
      return result;
    }
    for (std::size_t j = 0; j < in.size(); ++j) result.views[in[j]].rms_px = per_view.at<double>(static_cast<int>(j));
    std::vector<double> errs;
    for (std::size_t j = 0; j < in.size(); ++j) errs.push_back(per_view.at<double>(static_cast<int>(j)));
    const double med = median(errs);
    const std::size_t worst = static_cast<std::size_t>(std::max_element(errs.begin(), errs.end()) - errs.begin());
    const double limit = std::max(options.outlier_ratio * med, options.outlier_floor_px);
    if (!(errs[worst] > limit)) break;
    const IntrinsicsViewReport& w = result.views[in[worst]];
    if (in.size() <= need) {
      for (std::size_t i : in) result.views[i].used = true;
      result.status = IntrinsicsStatus::IllConditioned;
      result.message = "view " + printable(w.name) + " does not fit the others (RMS " + formatNumber(w.rms_px, 3) +
                       " px, median " + formatNumber(med, 3) + " px) and no view can be spared: retake it or " +
                       kAddViews;
      reject_unused();
      return result;
    }
    result.views[in[worst]].note = "outlier: RMS " + formatNumber(w.rms_px, 3) + " px, more than " +
                                   formatNumber(limit, 3) + " px (the other views' median " + formatNumber(med, 3) +
                                   " px)";
    in.erase(in.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  for (std::size_t i : in) result.views[i].used = true;
  // After the rejections the RMS of the dropped views is their fit to the final solution.
  for (std::size_t i : usable) {
    if (result.views[i].used) continue;
    cv::Mat rv, tv;
    std::vector<cv::Point2f> proj;
    if (!result.views[i].note.empty() && cv::solvePnP(object[i], image[i], k, d, rv, tv)) {
      cv::projectPoints(object[i], rv, tv, k, d, proj);
      double sse = 0;
      for (std::size_t p = 0; p < proj.size(); ++p) sse += std::pow(cv::norm(proj[p] - image[i][p]), 2);
      result.views[i].rms_px = std::sqrt(sse / static_cast<double>(proj.size()));
    }
  }
  reject_unused();
  result.rms_px = rms;
  max_tilt = 0.0;
  for (std::size_t j = 0; j < in.size(); ++j) {
    cv::Matx33d r;
    cv::Rodrigues(rvecs[j], r);
    const double tilt = std::acos(std::clamp(std::abs(r(2, 2)), 0.0, 1.0)) * 180.0 / std::numbers::pi;
    result.views[in[j]].tilt_deg = tilt;
    max_tilt = std::max(max_tilt, tilt);
  }

  // ---- the solution and its conditioning
  result.sigmas.fx = std_int.at<double>(0);
  result.sigmas.fy = std_int.at<double>(1);
  result.sigmas.cx = std_int.at<double>(2);
  result.sigmas.cy = std_int.at<double>(3);
  for (std::size_t j = 0; j < n_dist; ++j)
    result.sigmas.distortion.push_back(std_int.at<double>(static_cast<int>(4 + j)));
  Camera cam;
  cam.width = width;
  cam.height = height;
  cam.camera_matrix = cv::Matx33d(k);
  cam.distortion.assign(d.begin<double>(),
                        d.begin<double>() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(n_dist, d.total())));
  cam.reprojection_rms_px = rms;
  result.camera = cam;
  if (max_tilt < options.min_tilt_deg) return fronto(max_tilt);

  const double scale = rms > 0 ? std::max(1.0, options.noise_floor_px / rms) : 1e9;
  const double fx = cam.camera_matrix(0, 0), fy = cam.camera_matrix(1, 1);
  std::string weak;
  const auto known = [&](const char* name, double sigma, double value) {
    if (!std::isfinite(sigma)) return std::string(name) + " is not determined by these views";
    return std::string(name) + " " + formatNumber(value, 5) + " is known only to +-" + formatNumber(sigma * scale, 3) +
           " px";
  };
  if (!(result.sigmas.fx * scale <= options.max_focal_sigma_ratio * fx))
    weak = known("fx", result.sigmas.fx, fx);
  else if (!(result.sigmas.fy * scale <= options.max_focal_sigma_ratio * fy))
    weak = known("fy", result.sigmas.fy, fy);
  else if (!(result.sigmas.cx * scale <= options.max_principal_sigma_ratio * width))
    weak = known("cx", result.sigmas.cx, cam.camera_matrix(0, 2));
  else if (!(result.sigmas.cy * scale <= options.max_principal_sigma_ratio * height))
    weak = known("cy", result.sigmas.cy, cam.camera_matrix(1, 2));
  if (!weak.empty()) {
    result.status = IntrinsicsStatus::IllConditioned;
    result.message =
        weak + " (at " + formatNumber(std::max(rms, options.noise_floor_px), 2) + " px noise): " + kAddViews;
    return result;
  }
  try {
    cam.validate("solved camera");
  } catch (const CameraError& e) {
    result.status = IntrinsicsStatus::IllConditioned;
    result.message = std::string(e.what()) +
                     ": the lens model is not usable; add views with the board near the image corners and edges";
    return result;
  }
  result.status = IntrinsicsStatus::Solved;
  result.message = "solved from " + std::to_string(in.size()) + " of " + plural(n, "view") + ": RMS " +
                   formatNumber(rms, 3) + " px, fx " + formatNumber(fx, 6) + " +- " +
                   formatNumber(result.sigmas.fx, 2) + ", fy " + formatNumber(fy, 6) + " +- " +
                   formatNumber(result.sigmas.fy, 2) + ", cx " + formatNumber(cam.camera_matrix(0, 2), 5) + " +- " +
                   formatNumber(result.sigmas.cx, 2) + ", cy " + formatNumber(cam.camera_matrix(1, 2), 5) + " +- " +
                   formatNumber(result.sigmas.cy, 2) + " px";
  return result;
}

std::string intrinsicsCameraText(const IntrinsicsResult& result) {
  std::string text = cameraText(result.camera);
  if (!text.empty() && text.back() != '\n') text += '\n';
  std::ostringstream extra;
  extra.precision(17);
  extra << "avg_reprojection_error: " << result.rms_px << "\n";
  extra << "nr_of_frames: " << result.used.size() << "\n";
  return text + extra.str();
}

}  // namespace kccd::calib
