#include "kccd/hull/qhull.hpp"

#include <cstdio>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace kccd::hull {

QhullResult convexHull3(std::span<double> coords) {
  QhullResult result;
  // qhull's messages go nowhere; the sink is opened once (a fit builds thousands of small hulls,
  // and stdio locks the stream for the threads that share it).
  static FILE* const devnull = std::fopen("/dev/null", "w");
  qhT qh_storage;
  qhT* qh = &qh_storage;
  QHULL_LIB_CHECK
  qh_zero(qh, devnull);
  char options[] = "qhull Qt";
  result.code =
      qh_new_qhull(qh, 3, static_cast<int>(coords.size() / 3), coords.data(), False, options, nullptr, devnull);
  if (result.code == 0) {
    facetT* facet;
    vertexT *vertex, **vertexp;
    FORALLvertices result.vertices.push_back(qh_pointid(qh, vertex->point));
    FORALLfacets {
      QhullFacet f;
      FOREACHvertex_(facet->vertices) f.vertices.push_back(qh_pointid(qh, vertex->point));
      f.normal = Vec3(facet->normal[0], facet->normal[1], facet->normal[2]);
      result.facets.push_back(std::move(f));
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return result;
}

}  // namespace kccd::hull
