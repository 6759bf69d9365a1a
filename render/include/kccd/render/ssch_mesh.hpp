// Triangle meshes that contain an SSCH (hull of points ⊕ ball), built from sphere polytopes.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "kccd/render/mesh.hpp"
#include "kccd/types.hpp"

namespace kccd::render {

/// The unit sphere polytope of a tessellation level (icosahedron subdivided `level` times,
/// vertices on the unit sphere) and how much it must be scaled to contain the unit ball:
/// 1 / (smallest distance from the centre to a face plane), computed from the mesh itself.
struct SpherePolytope {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;   ///< counter-clockwise seen from outside
  std::vector<std::array<std::uint32_t, 3>> neighbours;  ///< triangle across edge k (vertices k, k + 1)
  double scale = 1.0;
  /// 2 sin(θ / 2) for the largest angle θ between a vertex and its faces' normals: every
  /// direction in a vertex's normal cone lies within this distance of the vertex direction.
  double cone_chord = 0.0;
};
/// The sphere polytope of a level (clamped to 0..5), made once per process.
const SpherePolytope& spherePolytope(int level);

/// Default smallest radius a volume is drawn with (metres). Points, segments and flat sets with
/// radius 0 are drawn as if their radius were this, so they stay visible and never look smaller.
inline constexpr double kMinDrawRadius = 1e-3;

/// How buildSschMesh builds a mesh.
enum class SschMeshing : std::uint8_t {
  Direct,  ///< from the core hull's normal fan (the default; falls back to Hull when rounding disagrees)
  Hull,    ///< the previous construction, the qhull hull of sphere polytopes around the core points (for comparisons)
};

/// A mesh containing the SSCH (points, radius): the Minkowski sum of the core points' convex
/// hull P and the sphere polytope Q of radius max(radius, min_radius) scaled to contain the ball
/// (turned by a fixed rotation), built directly from P's hull (tens of points) without a hull of
/// all p_i + q_j: a patch triangle v + t for each triangle t of Q (v the vertex of P supporting
/// its normal), a strip parallelogram e + g for each hull edge e of P and edge g of Q whose
/// normal arcs cross, and each facet of P offset by the vertex of Q supporting its normal.
/// Single points, collinear and flat sets (within 1e-9 (1 + extent), projected) and duplicate
/// points are handled by the same construction; if rounding makes its pieces disagree it falls
/// back to the hull of circumscribed sphere polytopes around the core points (qhull), which
/// SschMeshing::Hull asks for directly. Throws std::invalid_argument for empty or non-finite
/// input.
Mesh buildSschMesh(std::span<const Vec3> points, double radius, int level, double min_radius = kMinDrawRadius,
                   SschMeshing meshing = SschMeshing::Direct);

}  // namespace kccd::render
