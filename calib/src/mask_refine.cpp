#include "kccd/calib/mask_refine.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_file.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/format_number.hpp"
#include "outline_fit.hpp"

namespace kccd::calib {
namespace {

cv::Mat signedDistance(const cv::Mat& mask);

// A frame's target: the cleaned mask and its signed distance field (px; < 0 inside the robot).
// Where the mask is unknown it counts as robot (what such a region mostly holds, so the known
// part's outline does not end there), and the drawn outline's points in it count for nothing.
struct Target {
  cv::Mat mask;
  cv::Mat sdf;    // CV_32F
  cv::Mat known;  // empty: everywhere
  // `m` (a drawing, or the mask) where the mask is known.
  cv::Mat inKnown(const cv::Mat& m) const { return known.empty() ? m : (m & known); }
  void set(cv::Mat cleaned) {
    mask = cleaned;
    sdf = signedDistance(known.empty() ? cleaned : (cleaned | (known == 0)));
  }
  double iou(const cv::Mat& drawn) const { return maskIou(inKnown(drawn), inKnown(mask)); }
};

// Specks that are not near the drawn robot dropped, holes smaller than a few percent of the
// image's side filled: what segmentation leaves that no pose can explain.
cv::Mat cleanMask(const cv::Mat& mask, const cv::Mat& drawn) {
  const double diagonal = std::hypot(mask.cols, mask.rows);
  // Near: within a fifth of the image's diagonal of the drawing (a distance transform, not a
  // dilation by a kernel of hundreds of pixels).
  cv::Mat away, near;
  cv::distanceTransform(drawn == 0, away, cv::DIST_L2, cv::DIST_MASK_3);
  near = away <= static_cast<float>(std::max(3.0, 0.2 * diagonal));
  cv::Mat labels;
  const int n = cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x)
      if (const int l = labels.at<int>(y, x); l > 0 && near.at<unsigned char>(y, x))
        keep[static_cast<std::size_t>(l)] = 1;
  cv::Mat out = cv::Mat::zeros(mask.size(), CV_8UC1);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x)
      if (keep[static_cast<std::size_t>(labels.at<int>(y, x))] && labels.at<int>(y, x) > 0)
        out.at<unsigned char>(y, x) = 255;
  if (cv::countNonZero(out) == 0) out = mask.clone();  // nothing near: keep all, the fit says what it can
  // Holes: background components that do not touch the border and are small.
  cv::Mat background = out == 0, holes;
  const int m = cv::connectedComponents(background, holes, 4, CV_32S);
  std::vector<int> area(static_cast<std::size_t>(m), 0);
  std::vector<char> border(static_cast<std::size_t>(m), 0);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const int l = holes.at<int>(y, x);
      ++area[static_cast<std::size_t>(l)];
      if (x == 0 || y == 0 || x == out.cols - 1 || y == out.rows - 1) border[static_cast<std::size_t>(l)] = 1;
    }
  const double small = std::pow(0.03 * std::min(out.cols, out.rows), 2);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const int l = holes.at<int>(y, x);
      if (l > 0 && !border[static_cast<std::size_t>(l)] && area[static_cast<std::size_t>(l)] < small)
        out.at<unsigned char>(y, x) = 255;
    }
  return out;
}

