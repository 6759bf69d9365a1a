// Labelled points for calibrating a camera's pose (docs/formats.md section 5): a pixel and the
// world point it shows, either given directly or as a point fixed to a model body.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"

namespace kccd::calib {

/// A labels file that cannot be used, or a body label that does not fit a model: one line
/// "file:line:col: field: problem".
class LabelsError : public InputError {
 public:
  using InputError::InputError;
};

inline constexpr double kMaxLabelPixel = 1e6;            ///< |u|, |v| in pixels
inline constexpr double kMaxLabelPoint = 1e6;            ///< |world[k]|, |point[k]| in metres (as model lengths)
inline constexpr std::size_t kMaxLabelState = 4096;      ///< values in a label's state
inline constexpr std::size_t kMaxLabelsBytes = 1 << 20;  ///< file size

/// One labelled point: `world` set for a world point; otherwise `body` names a model body and
/// `point` is in that body's frame, placed by `state` (absent: the state log's state at the
/// frame's time gives it).
struct Label {
  std::string name;
  cv::Point2d pixel;                         ///< OpenCV convention: pixel centres at integers
  std::optional<cv::Point3d> world;          ///< a world point
  std::string body;                          ///< a body-fixed point: the body ...
  cv::Point3d point;                         ///< ... and the point in its frame
  std::optional<std::vector<double>> state;  ///< the state placing the body, when the file gives it
  std::string where;                         ///< "file:line:col" of the label, for later messages

  bool bodyFixed() const { return !world.has_value(); }
};

/// The labels of a file, in file order; names are unique.
struct Labels {
  std::vector<Label> labels;
  /// The label with this name, or nullptr.
  const Label* find(const std::string& name) const;
};

/// Parses `labels: - {name, pixel: [u, v], world: [x, y, z]}` or `{name, pixel, body, point:
/// [x, y, z], state: [...]}` (state optional); `source` names the text in messages. Checks: one
/// YAML document with unique keys, no unknown fields, at least one label, names non-empty without
/// control characters and not given twice, exactly one of world / body, point only with body and
/// required by it, state only with body, numbers finite and bounded (kMaxLabelPixel,
/// kMaxLabelPoint, at most kMaxLabelState state values). Throws LabelsError.
Labels parseLabels(const std::string& yaml_text, const std::string& source);
/// Reads a regular file of at most kMaxLabelsBytes and parses it. Throws LabelsError.
Labels loadLabels(const std::string& path);

/// The world point a label shows: `world` as given, or the body-fixed point placed by forward
/// kinematics of `model` at `state`. Throws LabelsError naming the label (at its place in its
/// file) when the body is not in the model, `state` does not have model.stateSize() values or a
/// state value is not finite.
cv::Point3d worldPoint(const Model& model, const Label& label, std::span<const double> state);
/// The same with the label's own state; a body label without one is a LabelsError.
cv::Point3d worldPoint(const Model& model, const Label& label);

}  // namespace kccd::calib
