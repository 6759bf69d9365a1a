// The outline of an SSCH as a pinhole camera sees it, straight from its core points: a convex
// polygon that contains the volume's image and lies within a pixel tolerance outside it.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "kccd/types.hpp"

namespace kccd::render {

/// How fine an outline must be and where it may not reach.
struct OutlineOptions {
  double focal_px = 1.0;      ///< pixels per unit of normalised image coordinates (the larger focal length)
  double tolerance_px = 0.5;  ///< largest distance of the polygon outside the true image, pixels
  double min_depth = 0.0;     ///< every sphere must lie at least this far in front of the camera (z)
  int max_vertices = 4096;    ///< give up (false) rather than use more vertices
};

/// The image of the SSCH (core points in camera coordinates: x right, y down, z forward; radius r)
/// is the convex hull of its spheres' images. Writes to `polygon` the vertices, in normalised
/// image coordinates (x / z, y / z) and in order of increasing edge direction angle, of a convex
/// polygon that contains that image and whose every point lies within tolerance_px / focal_px of
/// it: the intersection of the image's support half-planes at directions refined until each
/// vertex is within tolerance of the chord between its two lines' touching points (which lies in
/// the image). Coinciding corners are kept once, so a core thinner than the tolerance may give
/// fewer than three. Returns false (polygon empty) when the core is empty, a value is not finite, some
/// sphere reaches nearer than min_depth (or behind the camera), or more than max_vertices would
/// be needed.
bool sschOutline(std::span<const Vec3> points, double radius, const OutlineOptions& options,
                 std::vector<Eigen::Vector2d>& polygon);

}  // namespace kccd::render
