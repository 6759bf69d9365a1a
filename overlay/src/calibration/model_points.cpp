#include "kccd/overlay/calibration/model_points.hpp"

#include "kccd/kinematics.hpp"

namespace kccd::overlay {

std::vector<ModelPoint> modelPoints(const Model& model, std::span<const double> state) {
  std::vector<Pose> poses(model.joints.size());
  std::vector<ModelPoint> out;
  if (!framePoses(model, state, poses)) return out;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    for (std::size_t k = 0; k < body.points.size(); ++k) {
      const Vec3 p = framePose(poses, body.frame) * body.points[k];
      out.push_back({body.name + "." + std::to_string(k), static_cast<int>(b), static_cast<int>(k),
                     cv::Point3d(p.x(), p.y(), p.z())});
    }
  }
  return out;
}

std::vector<cv::Point3d> worldPoints(const std::vector<ModelPoint>& points) {
  std::vector<cv::Point3d> out;
  out.reserve(points.size());
  for (const ModelPoint& p : points) out.push_back(p.world);
  return out;
}

}  // namespace kccd::overlay
