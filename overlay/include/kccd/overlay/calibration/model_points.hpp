// The model's core points placed in the world at one state, named as labels and reports name
// them ("gripper.3"): what calibration projects to judge a pose and offers for labelling.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/model.hpp"

namespace kccd::overlay {

/// One core point of a body, placed in the world.
struct ModelPoint {
  std::string name;   ///< "<body name>.<k>"
  int body = 0;       ///< index into Model::bodies
  int point = 0;      ///< k: index into that body's points
  cv::Point3d world;  ///< metres
};

/// Every body's core points (bodies in model order, each body's points in order) placed by forward
/// kinematics at `state`; none when the state cannot place the frames (wrong size, not finite).
std::vector<ModelPoint> modelPoints(const Model& model, std::span<const double> state);

/// The world points of modelPoints(), in the same order.
std::vector<cv::Point3d> worldPoints(const std::vector<ModelPoint>& points);

}  // namespace kccd::overlay
