#include "kccd/calib/background.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

namespace kccd::calib {
namespace {

void checkSample(const BackgroundSample& s, const cv::Size& size, const std::string& what) {
  if (s.bgr.type() != CV_8UC3 || s.bgr.size() != size)
    throw InputError(what + ": a picture of " + std::to_string(s.bgr.cols) + "x" + std::to_string(s.bgr.rows) +
                     (s.bgr.type() == CV_8UC3 ? std::string() : " that is not 8-bit colour") + " among pictures of " +
                     std::to_string(size.width) + "x" + std::to_string(size.height));
  if (s.robot.type() != CV_8UC1 || s.robot.size() != size)
    throw InputError(what + ": a robot region that is not an 8-bit mask of its picture's size");
}

// The median of the first n values (reordered).
template <typename T>
T medianOf(T* v, int n) {
  std::nth_element(v, v + n / 2, v + n);
  return v[n / 2];
}

}  // namespace

Background estimateBackground(std::span<const BackgroundSample> samples, int min_samples) {
  if (samples.empty()) throw InputError("background: no frame to estimate it from");
  const cv::Size size = samples.front().bgr.size();
  for (const BackgroundSample& s : samples) checkSample(s, size, "background");
  const int n = static_cast<int>(samples.size());
  min_samples = std::max(1, min_samples);
  Background out;
  out.samples = n;
  out.bgr = cv::Mat::zeros(size, CV_8UC3);
  out.spread = cv::Mat::zeros(size, CV_32F);
  out.known = cv::Mat::zeros(size, CV_8UC1);
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<std::array<unsigned char, 3>> free(static_cast<std::size_t>(n));
    std::vector<unsigned char> channel(static_cast<std::size_t>(n));
    std::vector<int> distance(static_cast<std::size_t>(n));
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < size.width; ++x) {
        int m = 0;
        for (const BackgroundSample& s : samples) {
          if (s.robot.at<unsigned char>(y, x)) continue;
          const cv::Vec3b& c = s.bgr.at<cv::Vec3b>(y, x);
          free[static_cast<std::size_t>(m++)] = {c[0], c[1], c[2]};
        }
        if (m < min_samples) continue;
        cv::Vec3b median;
        for (int k = 0; k < 3; ++k) {
          for (int i = 0; i < m; ++i)
            channel[static_cast<std::size_t>(i)] = free[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
          median[k] = medianOf(channel.data(), m);
        }
        for (int i = 0; i < m; ++i) {
          const auto& c = free[static_cast<std::size_t>(i)];
          distance[static_cast<std::size_t>(i)] =
              std::abs(c[0] - median[0]) + std::abs(c[1] - median[1]) + std::abs(c[2] - median[2]);
        }
        out.bgr.at<cv::Vec3b>(y, x) = median;
        out.spread.at<float>(y, x) = static_cast<float>(1.4826 * medianOf(distance.data(), m));
        out.known.at<unsigned char>(y, x) = 255;
      }
  });
  return out;
}

cv::Mat robotRegion(const Camera& camera, std::span<const PlacedVolume> volumes, double widen_px) {
  const cv::Mat drawn = drawSilhouette(camera, volumes).mask;
  cv::Mat away;
  cv::distanceTransform(drawn == 0, away, cv::DIST_L2, cv::DIST_MASK_3);
  return away <= static_cast<float>(widen_px);
}

cv::Mat foregroundMask(const BackgroundSample& frame, const Background& background, const ForegroundOptions& options) {
  const cv::Size size = background.bgr.size();
  checkSample(frame, size, "foreground");
  // The frame's brightness against the background's, where both show the scene: a camera's
  // automatic exposure changes everything by about one gain.
  std::vector<float> ratios;
  for (int y = 0; y < size.height; y += 3)
    for (int x = 0; x < size.width; x += 3) {
      if (!background.known.at<unsigned char>(y, x) || frame.robot.at<unsigned char>(y, x)) continue;
      const cv::Vec3b& b = background.bgr.at<cv::Vec3b>(y, x);
      const cv::Vec3b& f = frame.bgr.at<cv::Vec3b>(y, x);
      const int sb = b[0] + b[1] + b[2], sf = f[0] + f[1] + f[2];
      if (sb >= 60) ratios.push_back(static_cast<float>(sf) / static_cast<float>(sb));
    }
  double gain = 1.0;
  if (ratios.size() >= 100)
    gain = std::clamp(static_cast<double>(medianOf(ratios.data(), static_cast<int>(ratios.size()))), 0.5, 2.0);
  cv::Mat mask = cv::Mat::zeros(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      if (!background.known.at<unsigned char>(y, x)) continue;
      const cv::Vec3b& b = background.bgr.at<cv::Vec3b>(y, x);
      const cv::Vec3b& f = frame.bgr.at<cv::Vec3b>(y, x);
      double d = 0.0;
      for (int k = 0; k < 3; ++k) d += std::abs(f[k] - gain * b[k]);
      const double limit = std::max(options.min_difference, options.spread_factor * background.spread.at<float>(y, x));
      if (d > limit) mask.at<unsigned char>(y, x) = 255;
    }
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  mask &= background.known;
  return mask;
}

}  // namespace kccd::calib
