// The tag layout: where AprilTags (family tag36h11) are placed in the world, for calibrating a
// camera's pose (docs/formats.md section 4), and the world points of a tag's corners.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/types.hpp"

namespace kccd::calib {

/// A tag layout file that cannot be used: one line "file:line:col: field: problem".
class TagLayoutError : public InputError {
 public:
  using InputError::InputError;
};

inline constexpr int kMaxTagId = 586;                       ///< tag36h11 has ids 0..586
inline constexpr double kMaxTagSize = 100.0;                ///< edge of the black square, metres
inline constexpr double kMaxTagPosition = 1e6;              ///< |xyz[k]| in metres (as model lengths)
inline constexpr std::size_t kMaxTagLayoutBytes = 1 << 20;  ///< file size

/// One tag: its id, the edge of its black square and the pose of its frame in the world.
/// The tag frame has its origin at the tag centre, x to the right and y up as the printed tag is
/// seen from its front, z out of the tag towards the viewer; `rpy` follows the URDF convention.
struct Tag {
  int id = 0;
  double size = 0.0;  ///< metres
  Vec3 xyz = Vec3::Zero();
  Vec3 rpy = Vec3::Zero();

  /// Tag frame -> world.
  Pose pose() const;
  /// The corners in the world, in AprilTag's detection order p[0..3]: the tag-frame points
  /// (-s/2, -s/2, 0), (s/2, -s/2, 0), (s/2, s/2, 0), (-s/2, s/2, 0) placed by pose().
  std::array<cv::Point3d, 4> corners() const;
};

/// The tags of a layout, in file order; ids are unique.
struct TagLayout {
  std::vector<Tag> tags;
  /// The tag with this id, or nullptr.
  const Tag* find(int id) const;
};

/// Parses a layout (`tags: - {id, size, xyz, rpy}`); `source` names it in messages. Checks: one
/// YAML document with unique keys, no unknown fields, at least one tag, ids integers in
/// 0..kMaxTagId and not listed twice, size finite in (0, kMaxTagSize], xyz finite within
/// kMaxTagPosition, rpy finite (all four fields required). Throws TagLayoutError.
TagLayout parseTagLayout(const std::string& yaml_text, const std::string& source);
/// Reads a regular file of at most kMaxTagLayoutBytes and parses it. Throws TagLayoutError.
TagLayout loadTagLayout(const std::string& path);

}  // namespace kccd::calib
