// The edges of a closed triangle mesh (internal to the mesh constructions).
#pragma once

#include "kccd/render/mesh.hpp"

namespace kccd::render::detail {

/// Fills Mesh::edges from the triangles (sorted half-edges, paired up), in order of their vertices.
void buildEdges(Mesh& mesh);

/// Fills Mesh::edges and checks that the triangles close up: every edge is shared by exactly two
/// triangles that run along it in opposite directions, and V - E + F = 2 (false otherwise).
bool closeUp(Mesh& mesh);

}  // namespace kccd::render::detail
