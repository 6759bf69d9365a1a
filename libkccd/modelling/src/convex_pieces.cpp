#include "kccd/modelling/convex_pieces.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "kccd/modelling/convex_hull.hpp"

namespace kccd::modelling {
namespace {

using Triangle = std::array<Vec3, 3>;

// A half-space n·x <= d.
struct HalfSpace {
  Vec3 n;
  double d;
};

// The part's solid on a voxel grid: voxels touched by a triangle, and those the outside cannot
// reach through untouched voxels (the enclosed volume).
struct Grid {
  Vec3 origin = Vec3::Zero();
  double h = 1.0;
  std::array<int, 3> size{0, 0, 0};
  std::vector<std::uint8_t> solid;

  std::size_t index(int x, int y, int z) const { return (static_cast<std::size_t>(z) * size[1] + y) * size[0] + x; }
  Vec3 centre(int x, int y, int z) const { return origin + h * Vec3(x + 0.5, y + 0.5, z + 0.5); }
  std::array<int, 3> cell(const Vec3& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a) {  // clamped before the cast (a NaN lands in cell 0)
      const double x = std::floor((p(a) - origin(a)) / h);
      c[a] = x >= 0.0 ? (x < size[a] - 1 ? static_cast<int>(x) : size[a] - 1) : 0;
    }
    return c;
  }
};

Grid voxelize(const std::vector<Triangle>& tris, int resolution) {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Triangle& t : tris)
    for (const Vec3& p : t) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  Grid g;
  const double longest = (hi - lo).maxCoeff();
  g.h = longest / resolution;
  g.origin = lo - Vec3::Constant(2.0 * g.h);  // two empty layers: the outside surrounds the part
  for (int a = 0; a < 3; ++a) g.size[a] = static_cast<int>(std::ceil((hi(a) - lo(a)) / g.h)) + 4;
  const std::size_t n = static_cast<std::size_t>(g.size[0]) * g.size[1] * g.size[2];
  std::vector<std::uint8_t> touched(n, 0);
  for (const Triangle& t : tris) {
    const double edge = std::max({(t[1] - t[0]).norm(), (t[2] - t[0]).norm(), (t[2] - t[1]).norm()});
    const int steps = std::max(1, static_cast<int>(std::ceil(edge / (0.5 * g.h))));
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const Vec3 p = t[0] + (t[1] - t[0]) * (double(i) / steps) + (t[2] - t[0]) * (double(j) / steps);
        const auto c = g.cell(p);
        touched[g.index(c[0], c[1], c[2])] = 1;
      }
  }
  // Flood the outside from a corner through untouched voxels (6-connected).
  std::vector<std::uint8_t> outside(n, 0);
  std::vector<std::array<int, 3>> stack{{0, 0, 0}};
  outside[0] = 1;
  while (!stack.empty()) {
    const auto c = stack.back();
    stack.pop_back();
    static constexpr int kStep[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : kStep) {
      const int x = c[0] + s[0], y = c[1] + s[1], z = c[2] + s[2];
      if (x < 0 || y < 0 || z < 0 || x >= g.size[0] || y >= g.size[1] || z >= g.size[2]) continue;
      const std::size_t i = g.index(x, y, z);
      if (outside[i] || touched[i]) continue;
      outside[i] = 1;
      stack.push_back({x, y, z});
    }
  }
  g.solid.resize(n);
  for (std::size_t i = 0; i < n; ++i) g.solid[i] = !outside[i];
  return g;
}

// Squared distance transform along one line (Felzenszwalb and Huttenlocher's lower envelope).
void distance1d(const double* f, double* out, int n, std::vector<int>& v, std::vector<double>& z) {
  v.resize(n);
  z.resize(n + 1);
  int k = 0;
  v[0] = 0;
  z[0] = -INFINITY;
  z[1] = INFINITY;
  for (int q = 1; q < n; ++q) {
    auto meet = [&](int r) { return ((f[q] + double(q) * q) - (f[r] + double(r) * r)) / (2.0 * q - 2.0 * r); };
    double s = meet(v[k]);
    while (s <= z[k]) s = meet(v[--k]);  // z[0] = -inf ends it
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = INFINITY;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    out[q] = (double(q) - v[k]) * (double(q) - v[k]) + f[v[k]];
  }
}

// Squared voxel distances from every voxel of a box to the nearest feature voxel (in place).
void distanceTransform(std::vector<double>& d, const std::array<int, 3>& n) {
  std::vector<double> line, out;
  std::vector<int> v;
  std::vector<double> z;
  const std::array<std::size_t, 3> stride{1, static_cast<std::size_t>(n[0]), static_cast<std::size_t>(n[0]) * n[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const int len = n[axis];
    line.resize(len);
    out.resize(len);
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int i = 0; i < n[a1]; ++i)
      for (int j = 0; j < n[a2]; ++j) {
        const std::size_t base = i * stride[a1] + j * stride[a2];
        for (int q = 0; q < len; ++q) line[q] = d[base + q * stride[axis]];
        distance1d(line.data(), out.data(), len, v, z);
        for (int q = 0; q < len; ++q) d[base + q * stride[axis]] = out[q];
      }
  }
}

