// The sphere around an SSCH given as points and radius (used by Ssch and by the checker's swept
// volumes). Internal.
#pragma once

#include <span>

#include "kccd/ssch.hpp"

namespace kccd::detail {

/// A sphere containing S(pts, radius): centred on the points' bounding box, with a radius
/// rounded up so that it holds every point. `pts` must not be empty.
Sphere boundingSphere(std::span<const Vec3> pts, double radius) noexcept;

}  // namespace kccd::detail
