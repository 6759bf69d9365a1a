// The geometry of one rigid part, reduced to what a conservative fit needs: points and balls
// whose convex hull contains every point of the part.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/ssch.hpp"

namespace kccd::modelling {

/// Points and exact balls whose convex hull contains the part. Curved primitives are covered
/// from outside (circumscribed polygons), never by an inscribed tessellation.
struct Part {
  std::vector<Vec3> points;
  std::vector<Sphere> balls;
  int triangles = 0;  ///< mesh triangles read
  /// The mesh triangles as indices into `points` (mesh readers fill it; primitives add none):
  /// what splitting a concave part into convex pieces cuts.
  std::vector<std::array<int, 3>> faces;
  int primitives = 0;             ///< analytic spheres, cylinders and cones covered exactly
  double coordinate_guard = 0.0;  ///< extra radius for single-precision input (metres)

  bool empty() const { return points.empty() && balls.empty(); }
  /// Every point and every ball's surface sampled densely (for hulls, reports and tests).
  std::vector<Vec3> samples(int per_ball = 162) const;

  /// A ball of `radius` around `center` mapped by `transform` (an ellipsoid when it scales
  /// unevenly: then covered by a circumscribed polyhedron).
  void addSphere(const Eigen::Affine3d& transform, double radius);
  /// A cylinder along local y, centred at the origin (Open Inventor / VRML / URDF-after-rotation).
  void addCylinderY(const Eigen::Affine3d& transform, double radius, double height);
  /// A cone along local y, base (bottom_radius) at y = -height/2, apex at +height/2.
  void addConeY(const Eigen::Affine3d& transform, double bottom_radius, double height);
  /// An axis-aligned box of the given full sizes, centred at the origin.
  void addBox(const Eigen::Affine3d& transform, const Vec3& size);
  /// Appends one mesh triangle: three points and their face.
  void addTriangle(const Vec3& a, const Vec3& b, const Vec3& c);
  /// Appends another part's geometry.
  void append(const Part& other);
};

/// A CAD part or mesh file that cannot be read: one line naming the file and the place.
class PartError : public InputError {
 public:
  using InputError::InputError;
};

/// Which part of a file to read.
struct ReadOptions {
  std::string part;                                 ///< name of a DEF'd node to read alone; empty: the whole file
  bool merge = false;                               ///< accept several top-level parts as one rigid body
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< applied in the file's frame (URDF mesh scale)
  /// Meshes read through Assimp are read in a child process (Assimp's readers are not hardened
  /// against malformed files): at most this long, and with at most this much memory beyond what
  /// the process has (not enforced under AddressSanitizer). Exceeded: PartError.
  double mesh_time_limit_s = 60.0;
  std::size_t mesh_memory_limit_mb = 4096;
};

/// Reads an Open Inventor (.iv, ASCII or binary) or VRML 1/2 (.wrl) file through Coin3D, an STL
/// file (ASCII or binary) directly, or any other mesh file Assimp reads (OBJ, COLLADA with its
/// unit and without its up-axis turn, PLY, glTF/GLB, ...; by extension), all transforms applied.
/// Throws PartError with a one-line message naming the file.
///
/// Refused with that error rather than read: anything but a regular file of at most
/// kMaxInputBytes (binary Open Inventor: kMaxBinaryInventorBytes); ASCII scenes nested deeper than
/// kMaxNesting braces or brackets; includes (Open Inventor File, VRML Inline and EXTERNPROTO,
/// VRML 1 WWWInline: the part must be one self-contained file); coordinate indices or vertex
/// counts outside their coordinates; negative or non-finite sizes of spheres, cylinders, cones
/// and boxes; non-finite transforms or vertices; zero or non-finite `options.scale`.
Part readPart(const std::string& path, const ReadOptions& options = {});

inline constexpr std::uintmax_t kMaxInputBytes = 256ull << 20;         ///< any part or URDF file
inline constexpr std::uintmax_t kMaxBinaryInventorBytes = 4ull << 20;  ///< see readPart
inline constexpr int kMaxNesting = 256;                                ///< braces and brackets, or groups

/// The whole content of an input file: regular files only (no directories, devices or FIFOs),
/// at most `max_bytes`. Throws InputError naming the file.
std::string readInputFile(const std::string& path, std::uintmax_t max_bytes = kMaxInputBytes);

/// Vertices of a polyhedron that contains the unit ball (its faces touch the ball from outside).
const std::vector<Vec3>& circumscribedUnitSphere();

}  // namespace kccd::modelling
