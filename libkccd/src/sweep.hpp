// Conservative joint sweeps and the point budget (docs/algorithms.md sections 1-3). Internal.
#pragma once

#include <span>

#include "kccd/model.hpp"
#include "kccd/ssch.hpp"

namespace kccd::detail {

/// Largest angle one revolute piece may span; wider intervals are split into equal pieces.
inline constexpr double kMaxPieceAngle = 1.5707963267948966;  // pi / 2

/// A revolute interval [lo, hi] as the arc its sweeps cover (start and width, widened by rounding:
/// docs/algorithms.md section 1) and the sines and cosines they use: made once per joint and box,
/// shared by every body swept through the joint. Default-constructed: made for no interval.
struct RevoluteTrig {
  static constexpr int kMaxPieces = 4;                            // 2 pi / kMaxPieceAngle
  double lo = 0.0, hi = -1.0;                                     ///< the interval it was made for (lo > hi: none)
  double start = 0.0, width = 0.0;                                ///< the arc: its first angle (in [0, 2 pi)) and width
  int pieces = 0;                                                 ///< 0: a single angle, start
  double c_end[kMaxPieces + 1] = {}, s_end[kMaxPieces + 1] = {};  ///< the pieces' ends
  double half_cos = 1.0;                                          ///< cos(step / 2)
  double c_mid = 1.0, s_mid = 0.0;                                ///< the arc's middle
  double c_half = 1.0, s_half = 0.0;                              ///< cos and sin of width / 2
  double half_chord = 0.0;                                        ///< 2 sin(width / 4)
};

/// The arc and trigonometry of the revolute interval [lo, hi] (finite values).
RevoluteTrig revoluteTrig(double lo, double hi) noexcept;

/// How many output points one input point can become in sweepJoint() (worst case).
int sweepExpansion(const Joint& joint) noexcept;

/// Sweeps S(in, radius) through `joint` over the box [lo, hi] (joint.dof values each) and maps
/// the result into the joint's parent frame. Writes the core points to `out` (room for
/// sweepExpansion() * in.size()) and returns their count; `radius` grows as needed. Returns -1 when
/// a value is not finite. The caller checks sweep-mode rules (exact needs lo == hi).
/// `below` is a sphere containing the input volume (the swept sphere of the level below): growths
/// that depend on how far points can lie from the axis or origin use it, as the exact stage does.
/// A revolute sweep covers the arcs of the points farthest from the axis by chords and the others
/// by their middle point, as far as `budget` output points allow; `rho` needs room for 2 n values.
/// `trig` is revoluteTrig(lo[0], hi[0]) for a revolute joint (ignored for the others).
int sweepJoint(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig,
               std::span<const Vec3> in, Vec3* out, double& radius, int budget, double* rho,
               const Sphere& below) noexcept;

/// Rounding guard of a rigid map (RigidMap): applying it to x errs by at most
/// roundingGuard(|x| + magnitude, kRigidGuardUlps).
inline constexpr int kRigidGuardUlps = 64;

/// A joint at one value as the rigid map x -> lin x + off into its parent frame, as sweepJoint()
/// moves points (fixed, revolute at a single angle, prismatic; `ok` is false for the 3-DOF joints,
/// whose sweeps add growth). Applied in floating point to x it errs from the exact motion by at
/// most roundingGuard(|x| + magnitude, kRigidGuardUlps); so does `lin` applied to a vector.
struct RigidMap {
  Eigen::Matrix3d lin = Eigen::Matrix3d::Identity();
  Vec3 off = Vec3::Zero();
  double magnitude = 0.0;
  bool ok = false;
};

/// The rigid map of `joint` at `value` (joint.dof values; `trig` as for sweepJoint()).
RigidMap rigidMap(const Joint& joint, const double* value, const RevoluteTrig& trig) noexcept;

/// The largest distance from the axis (through the origin) of a point of sphere s.
double rhoBound(const Vec3& axis, const Sphere& s) noexcept;

/// The affine maps x -> lin x + off whose images of a point set cover a joint's motion over the
/// box [lo, hi] and map into the parent frame (docs/algorithms.md section 6): chord ends (rigid), then for a
/// revolute joint the tangent apexes (radial part scaled by 1 / cos(step / 2)). Covering with the
/// first `chord_count` maps needs the radius to grow by `sagitta` times the distance from the
/// axis; every cover adds `fixed_growth` plus `point_growth` times the distance from the joint
/// frame's origin (3-DOF joints: the box around its centre). A rotation3d box of small reach also
/// has apexes: its centre rotation composed with the twelve rotations of an icosahedron around
/// the reach ball, whose cover (all maps) grows by `apex_point_growth` per unit distance instead.
// NOLINTNEXTLINE(bugprone-reserved-identifier): clang-tidy 14 flags the implicit copy's loop index
struct JointMaps {
  static constexpr int kMax = 13;
  int count = 0;
  int chord_count = 0;
  Eigen::Matrix3d lin[kMax];
  Vec3 off[kMax];
  double scale[kMax];     ///< bound on the operator norm of lin
  bool revolute = false;  ///< a revolute interval of non-zero width (sagitta applies)
  Vec3 axis = Vec3::UnitZ();
  double sagitta = 0.0;
  double apex_excess = 0.0;  ///< an apex lies at most this times rho (rotation3d: |p|) beyond the motion
  double fixed_growth = 0.0;
  double point_growth = 0.0;
  bool shared_lin = false;         ///< every map has the same linear part (translations)
  bool rotation_apexes = false;    ///< rotation3d apexes follow the chord map
  double apex_point_growth = 0.0;  ///< point_growth of the cover with the rotation3d apexes
  double offset_norm = 0.0;        ///< bound on |off|
};

/// The vertex maps of `joint` over [lo, hi] (values finite; the caller checks). `trig` is
/// revoluteTrig(lo[0], hi[0]) for a revolute joint (ignored for the others).
JointMaps jointMaps(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig) noexcept;

/// A sphere containing every position of sphere `in` under the joint's motion over [lo, hi],
/// in the joint's parent frame (cheap: no points are swept).
/// `trig` as for sweepJoint().
Sphere sweepSphere(const Joint& joint, const double* lo, const double* hi, const RevoluteTrig& trig,
                   const Sphere& in) noexcept;

/// Keeps at most `budget` of the n points (farthest-point selection) in pts[0..k) and grows
/// `radius` by an upper bound on the largest distance from a dropped point to the hull of the
/// kept ones. Returns k.
/// `dist` and `order` need room for n values.
int reduceToBudget(Vec3* pts, int n, int budget, double* dist, int* order, double& radius) noexcept;

}  // namespace kccd::detail
