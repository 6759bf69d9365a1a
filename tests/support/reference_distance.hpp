// Independent distance oracle for the tests: Wolfe's minimum-norm-point algorithm on the
// Minkowski difference, in long double. Slow and simple on purpose; shares no code with libkccd.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace kccd::testing {

/// Distance between conv(a) and conv(b) (0 when they intersect), accurate to ~1e-15 relative.
long double referenceHullDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b);

/// Distance between the SSCHs (a, ra) and (b, rb): max(0, hull distance - ra - rb).
long double referenceSschDistance(const std::vector<Eigen::Vector3d>& a, double ra,
                                  const std::vector<Eigen::Vector3d>& b, double rb);

/// Distance from point p to conv(pts).
long double referencePointHullDistance(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& pts);

}  // namespace kccd::testing