bool inside(const std::vector<HalfSpace>& cell, const Vec3& p) {
  for (const HalfSpace& s : cell)
    if (s.n.dot(p) > s.d) return false;
  return true;
}

// The triangles clipped to the half-space (Sutherland-Hodgman), fan-triangulated.
std::vector<Triangle> clip(const std::vector<Triangle>& tris, const HalfSpace& s) {
  std::vector<Triangle> out;
  for (const Triangle& t : tris) {
    std::array<double, 3> side;
    int kept = 0;
    for (int k = 0; k < 3; ++k) kept += (side[k] = s.n.dot(t[k]) - s.d) <= 0.0;
    if (kept == 3) {
      out.push_back(t);
      continue;
    }
    if (kept == 0) continue;
    Vec3 poly[4];
    int m = 0;
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      if (side[k] <= 0.0) poly[m++] = t[k];
      if ((side[k] <= 0.0) != (side[l] <= 0.0)) {
        const double u = side[k] / (side[k] - side[l]);
        poly[m++] = t[k] + u * (t[l] - t[k]);
      }
    }
    for (int k = 1; k + 1 < m; ++k) out.push_back({poly[0], poly[k], poly[k + 1]});
  }
  return out;
}

struct Piece {
  std::vector<HalfSpace> cell;
  std::vector<Triangle> tris;
  double concavity = 0.0;
  bool final = false;
};

// The largest distance from the piece's hull surface to the solid inside its cell.
double concavity(const Grid& g, const std::vector<HalfSpace>& cell, const std::vector<Triangle>& tris) {
  if (tris.empty()) return 0.0;
  std::vector<Vec3> pts;
  pts.reserve(3 * tris.size());
  for (const Triangle& t : tris) pts.insert(pts.end(), t.begin(), t.end());
  const ConvexHull hull = convexHull(pts);
  if (hull.dimension < 3) return 0.0;
  // The box of voxels around the hull, and the cell's solid voxels in it.
  std::array<int, 3> lo{g.size[0], g.size[1], g.size[2]}, hi{0, 0, 0};
  for (int i : hull.vertices) {
    const auto c = g.cell(pts[i]);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  }
  std::array<int, 3> n;
  for (int a = 0; a < 3; ++a) n[a] = hi[a] - lo[a] + 1;
  std::vector<double> d(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  const double far = 4.0 * (double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]) + 1.0;
  bool any = false;
  for (int z = 0; z < n[2]; ++z)
    for (int y = 0; y < n[1]; ++y)
      for (int x = 0; x < n[0]; ++x) {
        const int gx = lo[0] + x, gy = lo[1] + y, gz = lo[2] + z;
        const bool feature = g.solid[g.index(gx, gy, gz)] && inside(cell, g.centre(gx, gy, gz));
        any |= feature;
        d[(static_cast<std::size_t>(z) * n[1] + y) * n[0] + x] = feature ? 0.0 : far;
      }
  if (!any) return 0.0;  // thinner than a voxel
  distanceTransform(d, n);
  // Sampled over the hull's faces at about one voxel's spacing.
  double worst = 0.0;
  for (const auto& t : hull.triangles) {
    const Vec3 &a = pts[t[0]], &b = pts[t[1]], &c = pts[t[2]];
    const double edge = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
    const int steps = std::clamp(static_cast<int>(std::ceil(edge / g.h)), 1, 256);
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const Vec3 p = a + (b - a) * (double(i) / steps) + (c - a) * (double(j) / steps);
        const auto v = g.cell(p);
        const int x = std::clamp(v[0] - lo[0], 0, n[0] - 1), y = std::clamp(v[1] - lo[1], 0, n[1] - 1),
                  z = std::clamp(v[2] - lo[2], 0, n[2] - 1);
        worst = std::max(worst, d[(static_cast<std::size_t>(z) * n[1] + y) * n[0] + x]);
      }
  }
  // Voxel centres to a surface point: about half a voxel either way.
  return std::max(0.0, std::sqrt(worst) * g.h - 0.5 * g.h);
}

// Cuts per axis: at 1/16 ... 15/16 of the piece's extent.
constexpr int kCutPositions = 16;

// Principal axes of the piece's triangle corners (the coordinate axes when it has too few).
Eigen::Matrix3d principalAxes(const Piece& p) {
  Vec3 mean = Vec3::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  double count = 0;
  for (const Triangle& t : p.tris)
    for (const Vec3& v : t) mean += v, second += v * v.transpose(), ++count;
  if (count < 4) return Eigen::Matrix3d::Identity();
  mean /= count;
  const Eigen::Matrix3d cov = second / count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return eig.eigenvectors();
}

}  // namespace

