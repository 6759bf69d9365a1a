// Support candidates by direction (support_cells.hpp): the rounding argument is there.
#include "support_cells.hpp"

#include <algorithm>
#include <cmath>

namespace kccd::detail {

namespace {

constexpr int kCells = 6 * kCellsPerFace;
constexpr int kGrid = kCellsPerEdge + 1;  // grid vertices per edge of a face

double faceCoordinate(int i) { return -1.0 + 2.0 * static_cast<double>(i) / kCellsPerEdge; }

// The position of the first largest of values[0 .. n) (n > 0; the values are finite).
std::size_t argMax(const double* values, std::size_t n) {
  return static_cast<std::size_t>(std::max_element(values, values + n) - values);
}

// row[j] = the dot product of point j with the face's direction (1, s, t), from the points' face
// coordinates a, u, v: a + (s u + t v). Returns the position of the first largest.
std::size_t faceRow(const double* a, const double* u, const double* v, std::size_t n, double s, double t, double* row) {
  for (std::size_t j = 0; j < n; ++j) row[j] = a[j] + (s * u[j] + t * v[j]);
  return argMax(row, n);
}

constexpr int kWitnesses = 5;

// keep[j] = whether no witness beats point j at all four vertices c: rows[c][w] - rows[c][j] >
// threshold for one witness w (rows[c][x]: the dot product of point x with vertex c).
void unbeaten(const double* const* rows, std::size_t m, const std::size_t* witness, double threshold,
              unsigned char* keep) {
  std::size_t distinct[kWitnesses];
  int count = 0;
  for (int x = 0; x < kWitnesses; ++x) {
    if (std::find(distinct, distinct + count, witness[x]) == distinct + count) distinct[count++] = witness[x];
  }
  const double *r0 = rows[0], *r1 = rows[1], *r2 = rows[2], *r3 = rows[3];
  for (std::size_t j = 0; j < m; ++j) {
    bool beaten = false;
    for (int x = 0; x < count && !beaten; ++x) {
      const std::size_t w = distinct[x];
      beaten = r0[w] - r0[j] > threshold && r1[w] - r1[j] > threshold && r2[w] - r2[j] > threshold &&
               r3[w] - r3[j] > threshold;
    }
    keep[j] = static_cast<unsigned char>(!beaten);
  }
}

}  // namespace

SupportCells supportCells(std::span<const Vec3> pts, int min_points) {
  SupportCells out;
  if (static_cast<int>(pts.size()) < min_points) return out;
  double norm = 0.0;
  for (const Vec3& p : pts) {
    const double r = p.norm();
    if (!(r <= kCellMaxNorm)) return out;  // huge, infinite or NaN: beyond the argued range, scan all
    norm = std::max(norm, r);
  }
  if (!(norm >= kCellMinNorm)) return out;
  const double threshold = kCellThreshold * norm;
  const std::size_t n = pts.size();
  // Per face, first the points that no witness beats at the face's four corners (the others are
  // beaten at every grid vertex of the face, their combinations with weights summing to one),
  // then per cell those of them that no witness beats at the cell's four grid vertices. Dot
  // products come from the face's coordinates (faceRow: a along its axis, u and v along the next
  // two), each product exact or within the rounding the argument allows.
  std::vector<double> a(n), u(n), v(n);  // the face's coordinates of every point
  std::vector<double> face_dots(4 * n);  // per corner k of the face: face_dots[k * n + i]
  std::vector<std::size_t> kept;         // the face's remaining points, in order
  std::vector<double> ka, ku, kv;        // their coordinates
  std::vector<double> dots;              // per grid vertex g: dots[g * kept.size() + j]
  std::vector<double> centre;
  std::vector<unsigned char> keep(n);
  out.begin.reserve(kCells + 1);
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const double sign = face % 2 == 0 ? 1.0 : -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      a[i] = sign * pts[i][axis];
      u[i] = pts[i][(axis + 1) % 3];
      v[i] = pts[i][(axis + 2) % 3];
    }
    const double* corner_row[4];
    std::size_t witness[kWitnesses];
    for (int k = 0; k < 4; ++k) {
      const double s = (k & 1) != 0 ? 1.0 : -1.0, t = (k & 2) != 0 ? 1.0 : -1.0;
      double* row = face_dots.data() + static_cast<std::size_t>(k) * n;
      witness[k] = faceRow(a.data(), u.data(), v.data(), n, s, t, row);
      corner_row[k] = row;
    }
    witness[4] = argMax(a.data(), n);  // the farthest point along the face's axis
    unbeaten(corner_row, n, witness, threshold, keep.data());
    kept.clear();
    ka.clear();
    ku.clear();
    kv.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (keep[i] == 0) continue;
      kept.push_back(i);
      ka.push_back(a[i]);
      ku.push_back(u[i]);
      kv.push_back(v[i]);
    }
    const std::size_t m = kept.size();  // at least one: no point beats the witnesses at their corners
    dots.resize(static_cast<std::size_t>(kGrid * kGrid) * m);
    centre.resize(m);
    std::size_t grid_witness[kGrid * kGrid];  // positions in `kept`
    for (int ia = 0; ia < kGrid; ++ia) {
      for (int ib = 0; ib < kGrid; ++ib) {
        double* row = dots.data() + static_cast<std::size_t>(ia * kGrid + ib) * m;
        grid_witness[ia * kGrid + ib] =
            faceRow(ka.data(), ku.data(), kv.data(), m, faceCoordinate(ia), faceCoordinate(ib), row);
      }
    }
    for (int iu = 0; iu < kCellsPerEdge; ++iu) {
      for (int iv = 0; iv < kCellsPerEdge; ++iv) {
        out.begin.push_back(static_cast<int>(out.index.size()));
        const int corner[4] = {iu * kGrid + iv, (iu + 1) * kGrid + iv, iu * kGrid + iv + 1, (iu + 1) * kGrid + iv + 1};
        const double* row[4];
        for (int k = 0; k < 4; ++k) row[k] = dots.data() + static_cast<std::size_t>(corner[k]) * m;
        // Witnesses: the farthest points at the four grid vertices and (nearly) at the centre,
        // along their sum; any point would do, these beat the most.
        for (std::size_t j = 0; j < m; ++j) centre[j] = (row[0][j] + row[1][j]) + (row[2][j] + row[3][j]);
        const std::size_t cell_witness[kWitnesses] = {argMax(centre.data(), m), grid_witness[corner[0]],
                                                      grid_witness[corner[1]], grid_witness[corner[2]],
                                                      grid_witness[corner[3]]};
        unbeaten(row, m, cell_witness, threshold, keep.data());
        for (std::size_t j = 0; j < m; ++j) {
          if (keep[j] == 0) continue;
          out.points.push_back(pts[kept[j]]);
          out.index.push_back(static_cast<int>(kept[j]));
        }
      }
    }
  }
  out.begin.push_back(static_cast<int>(out.index.size()));
  return out;
}

}  // namespace kccd::detail