cv::Mat signedDistance(const cv::Mat& mask) {
  cv::Mat inside, outside;
  cv::distanceTransform(mask, inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(mask == 0, outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat sdf(mask.size(), CV_32F);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const float i = inside.at<float>(y, x), o = outside.at<float>(y, x);
      sdf.at<float>(y, x) = (o > 0 ? o - 0.5f : 0.0f) - (i > 0 ? i - 0.5f : 0.0f);
    }
  return sdf;
}

// Each frame's shape, as the outline fit takes it.
std::vector<detail::FrameShape> shapesOf(std::span<const MaskFrame> frames) {
  std::vector<detail::FrameShape> out;
  for (const MaskFrame& f : frames) out.push_back({f.volumes, f.meshes});
  return out;
}

// The masks' field: an outline point's signed distance to the mask's outline. The field should
// grow outward along the drawn outline's normal; where it does not (a hole's edge, another
// object's outline), the point counts little.
detail::Field maskField(const std::vector<Target>& targets) {
  return [&targets](const detail::OutlineSample& s, const cv::Point2d& p) {
    const cv::Mat& sdf = targets[s.frame].sdf;
    detail::FieldValue v;
    v.r = detail::sampleField(sdf, p.x, p.y);
    v.gx = 0.5 * (detail::sampleField(sdf, p.x + 1, p.y) - detail::sampleField(sdf, p.x - 1, p.y));
    v.gy = 0.5 * (detail::sampleField(sdf, p.x, p.y + 1) - detail::sampleField(sdf, p.x, p.y - 1));
    if (v.gx * s.normal.x + v.gy * s.normal.y < 0) v.trust = 0.1;
    const cv::Mat& known = targets[s.frame].known;
    if (!known.empty()) {
      const int x = static_cast<int>(std::lround(p.x)), y = static_cast<int>(std::lround(p.y));
      if (x < 0 || y < 0 || x >= known.cols || y >= known.rows || !known.at<unsigned char>(y, x)) v.trust = 0.0;
    }
    return v;
  };
}

// Pre-alignment, for a start far off (10 degrees is a robot's width in the image): the camera
// turned so the drawn robot's centroid lands on the mask's, and moved along its axis so their
// areas match, over all frames together. Rotation shows first as a shift of the whole image,
// distance as a change of size; the fit then starts where the outlines overlap.
Camera preAlign(const Camera& start, std::span<const MaskFrame> frames, const std::vector<Target>& targets,
                double spacing) {
  const std::vector<detail::FrameShape> volumes = shapesOf(frames);
  Camera cam = start;
  for (int round = 0; round < 6; ++round) {
    std::vector<cv::Mat> drawn;
    (void)detail::outlineSamples(cam, volumes, spacing, &drawn);
    double du = 0, dv = 0, drawn_area = 0, mask_area = 0;
    int used = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const cv::Moments a = cv::moments(targets[f].inKnown(drawn[f]), true),
                        b = cv::moments(targets[f].inKnown(targets[f].mask), true);
      if (a.m00 < 1 || b.m00 < 1) continue;
      du += b.m10 / b.m00 - a.m10 / a.m00;
      dv += b.m01 / b.m00 - a.m01 / a.m00;
      drawn_area += a.m00;
      mask_area += b.m00;
      ++used;
    }
    const double depth = detail::meanDepth(cam, volumes);
    if (used == 0 || depth <= 0) break;
    du /= used, dv /= used;
    // Size: the image of the robot's area grows with the square of its size.
    const double growth = std::clamp(std::sqrt(mask_area / drawn_area), 0.5, 2.0);
    cam = detail::turnedAndMoved(cam, du, dv, growth, depth);
    if (std::hypot(du, dv) < 0.5 && std::abs(growth - 1.0) < 1e-3) break;
  }
  return cam;
}

}  // namespace

cv::Mat readMask(const std::string& path, int width, int height, bool robot_and_background) {
  cv::Mat img;
  try {
    img = readImageFile(path, ImageColour::Unchanged);
  } catch (const ImageError& e) {
    throw MaskError(InputLocation{path, 0, 0, "mask"}, e.problem());
  }
  if (img.cols != width || img.rows != height)
    throw MaskError(InputLocation{path, 0, 0, "mask"}, std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                                                           ", but the camera's images are " + std::to_string(width) +
                                                           "x" + std::to_string(height));
  std::vector<cv::Mat> channels;
  cv::split(img, channels);
  cv::Mat mask = cv::Mat::zeros(img.size(), CV_8UC1);
  // With alpha: a cut-out (transparent background) is its alpha; an opaque image its colours.
  double alpha_min = 1.0;
  if (channels.size() == 4) cv::minMaxLoc(channels[3], &alpha_min);
  if (channels.size() == 4 && alpha_min == 0.0) {
    mask = channels[3] != 0;
  } else {
    for (std::size_t k = 0; k < std::min<std::size_t>(channels.size(), 3); ++k) mask |= (channels[k] != 0);
  }
  if (!robot_and_background) return mask;
  const int robot = cv::countNonZero(mask);
  if (robot == 0) throw MaskError(InputLocation{path, 0, 0, "mask"}, "no robot in it (every pixel is 0)");
  if (robot == width * height) throw MaskError(InputLocation{path, 0, 0, "mask"}, "nothing but robot (no pixel is 0)");
  return mask;
}

