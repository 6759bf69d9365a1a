// Triangle meshes that contain an SSCH (hull of points ⊕ ball), and a cache of them.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "kccd/ssch.hpp"

namespace kccd::render {

/// A closed convex triangle mesh. Triangles are wound counter-clockwise seen from outside.
struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Vec3> normals;                        ///< outward unit normal per triangle
  /// Every edge once: its two vertices and the two triangles that share it.
  std::vector<std::array<std::uint32_t, 4>> edges;
  int level = 0;                                    ///< sphere tessellation level used
  double mesh_radius = 0.0;                         ///< radius of the circumscribed sphere polytope (every vertex is this far from the core hull)
  bool direct = false;                              ///< built from the core hull (false: the qhull fallback)
  int hull_input = 0;                               ///< points passed to qhull (the core hull; 0 for points, segments, flat sets)
};

/// The unit sphere polytope of a tessellation level (icosahedron subdivided `level` times,
/// vertices on the unit sphere) and how much it must be scaled to contain the unit ball:
/// 1 / (smallest distance from the centre to a face plane), computed from the mesh itself.
struct SpherePolytope {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
  std::vector<std::array<std::uint32_t, 3>> neighbours; ///< triangle across edge k (vertices k, k + 1)
  double scale = 1.0;
  /// 2 sin(θ / 2) for the largest angle θ between a vertex and its faces' normals: every
  /// direction in a vertex's normal cone lies within this distance of the vertex direction.
  double cone_chord = 0.0;
};
const SpherePolytope& spherePolytope(int level);

/// Default smallest radius a volume is drawn with (metres). Points, segments and flat sets with
/// radius 0 are drawn as if their radius were this, so they stay visible and never look smaller.
inline constexpr double kMinDrawRadius = 1e-3;

/// A mesh containing the SSCH (points, radius): the Minkowski sum of the core points' convex
/// hull P and the sphere polytope Q of radius max(radius, min_radius) scaled to contain the ball
/// (turned by a fixed rotation), built directly from P's hull (tens of points) without a hull of
/// all p_i + q_j: a patch triangle v + t for each triangle t of Q (v the vertex of P supporting
/// its normal), a strip parallelogram e + g for each hull edge e of P and edge g of Q whose
/// normal arcs cross, and each facet of P offset by the vertex of Q supporting its normal.
/// Single points, collinear and flat sets (within 1e-9 (1 + extent), projected) and duplicate
/// points are handled by the same construction; if rounding makes its pieces disagree it falls
/// back to the hull of circumscribed sphere polytopes around the core points (qhull).
/// Throws std::invalid_argument for empty or non-finite input.
Mesh buildSschMesh(std::span<const Vec3> points, double radius, int level, double min_radius = kMinDrawRadius);

/// A drawable mesh from a triangle soup (three points per triangle, as modelling::readPart
/// gives a mesh file's triangles): vertices shared where equal and the triangles' normals are
/// within 40 degrees (smooth shading, sharp creases kept), normals as wound, no edges (drawn
/// without outline). Throws std::invalid_argument for a count not a multiple of 3
/// or non-finite points; degenerate triangles are dropped.
Mesh surfaceMesh(std::span<const Vec3> triangle_points);

/// Process-wide switch to the previous construction (the qhull hull of circumscribed sphere
/// polytopes around the core points), for comparisons in benchmarks and tests.
void useHullMeshing(bool on);

/// One SSCH to mesh (see buildSschMesh).
struct MeshRequest {
  std::span<const Vec3> points;
  double radius = 0.0;
  int level = 0;
  double min_radius = kMinDrawRadius;
};

/// Meshes keyed by the exact volume shape (the bytes of the points, radius, level and minimum radius): a volume
/// that does not change (a static body, the same state) reuses its mesh; entries unused for a
/// while are dropped so a moving robot does not grow the cache.
class MeshCache {
 public:
  explicit MeshCache(std::size_t capacity = 512) : capacity_(capacity) {}
  /// The mesh of the SSCH, built on first use.
  std::shared_ptr<const Mesh> get(std::span<const Vec3> points, double radius, int level,
                                  double min_radius = kMinDrawRadius);
  /// A mesh from getAll: null when it could not be built (qhull failed on extreme coordinates).
  struct Found {
    std::shared_ptr<const Mesh> mesh;
    bool built = false;  ///< built by this call (not from the cache)
  };
  /// The meshes of several SSCHs in order; those not cached are built in parallel
  /// (cv::parallel_for_), equal requests once.
  std::vector<Found> getAll(std::span<const MeshRequest> requests);
  /// Marks the start of a frame (entries unused for a few frames may then be evicted).
  void nextFrame() { ++frame_; }
  std::size_t size() const { return entries_.size(); }
  std::uint64_t built() const { return built_; }
  std::uint64_t reused() const { return reused_; }

 private:
  struct Entry {
    std::shared_ptr<const Mesh> mesh;
    std::uint64_t used = 0;
  };
  static std::string key(const MeshRequest& r);
  void makeRoom();
  std::size_t capacity_;
  std::uint64_t frame_ = 0, built_ = 0, reused_ = 0;
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace kccd::render
