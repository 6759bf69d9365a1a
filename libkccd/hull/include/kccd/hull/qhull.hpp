// One qhull run in 3-D (reentrant qhull, triangulated output), set up and torn down in one call.
#pragma once

#include <span>
#include <vector>

#include "kccd/types.hpp"

namespace kccd::hull {

/// A facet of the hull: the ids of its input points (qhull's order) and its outward unit normal.
struct QhullFacet {
  std::vector<int> vertices;
  Vec3 normal = Vec3::Zero();
};

/// What qhull returned: its exit code (0: success; the facets are empty otherwise), the ids of
/// the hull's vertices in qhull's vertex-list order and the facets in its facet-list order.
struct QhullResult {
  int code = 0;
  std::vector<int> vertices;
  std::vector<QhullFacet> facets;
};

/// The convex hull of the points (x, y, z triples in `coords`) by qhull with options "qhull Qt";
/// qhull's messages are discarded and its memory freed before this returns.
QhullResult convexHull3(std::span<double> coords);

}  // namespace kccd::hull
