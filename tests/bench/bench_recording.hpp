// What the recording benchmarks share (bench_overlay, bench_bag): the sample camera placed to see
// the humanoid, a textured 1280x720 frame (the codecs do real work), a state log of slow sinusoids.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"

namespace kccd::bench {

/// The sample camera's lens, placed 4.6 m from the humanoid so that all of it is in view.
inline calib::Camera benchCamera() {
  calib::Camera c = calib::loadCamera(std::string(KCCD_DATA_DIR) + "/demo_camera.yaml");
  const cv::Vec3d eye(3.6, -2.6, 1.7), target(0.1, 0.0, 1.0), up(0, 0, 1);
  const cv::Vec3d z = cv::normalize(target - eye);
  const cv::Vec3d x = cv::normalize(z.cross(up));
  const cv::Vec3d y = z.cross(x);
  const cv::Matx33d r(x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1], z[2]);
  cv::Mat rvec;
  cv::Rodrigues(cv::Mat(r), rvec);
  c.rvec = cv::Vec3d(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  c.tvec = -(r * eye);
  return c;
}

/// Frame i of the benchmark recordings: moving gradients with uniform noise from `rng`.
inline cv::Mat texturedFrame(int i, cv::RNG& rng) {
  cv::Mat f(720, 1280, CV_8UC3), noise(720, 1280, CV_8UC3);
  for (int y = 0; y < 720; ++y) {
    cv::Vec3b* row = f.ptr<cv::Vec3b>(y);
    for (int x = 0; x < 1280; ++x) row[x] = cv::Vec3b(uchar((x + 3 * i) / 5), uchar(y / 3), uchar((x + y + 5 * i) / 8));
  }
  rng.fill(noise, cv::RNG::UNIFORM, 0, 24);
  return f + noise;
}

/// A state log of `m` at `rate` Hz over `seconds`: slow sinusoids within the joint limits (times
/// written exactly: k / rate with the decimals of the rate's period).
inline void makeLog(const std::string& path, const Model& m, double seconds, int rate = 100) {
  std::ofstream out(path);
  out << "time";
  for (const std::string& n : m.stateNames()) out << "," << n;
  out << "\n";
  char buf[64];
  for (int k = 0; k <= static_cast<int>(seconds * rate) + 1; ++k) {
    const double t = static_cast<double>(k) / rate;
    std::snprintf(buf, sizeof buf, "%.*f", rate > 100 ? 3 : 2, t);
    out << buf;
    for (std::size_t j = 0; j < m.joints.size(); ++j) {
      const auto& joint = m.joints[j];
      const std::array<double, 2> lim = joint.limits.value_or(std::array<double, 2>{-1.0, 1.0});
      const double mid = 0.5 * (lim[0] + lim[1]), amp = 0.35 * (lim[1] - lim[0]);
      std::snprintf(buf, sizeof buf, ",%.6f", mid + amp * std::sin(0.8 * t + 0.7 * static_cast<double>(j)));
      out << buf;
    }
    out << "\n";
  }
}

}  // namespace kccd::bench
