// Support candidates by direction: a point set's directions cut into the cells of a cube map, and
// per cell the points that can be farthest along one of its directions, so that a support scan
// reads a few points instead of all of them. Internal.
//
// A cell is the cone over a rectangle of a cube face: its corners c_k are the face's grid vertices
// g_k (coordinates -1 + 2j / kCellsPerEdge, |g_k| <= sqrt 3) moved out by kCellSlack on each side,
// so that a direction placed in it with rounded ratios lies inside; |c_k - g_k| <= sqrt 2 kCellSlack.
// With N the set's largest |p|, a point p is left out of a cell when a witness w (another point of
// the set) beats it at every grid vertex of the cell by more than t = kCellThreshold N, computed as
// fl(fl(w.g_k) - fl(p.g_k)) > t (or at the four corners of the cell's face: each grid vertex of
// the face is a combination of the four with non-negative weights summing to one, so the exact
// inequality below, (w - p).g > t - 7 eps N, then holds at all of them). That difference errs by
// at most 7 eps N (each dot product by 1.5 eps N |g_k|, the subtraction by half an ulp of
// 2 N |g_k|; a product that underflows, by less than 1e-323, far below eps N in the cells'
// range), and |w - p| <= 2N, so with m = 64 eps N:
//   (w - p).c_k >= (w - p).g_k - 2N sqrt 2 kCellSlack > t - 7 eps N - 2.9e-6 N > 2m > m |c_k|.
// Every direction d of the cone is a non-negative combination of the corners, so (w - p).d >= m |d|
// there too (the triangle inequality), and with m above the scan's rounding (1.5 eps N |d| per dot
// product) the scan's computed value of w exceeds p's. So the largest computed dot product over
// the cell's points equals the largest over all points, bit for bit: the support value does not
// change, only the scan's length.
#pragma once

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "kccd/ssch.hpp"
#include "point_scan.hpp"

namespace kccd::detail {

/// Cells per edge of a cube face (6 kCellsPerEdge^2 cells).
inline constexpr int kCellsPerEdge = 4;
inline constexpr int kCellsPerFace = kCellsPerEdge * kCellsPerEdge;
/// How much a cell's rectangle is grown on each side (in face coordinates, from -1 to 1).
inline constexpr double kCellSlack = 1e-6;
/// The threshold by which a witness must beat a point at a cell's grid vertices, relative to the
/// set's largest |p|: above 2 sqrt 2 kCellSlack plus the rounding (the argument at the top).
inline constexpr double kCellThreshold = 4e-6;

/// The range of point sets (their largest |p|) and of directions (their largest |coordinate|)
/// the cells serve: the scale N |d| of every dot product then lies between 1e-250 and 1e301, so
/// none overflows and a product that underflows errs by far less than the rounding margins, as
/// the argument needs. Outside it (and for a set with a NaN) the scan reads every point.
inline constexpr double kCellMinNorm = 1e-100, kCellMaxNorm = 1e150;
inline constexpr double kCellMinDirection = 1e-150, kCellMaxDirection = 1e150;

/// The candidates of every cell: for cell c, points[begin[c] .. begin[c + 1]) (copies, for a
/// contiguous scan) and their indices in the set. Empty when the set is not worth it (few points)
/// or out of the cells' range.
struct SupportCells {
  std::vector<Vec3> points;
  std::vector<int> index;
  std::vector<int> begin;
  bool empty() const noexcept { return begin.empty(); }
};

/// The cells of point set `pts` (empty for fewer than `min_points` points, and out of the range).
SupportCells supportCells(std::span<const Vec3> pts, int min_points = 12);

/// The cell of direction d, or -1 when d is out of the cells' range (zero and not finite included).
inline int cellOf(const Vec3& d) noexcept {
  // The face: the axis of the largest |coordinate| (the first on a tie), chosen without branches
  // (which way it goes is unpredictable).
  const double ax = std::abs(d.x()), ay = std::abs(d.y()), az = std::abs(d.z());
  const bool y_wins = ay > ax && ay >= az, z_wins = az > ax && az > ay;
  const int axis = static_cast<int>(y_wins) + 2 * static_cast<int>(z_wins);
  const double m = std::max(ax, std::max(ay, az));
  if (!(m >= kCellMinDirection && m <= kCellMaxDirection)) return -1;  // tiny, huge or NaN
  static constexpr int kNext[3][2] = {{1, 2}, {2, 0}, {0, 1}};
  const double u = d[kNext[axis][0]], v = d[kNext[axis][1]];
  if (std::isnan(u) || std::isnan(v)) return -1;
  // The face coordinate u / m against the borders -1 + 2k / N, as u against m times them: no
  // division, and a border's product errs by an ulp at most, far inside kCellSlack.
  int iu = 0, iv = 0;
  for (int k = 1; k < kCellsPerEdge; ++k) {
    const double border = m * (-1.0 + 2.0 * k / kCellsPerEdge);
    iu += static_cast<int>(u >= border);
    iv += static_cast<int>(v >= border);
  }
  const int face = 2 * axis + static_cast<int>(std::signbit(d[axis]));
  return face * kCellsPerFace + iu * kCellsPerEdge + iv;
}

/// The points of the cell of direction d (all of `pts` when `cells` is empty or d has no cell),
/// and the map from their positions back to indices in `pts` (null: the identity).
struct CellScan {
  std::span<const Vec3> points;
  const int* index = nullptr;
};
inline CellScan cellScan(const SupportCells& cells, std::span<const Vec3> pts, const Vec3& d) noexcept {
  if (cells.empty()) return {pts, nullptr};
  const int cell = cellOf(d);
  if (cell < 0) return {pts, nullptr};
  const auto b = static_cast<std::size_t>(cells.begin[static_cast<std::size_t>(cell)]);
  const auto e = static_cast<std::size_t>(cells.begin[static_cast<std::size_t>(cell) + 1]);
  return {std::span<const Vec3>(cells.points).subspan(b, e - b), cells.index.data() + b};
}

/// The index in `pts` of a point farthest along d, read from d's cell (all of `pts` when there is
/// none): the largest dot product of supportIndex(pts, d), bit for bit (the argument at the
/// top), the cell's few candidates scanned in order (on a tie another point of that value).
inline int cellSupport(const SupportCells& cells, std::span<const Vec3> pts, const Vec3& d) noexcept {
  const CellScan scan = cellScan(cells, pts, d);
  if (scan.index == nullptr) return supportIndex(scan.points, d);
  const int j =
      scan.points.size() < kAvx2MinPoints ? supportIndexInOrder(scan.points, d) : supportIndex(scan.points, d);
  return scan.index[j];
}

}  // namespace kccd::detail
