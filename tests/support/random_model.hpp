// Random kinematic trees, volumes and interval boxes for the conservativeness property tests,
// plus forward kinematics written independently of libkccd.
#pragma once

#include <random>
#include <vector>

#include "kccd/model.hpp"

namespace kccd::testing {

/// A random model: 1..max_joints joints of every type and sweep mode, 2..max_bodies bodies.
Model randomModel(std::mt19937_64& rng, int max_joints = 5, int max_bodies = 4);

/// A random interval box for the model: widths from 0 through 1e-12 and tiny up to beyond 2*pi.
/// Joints with `sweep: exact` get zero-width intervals.
void randomBox(std::mt19937_64& rng, const Model& m, std::vector<double>& lower, std::vector<double>& upper);

/// One configuration drawn from the box, with a realisation of every joint's error bound.
struct Sample {
  std::vector<double> q;
  std::vector<Vec3> translation_error;   // per joint (translation3d)
  std::vector<Eigen::Matrix3d> rotation_error;  // per joint (rotation3d)
  std::vector<bool> error_first;          // rotation3d: apply the error before the measured rotation
};

/// Corners, edge points and uniform points of the box; errors on their bound's surface or inside.
Sample sampleBox(std::mt19937_64& rng, const Model& m, const std::vector<double>& lower,
                 const std::vector<double>& upper, int kind);

/// World pose of every joint frame for a sample (independent forward kinematics).
std::vector<Pose> jointPoses(const Model& m, const Sample& s);

/// The body's core points in the world for those poses.
std::vector<Eigen::Vector3d> worldPoints(const Model& m, const std::vector<Pose>& poses, int body);

}  // namespace kccd::testing
