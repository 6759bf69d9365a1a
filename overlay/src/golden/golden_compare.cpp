#include "kccd/overlay/golden/golden_compare.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

#include <opencv2/imgproc.hpp>

#include "kccd/format_number.hpp"

namespace kccd::overlay {
namespace {

std::string sizeText(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }

// The clusters of `changed`: their count of pixels, the largest and its box.
void measureClusters(Comparison& c) {
  c.changed_px = cv::countNonZero(c.changed);
  if (c.changed_px == 0) return;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(c.changed, labels, stats, centroids, 8, CV_32S);
  for (int k = 1; k < n; ++k) {
    const int area = stats.at<int>(k, cv::CC_STAT_AREA);
    if (area > c.largest_cluster_px) {
      c.largest_cluster_px = area;
      c.largest_cluster = cv::Rect(stats.at<int>(k, cv::CC_STAT_LEFT), stats.at<int>(k, cv::CC_STAT_TOP),
                                   stats.at<int>(k, cv::CC_STAT_WIDTH), stats.at<int>(k, cv::CC_STAT_HEIGHT));
    }
  }
}

std::string clusterText(const Comparison& c) {
  return "largest cluster of changed pixels " + std::to_string(c.largest_cluster_px) + " px at (" +
         std::to_string(c.largest_cluster.x) + ", " + std::to_string(c.largest_cluster.y) + ")";
}

struct Moments {
  double n = 0, x = 0, y = 0;
};

}  // namespace

Comparison compareMasks(const cv::Mat& expected, const std::vector<std::string>& expected_names, const cv::Mat& actual,
                        const std::vector<std::string>& actual_names, const MaskTolerance& tolerance) {
  Comparison c;
  if (expected.size() != actual.size() || expected.type() != CV_8UC1 || actual.type() != CV_8UC1) {
    c.reason = "size: the golden is " + sizeText(expected) + ", the image " + sizeText(actual);
    return c;
  }
  const std::set<std::string> want(expected_names.begin(), expected_names.end()),
      got(actual_names.begin(), actual_names.end());
  if (want != got) {
    std::string missing, added;
    for (const std::string& n : want)
      if (!got.count(n)) missing += (missing.empty() ? "'" : ", '") + n + "'";
    for (const std::string& n : got)
      if (!want.count(n)) added += (added.empty() ? "'" : ", '") + n + "'";
    c.reason = "bodies:" + (missing.empty() ? std::string() : " missing " + missing) +
               (added.empty() ? std::string() : " new " + added);
    return c;
  }
  // The actual labels in the golden's numbering.
  std::array<std::uint8_t, 256> lut{};
  std::map<std::string, int> index;
  for (std::size_t k = 0; k < expected_names.size() && k < 255; ++k) index[expected_names[k]] = static_cast<int>(k) + 1;
  for (std::size_t k = 0; k < actual_names.size() && k < 255; ++k)
    lut[k + 1] = static_cast<std::uint8_t>(index[actual_names[k]]);
  cv::Mat renumbered;
  cv::LUT(actual, cv::Mat(1, 256, CV_8UC1, lut.data()), renumbered);
  cv::compare(renumbered, expected, c.changed, cv::CMP_NE);
  measureClusters(c);

  // Per body: pixels, centroid and the golden's boundary.
  const std::size_t n = expected_names.size() + 1;
  std::vector<Moments> e(n), a(n);
  std::vector<int> boundary(n, 0);
  for (int y = 0; y < expected.rows; ++y) {
    const std::uint8_t* pe = expected.ptr<std::uint8_t>(y);
    const std::uint8_t* pa = renumbered.ptr<std::uint8_t>(y);
    const std::uint8_t* up = y > 0 ? expected.ptr<std::uint8_t>(y - 1) : nullptr;
    const std::uint8_t* down = y + 1 < expected.rows ? expected.ptr<std::uint8_t>(y + 1) : nullptr;
    for (int x = 0; x < expected.cols; ++x) {
      const std::size_t le = pe[x], la = pa[x];
      if (le < n && le) {
        e[le].n += 1, e[le].x += x, e[le].y += y;
        const bool edge = (x > 0 && pe[x - 1] != le) || (x + 1 < expected.cols && pe[x + 1] != le) ||
                          (up && up[x] != le) || (down && down[x] != le);
        boundary[le] += edge;
      }
      if (la < n && la) a[la].n += 1, a[la].x += x, a[la].y += y;
    }
  }
  std::string body_failure;
  for (std::size_t k = 1; k < n; ++k) {
    BodyChange b;
    b.name = expected_names[k - 1];
    b.expected_px = static_cast<int>(e[k].n);
    b.actual_px = static_cast<int>(a[k].n);
    b.boundary_px = boundary[k];
    b.allowed_area_change_px = std::max(1.0, tolerance.max_area_change_per_boundary_px * boundary[k]);
    if (e[k].n > 0 && a[k].n > 0)
      b.centroid_shift_px = std::hypot(a[k].x / a[k].n - e[k].x / e[k].n, a[k].y / a[k].n - e[k].y / e[k].n);
    const double area_change = std::abs(a[k].n - e[k].n);
    const double ratio = area_change / b.allowed_area_change_px;
    c.worst_centroid_shift_px = std::max(c.worst_centroid_shift_px, b.centroid_shift_px);
    c.worst_area_change_ratio = std::max(c.worst_area_change_ratio, ratio);
    if (body_failure.empty() && b.centroid_shift_px > tolerance.max_centroid_shift_px)
      body_failure = "body '" + b.name + "': centroid moved " + formatNumber(b.centroid_shift_px, 3) + " px (allowed " +
                     formatNumber(tolerance.max_centroid_shift_px, 3) + ")";
    if (body_failure.empty() && area_change > b.allowed_area_change_px)
      body_failure = "body '" + b.name + "': area changed by " + std::to_string(static_cast<long>(area_change)) +
                     " px (allowed " + formatNumber(b.allowed_area_change_px, 3) + ": " +
                     formatNumber(tolerance.max_area_change_per_boundary_px, 3) + " px per boundary pixel, " +
                     std::to_string(b.boundary_px) + ")";
    c.bodies.push_back(std::move(b));
  }
  if (c.changed_px == 0) {
    c.passed = c.identical = true;
    return c;
  }
  if (c.largest_cluster_px > tolerance.max_cluster_px) {
    c.reason = clusterText(c) + " (allowed " + std::to_string(tolerance.max_cluster_px) + ")";
  } else if (!body_failure.empty()) {
    c.reason = body_failure;
  } else {
    c.passed = true;
    c.reason = "forgiven: " + std::to_string(c.changed_px) + " isolated pixel(s) changed (largest cluster " +
               std::to_string(c.largest_cluster_px) + " px, centroids within " +
               formatNumber(c.worst_centroid_shift_px, 3) + " px)";
  }
  return c;
}

Comparison compareColour(const cv::Mat& expected, const cv::Mat& actual, const ColourTolerance& tolerance) {
  Comparison c;
  if (expected.size() != actual.size() || expected.type() != actual.type() || expected.depth() != CV_8U) {
    c.reason = "size: the golden is " + sizeText(expected) + " with " + std::to_string(expected.channels()) +
               " channel(s), the image " + sizeText(actual) + " with " + std::to_string(actual.channels());
    return c;
  }
  cv::Mat diff;
  cv::absdiff(expected, actual, diff);
  cv::Mat largest = diff.reshape(1, diff.rows * diff.cols);
  cv::reduce(largest, largest, 1, cv::REDUCE_MAX);
  largest = largest.reshape(1, diff.rows);
  if (cv::countNonZero(largest) == 0) {
    c.passed = c.identical = true;
    c.changed = cv::Mat::zeros(expected.size(), CV_8UC1);
    return c;
  }
  cv::compare(largest, tolerance.channel_threshold, c.changed, cv::CMP_GT);
  measureClusters(c);
  if (c.largest_cluster_px > tolerance.max_cluster_px) {
    c.reason = clusterText(c) + " (allowed " + std::to_string(tolerance.max_cluster_px) +
               "; a pixel changes when a channel moves by more than " + std::to_string(tolerance.channel_threshold) +
               " grey levels)";
  } else if (c.changed_px > tolerance.max_diff_px) {
    c.reason = std::to_string(c.changed_px) + " changed pixels (allowed " + std::to_string(tolerance.max_diff_px) + ")";
  } else {
    c.passed = true;
    c.reason = "forgiven: " + std::to_string(c.changed_px) + " pixel(s) beyond " +
               std::to_string(tolerance.channel_threshold) + " grey levels (largest cluster " +
               std::to_string(c.largest_cluster_px) + " px)";
  }
  return c;
}

cv::Mat falseColour(const cv::Mat& mask) {
  // Golden-angle hues: neighbouring labels far apart; background black.
  cv::Mat hsv(1, 256, CV_8UC3), lut;
  for (int l = 0; l < 256; ++l)
    hsv.at<cv::Vec3b>(0, l) = cv::Vec3b(static_cast<std::uint8_t>(std::fmod(l * 137.508, 360.0) / 2), 200, l ? 230 : 0);
  cv::cvtColor(hsv, lut, cv::COLOR_HSV2BGR);
  cv::Mat three, out;
  cv::cvtColor(mask, three, cv::COLOR_GRAY2BGR);
  cv::LUT(three, lut, out);
  return out;
}

cv::Mat picture(const cv::Mat& image, bool mask) {
  if (mask) return falseColour(image);
  cv::Mat out;
  if (image.channels() == 1)
    cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4) {
    // Over a checkerboard, so transparency shows.
    out.create(image.size(), CV_8UC3);
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) {
        const cv::Vec4b p = image.at<cv::Vec4b>(y, x);
        const double bg = ((x / 8 + y / 8) % 2) ? 90 : 140, al = p[3] / 255.0;
        for (int k = 0; k < 3; ++k)
          out.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<std::uint8_t>(p[k] * al + bg * (1 - al));
      }
  } else
    out = image.clone();
  return out;
}

cv::Mat diffPicture(const cv::Mat& expected, const cv::Mat& actual, const Comparison& comparison, bool masks) {
  if (comparison.changed.empty()) return picture(actual, masks);
  cv::Mat grey, out;
  cv::cvtColor(picture(expected, masks), grey, cv::COLOR_BGR2GRAY);
  grey = grey / 3 + 40;
  cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
  out.setTo(cv::Scalar(40, 40, 255), comparison.changed);
  return out;
}

cv::Mat magnifiedCrop(const cv::Mat& image, const cv::Rect& box, int scale) {
  if (box.empty() || image.empty()) return {};
  const int side = std::max({24, box.width + 8, box.height + 8});
  cv::Rect r(box.x + box.width / 2 - side / 2, box.y + box.height / 2 - side / 2, side, side);
  r &= cv::Rect(0, 0, image.cols, image.rows);
  cv::Mat out;
  cv::resize(image(r), out, cv::Size(), scale, scale, cv::INTER_NEAREST);
  return out;
}

}  // namespace kccd::overlay
