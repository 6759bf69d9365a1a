// The geometric vocabulary every part shares: points and rigid motions, nothing else (Eigen's
// core and geometry modules only), for callers that need the types without the SSCH or the model.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace kccd {

/// A point or a direction in metres, in the frame its context names.
using Vec3 = Eigen::Vector3d;
/// A rigid motion; one named `a_to_b` maps coordinates in frame a into frame b.
using Pose = Eigen::Isometry3d;

}  // namespace kccd
