#include "kccd/calib/pose_difference.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>

namespace kccd::calib {

cv::Vec3d cameraCentre(const Camera& camera) {
  cv::Matx33d rot;
  cv::Rodrigues(camera.rvec, rot);
  return -(rot.t() * camera.tvec);
}

PoseDifference poseDifference(const Camera& a, const Camera& b) {
  cv::Matx33d ra, rb;
  cv::Rodrigues(a.rvec, ra);
  cv::Rodrigues(b.rvec, rb);
  // The angle from both the sine (the skew part) and the cosine (the trace): exact near 0 and 180 deg.
  const cv::Matx33d d = ra * rb.t();
  const double sine = 0.5 * std::hypot(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  const double angle = std::atan2(sine, 0.5 * (d(0, 0) + d(1, 1) + d(2, 2) - 1.0)) * 180.0 / CV_PI;
  const cv::Vec3d ca = -(ra.t() * a.tvec), cb = -(rb.t() * b.tvec);
  return {angle, cv::norm(ca - cb)};
}

}  // namespace kccd::calib
