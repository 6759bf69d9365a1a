#include "outline_fit.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

namespace kccd::calib::detail {

std::vector<OutlineSample> outlineSamples(const Camera& camera, std::span<const FrameShape> frames, double spacing,
                                          std::vector<cv::Mat>* drawn) {
  std::vector<OutlineSample> out;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const Silhouette s = frames[f].meshes.empty() ? drawSilhouette(camera, frames[f].volumes, spacing)
                                                  : drawMeshSilhouette(camera, frames[f].meshes, spacing);
    if (drawn) drawn->push_back(s.mask);
    for (const OutlinePoint& p : s.outline)
      if (p.pixel.x >= 2 && p.pixel.y >= 2 && p.pixel.x <= camera.width - 3 && p.pixel.y <= camera.height - 3)
        out.push_back({f, cv::Point3d(p.world.x(), p.world.y(), p.world.z()), p.normal});
  }
  return out;
}

Camera turnedAndMoved(const Camera& cam, double du, double dv, double growth, double depth) {
  Camera out = cam;
  // A turn about the camera's y and x axes moves the image by fx * angle, fy * angle.
  const cv::Vec3d turn(-std::atan(dv / cam.camera_matrix(1, 1)), std::atan(du / cam.camera_matrix(0, 0)), 0.0);
  cv::Matx33d d, r;
  cv::Rodrigues(turn, d);
  cv::Rodrigues(cam.rvec, r);
  cv::Rodrigues(d * r, out.rvec);
  out.tvec = d * cam.tvec;
  // The image of a thing scales with 1 / depth.
  out.tvec[2] += depth * (1.0 / growth - 1.0);
  return out;
}

double meanDepth(const Camera& cam, std::span<const FrameShape> frames) {
  const Pose w2c = cam.worldToCamera();
  double depth = 0.0;
  int n = 0;
  for (const FrameShape& f : frames)
    for (const PlacedVolume& v : f.volumes)
      for (const Vec3& p : v.points)
        if (const double z = (w2c * p).z(); z > 0) depth += z, ++n;
  return n ? depth / n : 0.0;
}

double sampleField(const cv::Mat& f, double x, double y) {
  x = std::clamp(x, 0.0, f.cols - 1.001);
  y = std::clamp(y, 0.0, f.rows - 1.001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double ax = x - x0, ay = y - y0;
  const float* r0 = f.ptr<float>(y0);
  const float* r1 = f.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

Evaluation evaluate(const Camera& cam, const cv::Vec3d& rvec, const cv::Vec3d& tvec,
                    std::span<const OutlineSample> samples, const Field& field, double c, bool normal_equations,
                    const Anchors* anchors) {
  Evaluation e;
  if (anchors && !anchors->world.empty()) {
    std::vector<cv::Point2d> px;
    cv::Mat jac;
    cv::projectPoints(anchors->world, rvec, tvec, cam.camera_matrix, cam.distortion, px,
                      normal_equations ? jac : cv::noArray());
    const double a = anchors->scale_px;
    for (std::size_t i = 0; i < px.size(); ++i)
      for (int k = 0; k < 2; ++k) {
        const double r = k == 0 ? px[i].x - anchors->pixel[i].x : px[i].y - anchors->pixel[i].y;
        const double u = r / a, w = 1.0 / (1.0 + u * u);
        e.cost += 0.5 * a * a * std::log1p(u * u);
        if (!normal_equations) continue;
        cv::Vec6d j;
        for (int m = 0; m < 6; ++m) j[m] = jac.at<double>(static_cast<int>(2 * i) + k, m);
        e.jtj += w * (j * j.t());
        e.jtr += w * r * j;
      }
  }
  if (samples.empty()) return e;
  std::vector<cv::Point3d> world(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) world[i] = samples[i].world;
  std::vector<cv::Point2d> px;
  cv::Mat jac;
  cv::projectPoints(world, rvec, tvec, cam.camera_matrix, cam.distortion, px, normal_equations ? jac : cv::noArray());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const FieldValue v = field(samples[i], px[i]);
    const double u = v.r / c;
    const double w = v.trust / (1.0 + u * u);
    e.cost += v.trust * 0.5 * c * c * std::log1p(u * u);
    e.weight_sum += w;
    e.weighted_sq += w * v.r * v.r;
    if (!normal_equations) continue;
    cv::Vec6d j;
    for (int k = 0; k < 6; ++k)
      j[k] = v.gx * jac.at<double>(static_cast<int>(2 * i), k) + v.gy * jac.at<double>(static_cast<int>(2 * i + 1), k);
    e.jtj += w * (j * j.t());
    e.jtr += w * v.r * j;
  }
  return e;
}

Camera fitPose(Camera cam, const std::function<std::vector<OutlineSample>(const Camera&)>& samples_at,
               const Field& field, std::span<const double> scales_px, int max_iterations, int& iterations,
               const Anchors* anchors, double tiny, double min_gain) {
  for (const double c : scales_px) {
    double lambda = 1e-3;
    for (int it = 0; it < max_iterations; ++it) {
      const std::vector<OutlineSample> samples = samples_at(cam);
      if (samples.size() < 12) break;
      const Evaluation e = evaluate(cam, cam.rvec, cam.tvec, samples, field, c, true, anchors);
      bool stepped = false;
      while (lambda < 1e8) {
        cv::Matx66d a = e.jtj;
        for (int k = 0; k < 6; ++k) a(k, k) += lambda * std::max(e.jtj(k, k), 1e-12);
        cv::Vec6d delta;
        if (!cv::solve(a, -e.jtr, delta, cv::DECOMP_CHOLESKY)) {
          lambda *= 10;
          continue;
        }
        const cv::Vec3d r2 = cam.rvec + cv::Vec3d(delta[0], delta[1], delta[2]);
        const cv::Vec3d t2 = cam.tvec + cv::Vec3d(delta[3], delta[4], delta[5]);
        if (const double cost = evaluate(cam, r2, t2, samples, field, c, false, anchors).cost; cost < e.cost) {
          cam.rvec = r2, cam.tvec = t2;
          lambda = std::max(1e-7, lambda / 3);
          stepped = cv::norm(delta) > tiny && e.cost - cost > min_gain * e.cost;
          break;
        }
        lambda *= 4;
      }
      ++iterations;
      if (!stepped) break;
    }
  }
  return cam;
}

std::optional<FromStart> fromStart(const Camera& cam, const Camera& start) {
  if (!start.rotation_sigma_deg || !start.position_sigma_m) return std::nullopt;
  const PoseDifference d = poseDifference(cam, start);
  return FromStart{d, std::max(d.rotation_deg / std::max(*start.rotation_sigma_deg, 1e-9),
                               d.position_m / std::max(*start.position_sigma_m, 1e-12))};
}

cv::Matx66d poseCovariance(const Evaluation& e) {
  const double dof = std::max(1.0, e.weight_sum - 6.0);
  const double sigma2 = e.weighted_sq / dof * 5.0;
  cv::Matx66d inv;
  cv::invert(e.jtj, inv, cv::DECOMP_SVD);
  return sigma2 * inv;
}

}  // namespace kccd::calib::detail