PieceSplit splitConcave(const Part& part, const PieceOptions& options) {
  if (options.max_pieces < 1 || options.max_pieces > 64)
    throw std::invalid_argument("the number of pieces must be 1 ... 64 (got " + std::to_string(options.max_pieces) +
                                ")");
  if (!(options.concavity > 0.0) || !std::isfinite(options.concavity))
    throw std::invalid_argument("the concavity must be a positive length");
  if (options.resolution < 8 || options.resolution > 256)
    throw std::invalid_argument("the resolution must be 8 ... 256 voxels");
  PieceSplit out;
  // Only pure triangle meshes: every point in a face, no balls.
  std::vector<std::uint8_t> used(part.points.size(), 0);
  for (const auto& f : part.faces)
    for (int i : f) used[i] = 1;
  const bool mesh = !part.faces.empty() && part.balls.empty() &&
                    std::all_of(used.begin(), used.end(), [](std::uint8_t u) { return u != 0; });
  if (!mesh) {
    out.pieces.push_back(part);
    out.concavity.push_back(0.0);
    return out;
  }
  std::vector<Triangle> tris;
  tris.reserve(part.faces.size());
  double extent = 0.0;
  for (const auto& f : part.faces) {
    tris.push_back({part.points[f[0]], part.points[f[1]], part.points[f[2]]});
    for (int i : f) extent = std::max(extent, part.points[i].cwiseAbs().maxCoeff());
  }
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : part.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  // A flat part has no empty space; one whose extent overflows cannot be put on a grid.
  if (!((hi - lo).maxCoeff() > 0.0) || !std::isfinite((hi - lo).maxCoeff()) || !std::isfinite(extent)) {
    out.pieces.push_back(part);
    out.concavity.push_back(0.0);
    return out;
  }
  const Grid g = voxelize(tris, options.resolution);
  std::vector<Piece> pieces(1);
  pieces[0].tris = std::move(tris);
  pieces[0].concavity = concavity(g, {}, pieces[0].tris);
  out.whole_concavity = pieces[0].concavity;
  out.measured = true;
  while (static_cast<int>(pieces.size()) < options.max_pieces) {
    std::size_t worst = pieces.size();
    for (std::size_t i = 0; i < pieces.size(); ++i)
      if (!pieces[i].final && pieces[i].concavity > options.concavity &&
          (worst == pieces.size() || pieces[i].concavity > pieces[worst].concavity))
        worst = i;
    if (worst == pieces.size()) break;
    Piece& p = pieces[worst];
    // Cut normals: the part's own axes (CAD parts are mostly modelled along them), then the
    // piece's principal axes unless near one of those.
    const Eigen::Matrix3d principal = principalAxes(p);
    std::vector<Vec3> normals;
    for (const Vec3& n : {Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY()), Vec3(Vec3::UnitZ()), Vec3(principal.col(0)),
                          Vec3(principal.col(1)), Vec3(principal.col(2))})
      if (std::none_of(normals.begin(), normals.end(), [&](const Vec3& m) { return std::abs(m.dot(n)) > 0.99; }))
        normals.push_back(n);
    double best = INFINITY;
    Piece best_a, best_b;
    for (const Vec3& n : normals) {
      double a = INFINITY, b = -INFINITY;
      for (const Triangle& t : p.tris)
        for (const Vec3& v : t) a = std::min(a, n.dot(v)), b = std::max(b, n.dot(v));
      if (!(b - a > 2.0 * g.h)) continue;
      for (int k = 1; k < kCutPositions; ++k) {
        const double at = a + (b - a) * k / kCutPositions;
        Piece left, right;
        left.cell = right.cell = p.cell;
        left.cell.push_back({n, at});
        right.cell.push_back({-n, -at});
        left.tris = clip(p.tris, left.cell.back());
        right.tris = clip(p.tris, right.cell.back());
        if (left.tris.empty() || right.tris.empty()) continue;
        left.concavity = concavity(g, left.cell, left.tris);
        right.concavity = concavity(g, right.cell, right.tris);
        // The larger concavity, ties to the smaller sum.
        const double score = std::max(left.concavity, right.concavity) + 1e-3 * (left.concavity + right.concavity);
        if (score < best) best = score, best_a = std::move(left), best_b = std::move(right);
      }
    }
    // A cut must lower the piece's concavity by at least half a voxel, or the piece stays whole.
    if (!(std::max(best_a.concavity, best_b.concavity) <= p.concavity - 0.5 * g.h) || best_a.tris.empty()) {
      p.final = true;
      continue;
    }
    p = std::move(best_a);
    pieces.push_back(std::move(best_b));
  }
  // Clipped points are computed to a few ulps of the coordinates: the pieces' radii cover that.
  const double guard = part.coordinate_guard + 16.0 * std::numeric_limits<double>::epsilon() * extent;
  for (const Piece& p : pieces) {
    Part q;
    for (const Triangle& t : p.tris) q.addTriangle(t[0], t[1], t[2]);
    q.coordinate_guard = guard;
    out.pieces.push_back(std::move(q));
    out.concavity.push_back(p.concavity);
  }
  return out;
}

}  // namespace kccd::modelling
