#include "kccd/calib/edge_refine.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/pose.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/format_number.hpp"
#include "kccd/input_error.hpp"
#include "outline_fit.hpp"

namespace kccd::calib {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxTurnDeg = 30.0;  // an edge within this of the outline's direction can be the outline

// One pyramid level of a picture's edges: per pixel the edge's gradient direction in whole
// degrees of [0, 180) plus 1 (0: no edge), and the gradient's magnitude.
struct EdgeLevel {
  cv::Mat direction;   // CV_8U
  cv::Mat magnitude;   // CV_32F
  double scale = 1.0;  // level pixels per full-resolution pixel: 1 / 2^level
};

// The value below which `share` of `values` lie (a sample of every 7th, enough for a threshold).
double quantile(const cv::Mat& values, double share) {
  std::vector<float> v;
  v.reserve(values.total() / 7 + 1);
  const float* p = values.ptr<float>(0);
  for (std::size_t i = 0; i < values.total(); i += 7) v.push_back(p[i]);
  const auto k = static_cast<std::ptrdiff_t>(share * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[static_cast<std::size_t>(k)];
}

// Canny edges of `grey` reduced `level` times, with thresholds from the picture's own gradients:
// the strong threshold above most of the picture (its 90th percentile) and above its noise (3
// times the median), the weak one half of it.
EdgeLevel edgesOf(const cv::Mat& grey, int level) {
  cv::Mat g = grey;
  for (int l = 0; l < level; ++l) cv::pyrDown(g, g);
  cv::Mat blurred, dx, dy, fx, fy;
  cv::GaussianBlur(g, blurred, cv::Size(5, 5), 1.0);
  cv::Sobel(blurred, dx, CV_16S, 1, 0, 3);
  cv::Sobel(blurred, dy, CV_16S, 0, 1, 3);
  EdgeLevel out;
  out.scale = 1.0 / std::pow(2.0, level);
  dx.convertTo(fx, CV_32F);
  dy.convertTo(fy, CV_32F);
  cv::magnitude(fx, fy, out.magnitude);
  const double high = std::max({quantile(out.magnitude, 0.9), 3.0 * quantile(out.magnitude, 0.5), 20.0});
  cv::Mat edges;
  cv::Canny(dx, dy, edges, 0.5 * high, high, true);
  out.direction = cv::Mat::zeros(g.size(), CV_8U);
  for (int y = 0; y < g.rows; ++y)
    for (int x = 0; x < g.cols; ++x)
      if (edges.at<unsigned char>(y, x)) {
        double a = std::atan2(fy.at<float>(y, x), fx.at<float>(y, x)) * 180.0 / kPi;
        if (a < 0) a += 180.0;
        out.direction.at<unsigned char>(y, x) = static_cast<unsigned char>(std::min(179, static_cast<int>(a)) + 1);
      }
  return out;
}

// The signed distance (level pixels) along the unit normal `n` from `p` to the nearest edge of
// the normal's direction within `range`, refined to the gradient's peak; NaN when none.
double nearestEdge(const EdgeLevel& e, const cv::Point2d& p, const cv::Point2d& n, double range) {
  double want = std::atan2(n.y, n.x) * 180.0 / kPi;
  if (want < 0) want += 180.0;
  const auto along = [&](double t) -> double {
    const int x = static_cast<int>(std::lround(p.x + t * n.x)), y = static_cast<int>(std::lround(p.y + t * n.y));
    if (x < 1 || y < 1 || x >= e.direction.cols - 1 || y >= e.direction.rows - 1) return NAN;
    const int d = e.direction.at<unsigned char>(y, x);
    if (d == 0) return NAN;
    double turn = std::abs((d - 1) - want);
    turn = std::min(turn, 180.0 - turn);
    if (turn > kMaxTurnDeg) return NAN;
    // The edge pixel's centre projected on the normal, then the gradient's peak across it.
    const double at = (x - p.x) * n.x + (y - p.y) * n.y;
    const cv::Point2d c = p + at * n;
    const double m0 = detail::sampleField(e.magnitude, c.x, c.y);
    const double mm = detail::sampleField(e.magnitude, c.x - n.x, c.y - n.y);
    const double mp = detail::sampleField(e.magnitude, c.x + n.x, c.y + n.y);
    const double curve = mm - 2.0 * m0 + mp;
    const double shift = curve < 0 ? std::clamp(0.5 * (mm - mp) / curve, -0.75, 0.75) : 0.0;
    return at + shift;
  };
  for (double t = 0.0; t <= range; t += 0.5) {
    const double a = along(t);
    if (!std::isnan(a)) return a;
    if (t > 0) {
      const double b = along(-t);
      if (!std::isnan(b)) return b;
    }
  }
  return NAN;
}

// The edges' field at one pyramid level: an outline point's residual is its distance (full
// resolution pixels) to the nearest edge of its direction along its normal, point to line; a
// point with none within `range_px` costs as much as one that far off and does not pull.
detail::Field edgeField(const std::vector<std::vector<EdgeLevel>>& levels, int level, double range_px) {
  return [&levels, level, range_px](const detail::OutlineSample& s, const cv::Point2d& p) {
    const EdgeLevel& e = levels[s.frame][static_cast<std::size_t>(level)];
    const cv::Point2d q((p.x + 0.5) * e.scale - 0.5, (p.y + 0.5) * e.scale - 0.5);
    const double d = nearestEdge(e, q, s.normal, range_px * e.scale);
    detail::FieldValue v;
    if (std::isnan(d)) {
      v.r = range_px;
      return v;
    }
    v.r = -d / e.scale;
    v.gx = s.normal.x, v.gy = s.normal.y;
    return v;
  };
}

// The share of the outline on the edges, with the drawn outline shifted and scaled in the image:
// per frame and direction bin (8 of 22.5 degrees) the distance to the edges within a bin of it,
// at one pyramid level.
class ShiftSearch {
 public:
  ShiftSearch(const std::vector<std::vector<EdgeLevel>>& levels, int level) {
    for (const std::vector<EdgeLevel>& frame : levels) {
      const EdgeLevel& e = frame[static_cast<std::size_t>(level)];
      scale_ = e.scale;
      std::array<cv::Mat, 8> dist;
      for (int b = 0; b < 8; ++b) {
        cv::Mat none(e.direction.size(), CV_8U, cv::Scalar(255));
        for (int y = 0; y < none.rows; ++y)
          for (int x = 0; x < none.cols; ++x)
            if (const int d = e.direction.at<unsigned char>(y, x)) {
              const int bin = (d - 1) * 8 / 180, turn = std::abs(bin - b);
              if (std::min(turn, 8 - turn) <= 1) none.at<unsigned char>(y, x) = 0;
            }
        cv::distanceTransform(none, dist[static_cast<std::size_t>(b)], cv::DIST_L2, cv::DIST_MASK_3);
      }
      fields_.push_back(std::move(dist));
    }
  }

  // One drawn point: its frame, its pixel (full resolution) and its direction bin.
  struct Point {
    std::size_t frame;
    cv::Point2d pixel;
    int bin;
  };

  // Sum over `points` of 1 - d / 2 level px (0 beyond), each moved to c + growth (p - c) + shift.
  double score(std::span<const Point> points, const cv::Point2d& centre, double growth,
               const cv::Point2d& shift) const {
    double sum = 0.0;
    for (const Point& p : points) {
      const cv::Point2d q = centre + growth * (p.pixel - centre) + shift;
      const int x = static_cast<int>(std::lround((q.x + 0.5) * scale_ - 0.5));
      const int y = static_cast<int>(std::lround((q.y + 0.5) * scale_ - 0.5));
      const cv::Mat& d = fields_[p.frame][static_cast<std::size_t>(p.bin)];
      if (x < 0 || y < 0 || x >= d.cols || y >= d.rows) continue;
      sum += std::max(0.0f, 1.0f - 0.5f * d.at<float>(y, x));
    }
    return sum;
  }
  double scale() const { return scale_; }

 private:
  double scale_ = 1.0;
  std::vector<std::array<cv::Mat, 8>> fields_;
};

// Pre-alignment, for a start a link's width off (four rough clicks): the drawn outlines of all
// frames shifted over the image (up to 8% of its diagonal) and scaled (0.8 to 1.25) at the
// coarsest level, the best share on edges of the outline's direction taken, and the camera turned
// and moved to match; the start when nothing scores better.
Camera preAlign(const Camera& start, std::span<const detail::FrameShape> volumes,
                const std::vector<std::vector<EdgeLevel>>& levels) {
  const ShiftSearch search(levels, 2);
  std::vector<ShiftSearch::Point> points;
  cv::Point2d centre(0, 0);
  {
    const std::vector<detail::OutlineSample> samples = detail::outlineSamples(start, volumes, 4.0);
    std::vector<cv::Point3d> world;
    for (const detail::OutlineSample& s : samples) world.push_back(s.world);
    if (world.size() < 12) return start;
    std::vector<cv::Point2d> px;
    cv::projectPoints(world, start.rvec, start.tvec, start.camera_matrix, start.distortion, px);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      double a = std::atan2(samples[i].normal.y, samples[i].normal.x) * 180.0 / kPi;
      if (a < 0) a += 180.0;
      points.push_back({samples[i].frame, px[i], std::min(7, static_cast<int>(a * 8 / 180))});
      centre += px[i];
    }
    centre *= 1.0 / static_cast<double>(points.size());
  }
  const double step = 1.0 / search.scale();  // one level pixel
  const int reach = static_cast<int>(std::ceil(0.08 * std::hypot(start.width, start.height) / step));
  double best = search.score(points, centre, 1.0, {0, 0}), best_growth = 1.0;
  cv::Point2d best_shift(0, 0);
  const double at_start = best;
  for (const double growth : {0.8, 0.86, 0.93, 1.0, 1.07, 1.15, 1.25})
    for (int j = -reach; j <= reach; ++j)
      for (int i = -reach; i <= reach; ++i) {
        const cv::Point2d shift(i * step, j * step);
        if (const double s = search.score(points, centre, growth, shift); s > best)
          best = s, best_growth = growth, best_shift = shift;
      }
  if (!(best > 1.1 * at_start)) return start;
  // The camera turned so the centre lands where the search put it after the move along the axis,
  // which scales the image about the principal point.
  const cv::Point2d pp(start.camera_matrix(0, 2), start.camera_matrix(1, 2));
  const cv::Point2d turn = (centre + best_shift - pp) * (1.0 / best_growth) - centre + pp;
  return detail::turnedAndMoved(start, turn.x, turn.y, best_growth, detail::meanDepth(start, volumes));
}

}  // namespace

