// The immutable robot model: kinematic tree, bodies, checked pairs. Built once from a file.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/types.hpp"

namespace kccd {

/// Index of the world frame wherever a joint index is expected.
inline constexpr int kWorld = -1;

enum class JointType : std::uint8_t { Fixed, Revolute, Prismatic, Translation3d, Rotation3d };

/// How a joint's interval is swept: `Exact` accepts only zero-width intervals; `Accurate` (chords,
/// with tangent apexes and box splitting in the exact stage) covers any interval. (The chords-only
/// `fast` mode is retired: model files may still say `fast`, read as `accurate`; the measured
/// reason is in docs/explanation/trade.md.)
enum class SweepMode : std::uint8_t { Exact, Accurate };

/// One joint. Its motion acts in the joint frame given by `origin` (pose in the parent frame at
/// zero state); its children and bodies move with it.
struct Joint {
  std::string name;
  int parent = kWorld;  ///< index of the parent joint, or kWorld
  JointType type = JointType::Fixed;
  Pose origin = Pose::Identity();
  Vec3 axis = Vec3::UnitZ();  ///< unit axis (revolute / prismatic)
  SweepMode sweep = SweepMode::Accurate;
  std::optional<std::array<double, 2>> limits;  ///< position limits (1-DOF joints)
  double error = 0.0;                           ///< translation3d: metres; rotation3d: radians
  int state_offset = 0;                         ///< first index of this joint's values in the state vector
  int dof = 0;                                  ///< number of state values (0, 1 or 3)
};

/// One rigid body: an SSCH in the frame of a joint (or the world).
struct Body {
  std::string name;
  int frame = kWorld;
  std::vector<Vec3> points;
  double radius = 0.0;
  /// The link this body is a convex piece of (a concave link modelled in pieces: every piece in
  /// the link's frame); empty when the body is a whole link. See linkName().
  std::string link;
  /// How far the volume may reach outside its link's (piece's) convex hull, as fitted (metres);
  /// negative when the file does not say. Informative: the checks use the points and radius.
  double tolerance = -1.0;
  /// The link the user knows the body as: `link` when it is a piece, else its own name.
  const std::string& linkName() const { return link.empty() ? name : link; }
};

/// How a link looks, for drawing only (never checked for collision): a mesh file or a
/// primitive, placed in a frame, with a colour. `kccd import` writes them from URDF `<visual>` elements.
struct Visual {
  enum class Shape : std::uint8_t { Mesh, Box, Cylinder, Sphere };
  int frame = kWorld;
  Shape shape = Shape::Mesh;
  std::string mesh;                ///< Mesh: the file (relative paths resolved against the model file's folder)
  Vec3 scale = Vec3::Ones();       ///< Mesh: scale per axis, in the mesh's frame
  Vec3 size = Vec3::Zero();        ///< Box: full sizes; Cylinder: radius, radius, length (along z); Sphere: radius in x
  Pose origin = Pose::Identity();  ///< pose in the frame
  std::array<double, 4> colour{0.7, 0.7, 0.7, 1.0};  ///< RGBA, 0..1
};

/// A checked body pair and the frame both are compared in (least common ancestor).
struct BodyPair {
  int a = 0;
  int b = 0;
  int lca = kWorld;
};

/// Why a pair of bodies is left out of the checks, as its `pairs: ignore` entry says (the
/// optional third element: `[a, b, adjacent]`; none means `user`).
enum class IgnoreReason : std::uint8_t {
  User,            ///< the file's author said so (no reason written)
  Adjacent,        ///< one moving joint between them, no body on a link between (MoveIt's rule)
  Rigid,           ///< only fixed joints between them: one constant distance
  Never,           ///< proven never within the margin over the joint limits (kccd pairs)
  AlwaysTouching,  ///< proven within the margin at every configuration (kccd pairs)
  Srdf,            ///< an SRDF's disable_collisions
};

/// An ignored body pair and why it is ignored.
struct IgnoredPair {
  int a = 0;
  int b = 0;
  IgnoreReason reason = IgnoreReason::User;
};

/// A model file that cannot be loaded: the message names file, line and field.
class ModelError : public InputError {
 public:
  using InputError::InputError;
};

/// Largest absolute length a model file may give (points, radii, origins, margins, error bounds):
/// metres, far beyond any robot cell, and small enough that squares and sums stay exact to ~1e-7 m.
inline constexpr double kMaxModelLength = 1e6;

/// Most bodies a model file may hold (the checked pairs grow with their square: 8 million at this
/// bound); a cell of a few robots has tens to hundreds.
inline constexpr std::size_t kMaxModelBodies = 4096;

/// The immutable model. Build it with loadModel() / parseModel() or assemble it and call
/// finalize(); a Checker then holds every mutable buffer.
class Model {
 public:
  std::string name;
  double safety_margin = 0.0;
  int point_budget = 32;      ///< max core points of any swept volume
  std::vector<Joint> joints;  ///< parents always precede children
  std::vector<Body> bodies;
  std::vector<BodyPair> pairs;
  std::vector<IgnoredPair> ignored;  ///< the file's `pairs: ignore` entries, in file order
  std::vector<Visual> visuals;       ///< appearance for drawing (optional)

  /// Number of state values.
  int stateSize() const { return state_size_; }
  /// Names of the state values (`shoulder`, `payload_pose.x`, ...).
  const std::vector<std::string>& stateNames() const { return state_names_; }
  /// Index of a joint or body by name, or -1.
  int jointIndex(const std::string& joint) const;
  int bodyIndex(const std::string& body) const;
  /// Least common ancestor of two frames (kWorld when none).
  int commonAncestor(int frame_a, int frame_b) const;
  /// Name of a frame index ("world" for kWorld).
  const std::string& frameName(int frame) const;

  /// Computes state offsets, names and the pair list. `check_all` selects every pair of bodies
  /// in different frames; `ignore` removes pairs, `include` adds them. Throws ModelError.
  void finalize(bool check_all, const std::vector<std::array<int, 2>>& ignore,
                const std::vector<std::array<int, 2>>& include);

 private:
  int state_size_ = 0;
  std::vector<std::string> state_names_;
};

/// Loads a `kccd: 1` YAML model file: exactly one YAML document, no repeated key, lengths within
/// kMaxModelLength, any finite angle. Throws ModelError("file:line:col: field: problem").
Model loadModel(const std::string& path);
/// The text of a model file (a regular file of at most 64 MiB). Throws ModelError.
std::string readModelText(const std::string& path);
/// Parses YAML text; `source` names it in error messages.
Model parseModel(const std::string& yaml_text, const std::string& source);

const char* toString(JointType type);
const char* toString(SweepMode mode);
const char* toString(IgnoreReason reason);
/// The reason named by `word` (toString's words), false when there is none.
bool parseIgnoreReason(const std::string& word, IgnoreReason& reason);

}  // namespace kccd
