// Fitting a conservative SSCH to a rigid part: few core points, smallest volume, every point of
// the part inside.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling {

/// The most core points a fit may use.
inline constexpr int kMaxCorePoints = 16;

struct FitOptions {
  int points = 8;                        ///< number of core points K (1 ... 16)
  int max_evaluations = 4000;            ///< optimiser budget per start (volume evaluations)
  std::uint64_t seed = 1;                ///< for the optimiser's random search directions
  std::function<void(double)> progress;  ///< called with the fraction done (0 ... 1), optional
};

/// A fitted SSCH and what it costs: its volume against the part's hull and two simple baselines.
struct FitResult {
  std::vector<Vec3> points;  ///< rounded to 10 significant digits: printing them loses nothing
  double radius = 0.0;
  double volume = 0.0;          ///< of the SSCH (closed form)
  double hull_volume = 0.0;     ///< of the part's convex hull
  double sphere_volume = 0.0;   ///< baseline: smallest enclosing sphere found (K = 1)
  double capsule_volume = 0.0;  ///< baseline: capsule on the principal axis (K = 2)
  int hull_vertices = 0;
  int evaluations = 0;
  /// Upper bound on how far the volume reaches outside the part's convex hull (metres): the
  /// largest distance from a point of the volume to the hull (outsideDistance).
  double outside = 0.0;
  /// How the points were chosen: "fit" (K optimised points), "hull" (every hull vertex) or
  /// "simplified hull" (the fewest hull vertices meeting a tolerance, fitToTolerance).
  const char* method = "fit";
};

/// Fits K core points minimising the SSCH volume, rounds them to 10 significant digits, then sets
/// the radius exactly for those points (conservative; print it with yamlNumber(r, true)).
/// Throws std::invalid_argument when K is out of range or the part is empty.
FitResult fit(const Part& part, const FitOptions& options = {});

/// No fit: the part's own convex hull as an SSCH, for links whose clearance matters more than
/// query time. Core = every hull vertex (a ball by a polytope circumscribing it), rounded to 10
/// significant digits, radius exactly covering the part for those points (the input's rounding
/// guard and a few ulps). Throws std::invalid_argument when the part is empty.
FitResult exactHull(const Part& part);

/// The fewest core points whose volume lies at most `tolerance` metres outside the part's convex
/// hull (FitResult::outside <= tolerance): the K = options.points fit when it meets the
/// tolerance with no more points than the simplified hull, else the simplified hull (hull vertices
/// added one at a time, farthest first, until the covering radius meets the tolerance; at worst
/// every hull vertex). Throws std::invalid_argument when the tolerance is not a positive finite
/// length, or as fit() does.
FitResult fitToTolerance(const Part& part, double tolerance, const FitOptions& options = {});

/// Upper bound on the one-sided distance from conv(core) ⊕ ball(radius) to the part's convex hull
/// H: max(0, max over core points of their signed distance to H, plus radius) — exact for a point
/// outside H, minus its depth inside (a ball of that depth around it lies in H). H is the hull of
/// the part's points and of points on its balls' surfaces (inside the true hull: a bound).
double outsideDistance(std::span<const Vec3> core, double radius, const Part& part);

/// The smallest radius r such that conv(core) ⊕ ball(r) contains the part (rounding covered).
double coveringRadius(std::span<const Vec3> core, const Part& part);

/// Volume of conv(points) ⊕ ball(radius) (Steiner's formula).
double sschVolume(std::span<const Vec3> points, double radius);

}  // namespace kccd::modelling
