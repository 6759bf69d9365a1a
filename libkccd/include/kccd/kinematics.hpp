// Forward kinematics at one configuration: where every joint frame is. For drawing and
// calibration; the safety checks themselves work on intervals (Checker).
#pragma once

#include <span>

#include "kccd/model.hpp"

namespace kccd {

/// The motion of one joint in its own frame at its state values `q` (joint.dof of them): the
/// pose its child frame has in the joint frame. Never allocates.
Pose jointMotion(const Joint& joint, const double* q) noexcept;

/// The pose of every joint frame in the world at `state` (error bounds not applied): frame j's
/// coordinates map to world coordinates by poses[j]. Returns false, leaving `poses` unspecified,
/// when `state` or `poses` has the wrong length or a state value is not finite. Never allocates.
bool framePoses(const Model& model, std::span<const double> state, std::span<Pose> poses) noexcept;

/// The world pose of a frame given the frame poses (identity for the world frame).
inline const Pose& framePose(std::span<const Pose> poses, int frame) {
  static const Pose identity = Pose::Identity();
  return frame == kWorld ? identity : poses[static_cast<std::size_t>(frame)];
}

/// True when joint `frame` or one of its ancestors has an error bound (translation3d /
/// rotation3d with error > 0): volumes below it grow even at a single configuration.
bool hasErrorBound(const Model& model, int frame) noexcept;

}  // namespace kccd
