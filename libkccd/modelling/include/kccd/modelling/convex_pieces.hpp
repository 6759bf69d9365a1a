// Splitting a concave mesh part into convex pieces (an approximate convex decomposition): each
// piece is the part's triangles clipped to one cell of a binary space partition, so the pieces'
// hulls together cover every point of the part's surface.
#pragma once

#include <vector>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling {

struct PieceOptions {
  int max_pieces = 8;       ///< at most this many pieces (1: never split)
  double concavity = 0.04;  ///< split while a piece's concavity exceeds this (metres)
  int resolution = 64;      ///< voxels along the part's longest side for measuring concavity
};

/// The pieces of a part and how concave each is.
struct PieceSplit {
  std::vector<Part> pieces;       ///< in the part's frame; one piece (the part) when not split
  std::vector<double> concavity;  ///< per piece (metres)
  double whole_concavity = 0.0;   ///< of the part before splitting (metres); 0 when not measured
  bool measured = false;          ///< false: the part is not a pure triangle mesh (primitives, balls, loose points)
};

/// Concavity of a part: the largest distance from a point of its convex hull's surface to the
/// part's solid (the mesh and what it encloses), measured on a voxel grid of `resolution` cells
/// along the longest side (to about a voxel: an estimate for choosing cuts, never a safety bound).
/// Splits the part while the most concave piece exceeds `options.concavity` and a cut lowers it:
/// each cut is the plane across one of the piece's principal axes or the part's own axes (at
/// 1/16 ... 15/16 of its extent) whose two halves have the smallest larger concavity, kept only
/// when that is lower than the piece's by at least half a voxel. Parts that are not pure triangle meshes
/// are returned whole and unmeasured. Throws std::invalid_argument on bad options.
PieceSplit splitConcave(const Part& part, const PieceOptions& options = {});

}  // namespace kccd::modelling
