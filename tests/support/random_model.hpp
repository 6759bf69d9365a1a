// Random kinematic trees, volumes and interval boxes for the conservativeness property tests,
// plus forward kinematics written independently of libkccd.
#pragma once

#include <random>
#include <vector>

#include "kccd/model.hpp"

namespace kccd::testing {

/// A mobile base at the root of a random model, as `kccd import` maps URDF joints: planar
/// (prismatic along u, prismatic along v, revolute about n = u x v, the last two at the first's
/// origin) or floating (translation3d, then rotation3d at its origin).
enum class MobileBase { None, Planar, Floating };

/// A random model: 1..max_joints joints of every type and sweep mode, 2..max_bodies bodies; with a
/// mobile base, its joints come first (random plane and origin) and the others may hang from it.
Model randomModel(std::mt19937_64& rng, int max_joints = 5, int max_bodies = 4, MobileBase base = MobileBase::None);

/// A random interval box for the model: widths from 0 through 1e-12 and tiny up to beyond 2*pi.
/// Joints with `sweep: exact` get zero-width intervals.
void randomBox(std::mt19937_64& rng, const Model& m, std::vector<double>& lower, std::vector<double>& upper);

/// One configuration drawn from the box, with a realisation of every joint's error bound.
struct Sample {
  std::vector<double> q;
  std::vector<Vec3> translation_error;          // per joint (translation3d)
  std::vector<Eigen::Matrix3d> rotation_error;  // per joint (rotation3d)
  std::vector<bool> error_first;                // rotation3d: apply the error before the measured rotation
};

/// Corners, edge points and uniform points of the box; errors on their bound's surface or inside.
Sample sampleBox(std::mt19937_64& rng, const Model& m, const std::vector<double>& lower,
                 const std::vector<double>& upper, int kind);

/// World pose of every joint frame for a sample (independent forward kinematics).
std::vector<Pose> jointPoses(const Model& m, const Sample& s);

/// The body's core points in the world for those poses.
std::vector<Eigen::Vector3d> worldPoints(const Model& m, const std::vector<Pose>& poses, int body);

/// The pair's SSCH distance for those poses, by the independent oracle (referenceSschDistance).
double referencePairDistance(const Model& m, const std::vector<Pose>& poses, const BodyPair& pair);

}  // namespace kccd::testing