RefineResult refineToMasks(const Camera& start, std::span<const MaskFrame> frames, const RefineOptions& options) {
  if (frames.empty()) throw InputError("masks: no frame to refine the pose with");
  for (const MaskFrame& f : frames) {
    if (f.mask.cols != start.width || f.mask.rows != start.height || f.mask.type() != CV_8UC1)
      throw InputError("masks: a mask of " + std::to_string(f.mask.cols) + "x" + std::to_string(f.mask.rows) +
                       " for a camera of " + std::to_string(start.width) + "x" + std::to_string(start.height));
    if (!f.known.empty() && (f.known.size() != f.mask.size() || f.known.type() != CV_8UC1))
      throw InputError("masks: a known region that is not an 8-bit mask of the mask's size");
  }
  RefineResult result;
  result.camera = start;
  const std::vector<detail::FrameShape> shapes = shapesOf(frames);
  const auto samplesAt = [&](const Camera& at, std::vector<cv::Mat>* drawn = nullptr) {
    return detail::outlineSamples(at, shapes, options.spacing_px, drawn);
  };
  // Targets: each mask cleaned against the start's drawing.
  std::vector<cv::Mat> drawn_start;
  (void)samplesAt(start, &drawn_start);
  std::vector<Target> targets(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!frames[f].known.empty()) targets[f].known = frames[f].known != 0;
    targets[f].set(cleanMask(targets[f].inKnown(frames[f].mask != 0), drawn_start[f]));
  }
  result.frames.resize(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) result.frames[f].iou_before = targets[f].iou(drawn_start[f]);

  // Pre-aligned by centroid and size, the masks cleaned again against that drawing; kept only
  // if it overlaps the masks better than the start.
  Camera cam = preAlign(start, frames, targets, options.spacing_px);
  {
    std::vector<cv::Mat> drawn;
    (void)samplesAt(cam, &drawn);
    double before = 0, after = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      before += result.frames[f].iou_before;
      after += targets[f].iou(drawn[f]);
    }
    if (after > before) {
      for (std::size_t f = 0; f < frames.size(); ++f)
        targets[f].set(cleanMask(targets[f].inKnown(frames[f].mask != 0), drawn[f]));
    } else {
      cam = start;
    }
  }
  // Coarse to fine. Meshes are slower to draw, and their outline is traced on pixels: their
  // stages end at steps below 1e-5 (0.0006 deg, 0.01 mm) or gains below 1e-4 of the cost.
  const double diagonal = std::hypot(start.width, start.height);
  std::vector<double> scales;
  for (const double scale : {0.08, 0.03, 0.01, 0.004}) scales.push_back(std::max(1.5, scale * diagonal));
  const detail::Field field = maskField(targets);
  const bool meshes = std::any_of(frames.begin(), frames.end(), [](const MaskFrame& f) { return !f.meshes.empty(); });
  cam = detail::fitPose(
      cam, [&](const Camera& at) { return samplesAt(at); }, field, scales, options.max_iterations, result.iterations,
      nullptr, meshes ? 1e-5 : 1e-7, meshes ? 1e-4 : 0.0);

  // Agreement at the result, and whether it is kept.
  std::vector<cv::Mat> drawn_after;
  const std::vector<detail::OutlineSample> final_samples = samplesAt(cam, &drawn_after);
  double before = 0.0, after = 0.0, worst_drop = 0.0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    FrameAgreement& a = result.frames[f];
    a.iou_after = targets[f].iou(drawn_after[f]);
    before += a.iou_before;
    after += a.iou_after;
    worst_drop = std::max(worst_drop, a.iou_before - a.iou_after);
  }
  before /= static_cast<double>(frames.size());
  after /= static_cast<double>(frames.size());
  const double c_final = std::max(1.5, 0.004 * diagonal);
  const detail::Evaluation e = detail::evaluate(cam, cam.rvec, cam.tvec, final_samples, field, c_final, true);
  // Each frame's outline rms and point count at `at` (the refined pose, or the start when kept).
  const auto outlineAgreement = [&](const Camera& at, const std::vector<detail::OutlineSample>& samples) {
    for (std::size_t f = 0; f < frames.size(); ++f) {
      std::vector<detail::OutlineSample> mine;
      for (const detail::OutlineSample& s : samples)
        if (s.frame == f) mine.push_back(s);
      const detail::Evaluation ef = detail::evaluate(at, at.rvec, at.tvec, mine, field, c_final, false);
      result.frames[f].outline_points = static_cast<int>(mine.size());
      result.frames[f].rms_px = ef.weight_sum > 0 ? std::sqrt(ef.weighted_sq / ef.weight_sum) : 0.0;
    }
  };
  outlineAgreement(cam, final_samples);
  // The start is returned: its figures, not the refined pose's.
  const auto keepStart = [&](std::string message) {
    for (FrameAgreement& a : result.frames) a.iou_after = a.iou_before;
    outlineAgreement(start, samplesAt(start));
    result.covariance = cv::Matx66d::zeros();
    result.message = std::move(message);
    return result;
  };
  if (final_samples.size() < 12)
    return keepStart("the drawn robot's outline is not in the images (" + std::to_string(final_samples.size()) +
                     " points): the start is kept");
  if (!(after > before + 1e-4) || worst_drop > options.max_frame_drop)
    return keepStart("the masks did not improve the pose (mean IoU " + formatNumber(before, 4) + " at the start, " +
                     formatNumber(after, 4) + " refined" +
                     (worst_drop > options.max_frame_drop ? ", one frame " + formatNumber(worst_drop, 3) + " worse"
                                                          : std::string()) +
                     "): the start is kept");
  // A start with known uncertainty is a strong prior: a refined pose far outside it (3 sigma) for a
  // small gain in agreement says the masks and the volumes differ (a robot thinner than its
  // volumes, masks that are too wide), not that the start was wrong.
  if (const std::optional<detail::FromStart> d = detail::fromStart(cam, start); options.start_is_prior && d) {
    const double gain = after - before;
    if (d->sigmas > 3.0 && gain < 0.02)
      return keepStart("the masks' best pose lies " + formatNumber(d->difference.rotation_deg, 3) + " deg and " +
                       formatNumber(d->difference.position_m * 1000, 3) + " mm from the start (" +
                       formatNumber(d->sigmas, 3) + " sigma) for a mean IoU gain of " + formatNumber(gain, 3) +
                       ": the start is kept (are the volumes wider or the masks narrower than the robot?)");
  }
  result.covariance = detail::poseCovariance(e);
  const auto [rotation_sigma, position_sigma] = poseSigmas(cam.rvec, cam.tvec, result.covariance);
  cam.rotation_sigma_deg = rotation_sigma;
  cam.position_sigma_m = position_sigma;
  if (after < options.min_iou || !(*cam.rotation_sigma_deg <= options.max_rotation_sigma_deg))
    return keepStart("the drawn robot and the masks agree too little (mean IoU " + formatNumber(after, 3) +
                     ", at least " + formatNumber(options.min_iou, 3) + " needed; rotation +-" +
                     formatNumber(*cam.rotation_sigma_deg, 3) +
                     " deg): check each frame's state, the clock, and which bodies the masks show (--mask-bodies); the "
                     "start is kept");
  result.camera = cam;
  result.improved = true;
  result.message = "refined to the masks: mean IoU " + formatNumber(before, 4) + " -> " + formatNumber(after, 4) +
                   " over " + std::to_string(frames.size()) + " frame(s), rotation +-" +
                   formatNumber(*cam.rotation_sigma_deg, 3) + " deg, position +-" +
                   formatNumber(*cam.position_sigma_m, 3) + " m";
  return result;
}

}  // namespace kccd::calib
