#include "kccd/kinematics.hpp"

#include <cmath>

#include "kccd/rotation.hpp"

namespace kccd {

Pose jointMotion(const Joint& joint, const double* q) noexcept {
  Pose motion = Pose::Identity();
  switch (joint.type) {
    case JointType::Fixed:
      break;
    case JointType::Revolute:
      motion.linear() = Eigen::AngleAxisd(q[0], joint.axis).toRotationMatrix();
      break;
    case JointType::Prismatic:
      motion.translation() = q[0] * joint.axis;
      break;
    case JointType::Translation3d:
      motion.translation() = Vec3(q[0], q[1], q[2]);
      break;
    case JointType::Rotation3d:
      motion.linear() = rotationFromVector(Vec3(q[0], q[1], q[2]));
      break;
  }
  return motion;
}

bool framePoses(const Model& model, std::span<const double> state, std::span<Pose> poses) noexcept {
  if (static_cast<int>(state.size()) != model.stateSize() || poses.size() != model.joints.size()) return false;
  for (double v : state)
    if (!std::isfinite(v)) return false;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const Pose& parent = framePose(poses, joint.parent);
    poses[j] = parent * joint.origin * jointMotion(joint, state.data() + joint.state_offset);
  }
  return true;
}

bool hasErrorBound(const Model& model, int frame) noexcept {
  for (int f = frame; f != kWorld; f = model.joints[static_cast<std::size_t>(f)].parent)
    if (model.joints[static_cast<std::size_t>(f)].error > 0.0) return true;
  return false;
}

}  // namespace kccd
