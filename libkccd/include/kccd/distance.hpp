// Distance between two SSCHs: GJK with a signed-volumes sub-algorithm and an any-time lower bound.
#pragma once

#include <cstdint>
#include <limits>

#include "kccd/ssch.hpp"

namespace kccd {

/// How a distance computation ended. Every value still comes with a valid lower bound.
enum class GjkStatus : std::uint8_t {
  Converged,       ///< lower and upper bound agree to the requested tolerance
  Overlap,         ///< the hulls intersect (distance 0)
  StoppedEarly,    ///< the lower bound reached `stop_above`, or the upper bound `stop_below`
  NoProgress,      ///< rounding stopped the descent; the bounds are valid but may be looser
  IterationLimit,  ///< `GjkOptions::max_iterations` reached; the bounds are valid
  InvalidInput,    ///< empty set, NaN/inf coordinate or negative radius: distance reported as 0
};

/// Tuning of one distance call. The defaults give about 1e-12 relative accuracy.
struct GjkOptions {
  int max_iterations = 128;           ///< hard bound on the iteration count
  double relative_tolerance = 1e-12;  ///< stop when (upper - lower) <= tol * upper
  /// Stop as soon as the SSCH distance is proven to be >= this (e.g. the safety margin).
  double stop_above = std::numeric_limits<double>::infinity();
  /// Stop as soon as the volumes are proven to come within this distance of each other (two
  /// points of them are): refining the lower bound further cannot lift it above this.
  double stop_below = -std::numeric_limits<double>::infinity();
  /// Optional warm start: a separating direction (pointing from b to a), e.g. from the last cycle.
  const Vec3* warm_start = nullptr;
};

/// The outcome of a distance call between SSCHs a and b.
struct DistanceResult {
  /// Guaranteed lower bound on the distance between the two volumes; 0 when they touch or overlap.
  double distance = 0.0;
  /// Lower and upper bounds on the distance between the two hulls conv(Pa), conv(Pb).
  double hull_lower = 0.0;
  double hull_upper = 0.0;
  /// Closest points found on the surfaces of a and b (on the hulls when they overlap).
  Vec3 witness_a = Vec3::Zero();
  Vec3 witness_b = Vec3::Zero();
  /// Unit direction from b to a of the last iterate; feed it back as a warm start.
  Vec3 direction = Vec3::UnitX();
  int iterations = 0;
  GjkStatus status = GjkStatus::InvalidInput;
};

/// Distance between SSCHs a and b given in the same frame. Never allocates, never throws, and
/// never returns NaN: on invalid input the status says so and the distance is 0 (unsafe).
DistanceResult distance(const SschView& a, const SschView& b, const GjkOptions& options = {}) noexcept;

/// Penetration estimate for overlapping volumes (libccd MPR), for reporting only.
struct Penetration {
  bool overlapping = false;
  double depth = 0.0;             ///< approximate depth; 0 when not overlapping
  Vec3 direction = Vec3::Zero();  ///< unit direction to move b by `depth` to separate it
  Vec3 position = Vec3::Zero();   ///< a point in the overlap
};

/// Penetration depth of two SSCHs via libccd's MPR. Not a bound; not for the real-time path.
Penetration penetration(const SschView& a, const SschView& b);

/// True when the volumes intersect according to libccd's GJK (an independent implementation).
bool intersectsLibccd(const SschView& a, const SschView& b);

}  // namespace kccd
