// Rounding guards: how much a computed length may be off because of floating-point rounding,
// so that every bound the library reports stays conservative. Internal.
//
// Each guard is one product of a small count of machine epsilons and a magnitude. The counts are
// powers of two, so `ulps * kEps` is exact and the result equals the written-out expression
// `ulps * eps * magnitude` bit for bit; the counts themselves (how many ulps an expression can
// err by) are chosen and argued where each guard is used.
#pragma once

#include <limits>

namespace kccd::detail {

/// Machine epsilon of double (one ulp of 1.0).
inline constexpr double kEps = std::numeric_limits<double>::epsilon();

/// Absolute guard for a quantity computed from values of at most `magnitude`: `ulps` ulps of it,
/// i.e. ulps * eps * magnitude. Add it to a radius (or subtract it from a distance).
constexpr double roundingGuard(double magnitude, int ulps) noexcept {
  return static_cast<double>(ulps) * kEps * magnitude;
}

/// A length `value` grown by `ulps` relative ulps: value * (1 + ulps * eps). Use for a computed
/// length that must not be underestimated (a radius, a growth, an arc width).
constexpr double roundedUp(double value, int ulps) noexcept { return value * (1.0 + static_cast<double>(ulps) * kEps); }

/// Relative shrink applied to a distance lower bound before it is stored or reported: the
/// bound is multiplied by (1 - kBoundShrink), which covers the few ulps of error in a difference
/// of computed lengths (sphere gaps, bounds lowered by a reach) with a wide margin.
inline constexpr double kBoundShrink = 1e-12;

/// A distance lower bound `value` scaled down by kBoundShrink: value * (1 - 1e-12).
constexpr double shrunkBound(double value) noexcept { return value * (1.0 - kBoundShrink); }

}  // namespace kccd::detail