RefineResult refineToEdges(const Camera& start, std::span<const EdgeFrame> frames, const EdgeOptions& options,
                           std::span<const Correspondence> clicks) {
  if (frames.empty()) throw InputError("edges: no frame to refine the pose with");
  std::vector<std::vector<EdgeLevel>> levels;
  std::vector<detail::FrameShape> shapes, volumes;  // with meshes when given; the volumes alone
  for (const EdgeFrame& f : frames) {
    if (f.image.cols != start.width || f.image.rows != start.height || f.image.depth() != CV_8U ||
        (f.image.channels() != 1 && f.image.channels() != 3))
      throw InputError("edges: a picture of " + std::to_string(f.image.cols) + "x" + std::to_string(f.image.rows) +
                       " with " + std::to_string(f.image.channels()) + " channel(s) for a camera of " +
                       std::to_string(start.width) + "x" + std::to_string(start.height) +
                       " (8-bit grey or BGR needed)");
    cv::Mat grey;
    if (f.image.channels() == 3)
      cv::cvtColor(f.image, grey, cv::COLOR_BGR2GRAY);
    else
      grey = f.image;
    levels.push_back({edgesOf(grey, 0), edgesOf(grey, 1), edgesOf(grey, 2)});
    shapes.push_back({f.volumes, f.meshes});
    volumes.push_back({f.volumes, {}});
  }
  RefineResult result;
  result.source = RefineSource::Edges;
  result.camera = start;
  result.frames.resize(frames.size());
  const auto samplesAt = [&](const Camera& at) { return detail::outlineSamples(at, shapes, options.spacing_px); };
  const auto volumeSamplesAt = [&](const Camera& at) {
    return detail::outlineSamples(at, volumes, options.spacing_px);
  };
  const bool meshes = std::any_of(frames.begin(), frames.end(), [](const EdgeFrame& f) { return !f.meshes.empty(); });

  // Coarse to fine: (level, Cauchy scale as a share of the diagonal); the search reaches 3 scales.
  // The coarsest level is for the pre-alignment only: a fit there is pulled by what a quarter of
  // the resolution leaves of the edges (measured: from the true pose into an 8 degree error).
  const double diagonal = std::hypot(start.width, start.height);
  const struct {
    int level;
    double scale;
  } stages[] = {{1, 0.03}, {1, 0.012}, {0, 0.005}, {0, 0.002}};
  detail::Anchors anchors;
  anchors.scale_px = options.click_px;
  for (const Correspondence& c : clicks) anchors.world.push_back(c.world), anchors.pixel.push_back(c.pixel);
  // Meshes are slower to draw: the half-resolution stages draw the volumes (the caller gives those
  // of the bodies the meshes show), the full-resolution ones the meshes, whose outline is traced on
  // pixels: a stage with them ends at steps below 1e-5 or gains below 1e-4 of the cost.
  const auto fitFrom = [&](Camera cam) {
    for (const auto& stage : stages) {
      const double c = std::max(1.5, stage.scale * diagonal);
      const double scales[] = {c};
      const bool fine = meshes && stage.level == 0;
      if (fine)
        cam = detail::fitPose(cam, samplesAt, edgeField(levels, stage.level, 3.0 * c), scales, options.max_iterations,
                              result.iterations, &anchors, 1e-5, 1e-4);
      else
        cam = detail::fitPose(cam, volumeSamplesAt, edgeField(levels, stage.level, 3.0 * c), scales,
                              options.max_iterations, result.iterations, &anchors);
    }
    return cam;
  };
  const double c_final = std::max(1.5, 0.002 * diagonal);
  const detail::Field fine = edgeField(levels, 0, 3.0 * c_final);
  // Per frame at `at`: the share of the outline within match_px of an edge of its direction, the
  // outline points' robust rms and their count; and the mean share over the frames.
  struct Shares {
    std::vector<FrameAgreement> frames;  // matched_after, rms_px, outline_points
    double mean = 0.0;
    std::vector<detail::OutlineSample> samples;
  };
  const auto sharesAt = [&](const Camera& at) {
    Shares out;
    out.samples = samplesAt(at);
    const std::vector<detail::OutlineSample>& samples = out.samples;
    out.frames.resize(frames.size());
    for (std::size_t f = 0; f < frames.size(); ++f) {
      std::vector<detail::OutlineSample> mine;
      for (const detail::OutlineSample& s : samples)
        if (s.frame == f) mine.push_back(s);
      std::vector<cv::Point3d> world;
      for (const detail::OutlineSample& s : mine) world.push_back(s.world);
      std::vector<cv::Point2d> px;
      if (!world.empty()) cv::projectPoints(world, at.rvec, at.tvec, at.camera_matrix, at.distortion, px);
      int on = 0;
      for (std::size_t i = 0; i < mine.size(); ++i)
        if (std::abs(fine(mine[i], px[i]).r) <= options.match_px) ++on;
      const detail::Evaluation e = detail::evaluate(at, at.rvec, at.tvec, mine, fine, c_final, false);
      FrameAgreement& a = out.frames[f];
      a.matched_after = mine.empty() ? 0.0 : static_cast<double>(on) / static_cast<double>(mine.size());
      a.rms_px = e.weight_sum > 0 ? std::sqrt(e.weighted_sq / e.weight_sum) : 0.0;
      a.outline_points = static_cast<int>(mine.size());
      out.mean += a.matched_after / static_cast<double>(frames.size());
    }
    return out;
  };
  // From the start and from its pre-alignment (clicks, when given, hold both near them); the fit
  // with more of its outline on edges is taken.
  Camera cam = fitFrom(start);
  {
    const Camera other = fitFrom(preAlign(start, volumes, levels));
    if (sharesAt(other).mean > sharesAt(cam).mean) cam = other;
  }
  // The clicks' rms distance from where the fit puts their points.
  double clicks_rms = 0.0;
  if (!clicks.empty()) {
    std::vector<cv::Point2d> px;
    cv::projectPoints(anchors.world, cam.rvec, cam.tvec, cam.camera_matrix, cam.distortion, px);
    for (std::size_t i = 0; i < px.size(); ++i)
      clicks_rms += std::pow(cv::norm(px[i] - anchors.pixel[i]), 2) / static_cast<double>(px.size());
    clicks_rms = std::sqrt(clicks_rms);
  }

  // The agreement before and after (the figures of the returned pose: the start's when it is kept).
  const Shares at_start = sharesAt(start), at_end = sharesAt(cam);
  const double before = at_start.mean, after = at_end.mean;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    result.frames[f] = at_end.frames[f];
    result.frames[f].matched_before = at_start.frames[f].matched_after;
  }
  double worst_drop = 0.0;
  for (const FrameAgreement& a : result.frames) worst_drop = std::max(worst_drop, a.matched_before - a.matched_after);

  const auto keepStart = [&](std::string message) {
    for (std::size_t f = 0; f < frames.size(); ++f) {
      result.frames[f] = at_start.frames[f];
      result.frames[f].matched_before = at_start.frames[f].matched_after;
    }
    result.covariance = cv::Matx66d::zeros();
    result.message = std::move(message);
    return result;
  };
  if (at_end.samples.size() < 12)
    return keepStart("the drawn robot's outline is not in the pictures (" + std::to_string(at_end.samples.size()) +
                     " points): the start is kept");
  if (!(after > before + 1e-3) || worst_drop > 0.05)
    return keepStart(
        "the edges did not improve the pose (" + formatNumber(100 * before, 3) +
        "% of the outline on edges at the start, " + formatNumber(100 * after, 3) + "% refined" +
        (worst_drop > 0.05 ? ", one frame " + formatNumber(100 * worst_drop, 3) + " points worse" : std::string()) +
        "): the start is kept");
  if (clicks_rms > 3.0 * options.click_px)
    return keepStart("the edges' best pose leaves the clicks " + formatNumber(clicks_rms, 3) +
                     " px rms from their points (more than 3 x " + formatNumber(options.click_px, 3) +
                     " px): the edges and the clicks disagree, the start is kept (check the clicks, "
                     "or start closer)");
  if (const std::optional<detail::FromStart> d = detail::fromStart(cam, start); options.start_is_prior && d) {
    if (d->sigmas > 3.0 && after - before < 0.05)
      return keepStart("the edges' best pose lies " + formatNumber(d->difference.rotation_deg, 3) + " deg and " +
                       formatNumber(d->difference.position_m * 1000, 3) + " mm from the start (" +
                       formatNumber(d->sigmas, 3) + " sigma) for " + formatNumber(100 * (after - before), 3) +
                       " points more of the outline on edges: the start is kept");
  }
  const detail::Evaluation e = detail::evaluate(cam, cam.rvec, cam.tvec, at_end.samples, fine, c_final, true);
  result.covariance = detail::poseCovariance(e);
  const auto [rotation_sigma, position_sigma] = poseSigmas(cam.rvec, cam.tvec, result.covariance);
  cam.rotation_sigma_deg = rotation_sigma;
  cam.position_sigma_m = position_sigma;
  if (after < options.min_matched || !(*cam.rotation_sigma_deg <= options.max_rotation_sigma_deg))
    return keepStart(
        "the drawn robot's outline and the pictures' edges agree too little (" + formatNumber(100 * after, 3) +
        "% on edges, at least " + formatNumber(100 * options.min_matched, 3) + "% needed; rotation +-" +
        formatNumber(*cam.rotation_sigma_deg, 3) + " deg, at most " + formatNumber(options.max_rotation_sigma_deg, 3) +
        "): add frames with the robot elsewhere, check each frame's state and which bodies are in view, or give masks; "
        "the start is kept");
  result.camera = cam;
  result.improved = true;
  result.message = "refined to the edges: " + formatNumber(100 * before, 3) + "% -> " + formatNumber(100 * after, 3) +
                   "% of the outline on edges over " + std::to_string(frames.size()) + " frame(s), rotation +-" +
                   formatNumber(*cam.rotation_sigma_deg, 3) + " deg, position +-" +
                   formatNumber(*cam.position_sigma_m, 3) + " m";
  return result;
}

}  // namespace kccd::calib
