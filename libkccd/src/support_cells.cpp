// Support candidates by direction (support_cells.hpp): the rounding argument is there.
#include "support_cells.hpp"

#include <algorithm>
#include <cmath>

#include "point_scan.hpp"
#include "rounding.hpp"

namespace kccd::detail {

namespace {

constexpr int kCells = 6 * kCellsPerFace;

// The direction with face coordinates (u, v) on face `face` (axis face / 2, sign by face % 2).
Vec3 faceDirection(int face, double u, double v) {
  const int axis = face / 2;
  Vec3 d = Vec3::Zero();
  d[axis] = face % 2 == 0 ? 1.0 : -1.0;
  d[(axis + 1) % 3] = u;
  d[(axis + 2) % 3] = v;
  return d;
}

double faceCoordinate(int i) { return -1.0 + 2.0 * static_cast<double>(i) / kCellsPerEdge; }

}  // namespace

SupportCells supportCells(std::span<const Vec3> pts, int min_points) {
  SupportCells out;
  if (static_cast<int>(pts.size()) < min_points) return out;
  double norm = 0.0;
  for (const Vec3& p : pts) norm = std::max(norm, p.norm());
  if (!(norm >= kCellMinNorm && norm <= kCellMaxNorm)) return out;  // beyond the argued range: scan all
  // Above the scan's rounding (a few ulps of |p| |d| per dot product) and the test's own (a few
  // ulps of |w - p| |c|, |w - p| <= 2 norm), with a wide margin.
  const double margin = roundingGuard(norm, 64);
  out.begin.reserve(kCells + 1);
  for (int cell = 0; cell < kCells; ++cell) {
    out.begin.push_back(static_cast<int>(out.index.size()));
    const int face = cell / kCellsPerFace;
    const int iu = (cell % kCellsPerFace) / kCellsPerEdge, iv = cell % kCellsPerEdge;
    const double u0 = faceCoordinate(iu) - kCellSlack, u1 = faceCoordinate(iu + 1) + kCellSlack;
    const double v0 = faceCoordinate(iv) - kCellSlack, v1 = faceCoordinate(iv + 1) + kCellSlack;
    const Vec3 corner[4] = {faceDirection(face, u0, v0), faceDirection(face, u1, v0), faceDirection(face, u0, v1),
                            faceDirection(face, u1, v1)};
    double corner_margin[4];
    for (int k = 0; k < 4; ++k) corner_margin[k] = margin * roundedUp(corner[k].norm(), 4);
    int witness[5];
    witness[0] = supportIndex(pts, faceDirection(face, 0.5 * (u0 + u1), 0.5 * (v0 + v1)));
    for (int k = 0; k < 4; ++k) witness[k + 1] = supportIndex(pts, corner[k]);
    for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
      bool beaten = false;
      for (int w = 0; w < 5 && !beaten; ++w) {
        const Vec3 gap = pts[static_cast<std::size_t>(witness[w])] - pts[static_cast<std::size_t>(i)];
        bool everywhere = true;
        for (int k = 0; k < 4 && everywhere; ++k) everywhere = gap.dot(corner[k]) > corner_margin[k];
        beaten = everywhere;
      }
      if (beaten) continue;
      out.points.push_back(pts[static_cast<std::size_t>(i)]);
      out.index.push_back(i);
    }
  }
  out.begin.push_back(static_cast<int>(out.index.size()));
  return out;
}

}  // namespace kccd::detail
