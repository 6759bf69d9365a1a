// Triangle meshes as the renderer draws them, and drawable meshes from triangle soups (e.g. a
// link's visual geometry).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "kccd/types.hpp"

namespace kccd::render {

/// A triangle mesh: closed and convex when it holds an SSCH (see buildSschMesh), any surface when
/// made by surfaceMesh. Triangles are wound counter-clockwise seen from outside.
struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Vec3> normals;  ///< outward unit normal per triangle
  /// Every edge once: its two vertices and the two triangles that share it (empty for surfaces).
  std::vector<std::array<std::uint32_t, 4>> edges;
  int level = 0;  ///< sphere tessellation level used
  double mesh_radius =
      0.0;              ///< radius of the circumscribed sphere polytope (every vertex is this far from the core hull)
  bool direct = false;  ///< built from the core hull (false: the qhull construction)
  int hull_input = 0;   ///< points passed to qhull (the core hull; 0 for points, segments, flat sets)
};

/// A drawable mesh from a triangle soup (three points per triangle, as modelling::readPart
/// gives a mesh file's triangles): vertices shared where equal and the triangles' normals are
/// within 40 degrees (smooth shading, sharp creases kept), normals as wound, no edges (drawn
/// without outline). Throws std::invalid_argument for a count not a multiple of 3
/// or non-finite points; degenerate triangles are dropped.
Mesh surfaceMesh(std::span<const Vec3> triangle_points);

}  // namespace kccd::render
