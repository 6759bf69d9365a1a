// The icosphere polytope and how far it must be scaled to contain the unit ball.
#pragma once

#include <array>
#include <vector>

#include "kccd/types.hpp"

namespace kccd::hull {

/// An icosahedron subdivided `levels` times with its vertices on the unit sphere.
struct Icosphere {
  std::vector<Vec3> vertices;                 ///< on the unit sphere
  std::vector<std::array<int, 3>> triangles;  ///< counter-clockwise seen from outside
  double min_plane = 1.0;                     ///< smallest distance from the centre to a face plane
};

/// The icosphere of `levels` subdivisions (level 0: the icosahedron's 12 vertices).
Icosphere icosphere(int levels);

/// Factor that makes the icosphere contain the unit ball: (1 / min_plane) with a relative guard
/// of 1e-12, so rounding in the scaled vertices never moves a face inside the ball.
double circumscribedScale(const Icosphere& sphere);

/// The vertices scaled to contain the unit ball, each rounded as v * (1 / min_plane) * (1 + 1e-12)
/// (the same guard as circumscribedScale, applied vertex by vertex).
std::vector<Vec3> circumscribedVertices(const Icosphere& sphere);

}  // namespace kccd::hull
