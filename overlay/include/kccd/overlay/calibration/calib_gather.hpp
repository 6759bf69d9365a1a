// Calibration's correspondences gathered from its inputs: the pictures (image files, frames of a
// recording, or pictures already decoded), the AprilTags a tag layout places, hand labels, and the
// model placing body labels at each frame's state. What `kccd calib` solves a pose from, as data.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/correspondence.hpp"
#include "kccd/calib/labels.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"

namespace kccd::overlay {

/// Calibration inputs that do not fit together (a picture of another size than the camera, a body
/// label without a model or a state): one line naming the file and place.
class CalibInputError : public InputError {
 public:
  using InputError::InputError;
};

/// The camera of a camera file as calibration starts from it: its intrinsics and lens, the pose
/// zero and no quality figures.
calib::Camera intrinsicsOf(calib::Camera camera);

/// Checks that a picture has the camera's size and is 8-bit BGR; `image` and `camera_name` name
/// them in the message. Throws CalibInputError.
void checkPicture(const cv::Mat& bgr, const calib::Camera& camera, const std::string& image,
                  const std::string& camera_name);

/// Frames of a recording picked by index, and the frame rate it declares.
struct RecordingFrames {
  std::vector<cv::Mat> frames;  ///< 8-bit BGR, in the order asked for
  double fps = 0.0;             ///< 0: the recording declares none
};

/// Frames `wanted` (indices from 0, any order) of a recording (VideoSource: a video file or an
/// image sequence), decoded in order up to the last one asked for; `label` names it in errors
/// (default: the path). Throws VideoError when it cannot be read, ends before a frame asked for,
/// or a frame asked for is not 8-bit colour.
RecordingFrames readRecordingFrames(const std::string& path, const std::vector<int>& wanted,
                                    const std::string& label = "");

/// About `count` frames spread evenly over a whole recording (all of them when it has fewer), in
/// order, with their indices in `indices`; one pass. Throws VideoError as readRecordingFrames.
RecordingFrames sampleRecordingFrames(const std::string& path, std::size_t count, std::vector<int>& indices,
                                      const std::string& label = "");

/// One frame of a calibration: its picture, what is labelled in it and the robot's state in it.
struct CalibFrame {
  /// The image file, read when `bgr` is empty; with `bgr`, the picture's name (e.g.
  /// "video.mkv#12"); empty without `bgr`: no picture (labels only).
  std::string image;
  cv::Mat bgr;                          ///< the picture (8-bit BGR), when already decoded
  std::optional<calib::Labels> labels;  ///< points labelled in this frame
  /// The robot's state in this frame (the model's state size): places body labels without a state
  /// of their own.
  std::optional<std::vector<double>> state;
};

/// Everything a calibration gathers its points from.
struct GatherInputs {
  calib::Camera camera;                  ///< the intrinsics: every picture must have its size
  std::string camera_name;               ///< names the camera in messages (its file)
  std::vector<CalibFrame> frames;        ///< in order; names get "fK/" prefixes when there are several
  std::optional<calib::TagLayout> tags;  ///< detected tags it places become points (frames with a picture)
  const Model* model = nullptr;          ///< places body labels (null: world labels only)
};

/// What one frame gave.
struct GatheredFrame {
  std::string image;             ///< the picture's name; empty: labels only
  cv::Mat bgr;                   ///< the picture (empty: none)
  std::vector<double> state;     ///< the frame's state (empty: none given)
  std::vector<int> unknown_ids;  ///< detected tag ids the layout does not place, ascending
  int tag_points = 0;            ///< tag corners gathered
  int label_points = 0;          ///< labels gathered
};

/// Where a gathered point came from.
struct PointSource {
  std::size_t frame = 0;  ///< index into Gathered::frames
  bool tag = false;       ///< a tag corner (else a label)
  /// What the check image writes next to it: the label's name, or "tagN" on a tag's first corner
  /// (empty on its other corners), prefixed like the point's name.
  std::string label;
};

/// The gathered correspondences and where each came from.
struct Gathered {
  std::vector<GatheredFrame> frames;  ///< one per input frame
  /// Per frame: tag corners (detection, then corner order), then labels (file order); with
  /// several frames every name is prefixed "fK/" (K from 1).
  std::vector<calib::Correspondence> points;
  std::vector<PointSource> sources;  ///< one per point
  std::vector<int> unknown_tag_ids;  ///< over all frames, ascending, each once
};

/// Gathers every frame's points: its picture read and checked (checkPicture), the layout's tags
/// detected in it (corner names "tagN.c0".."tagN.c3"), and its labels, each at its world point (a
/// body label placed by the model at the label's own state, else at the frame's). Throws
/// CalibInputError (a picture that does not fit, a frame state of the wrong size, a body label
/// without a model or without a state), calib::ImageError, calib::TagDetectionError or
/// calib::LabelsError.
Gathered gatherCorrespondences(const GatherInputs& inputs);

/// The gathered points moved from the world into the model's frame `frame` (a joint's; a camera
/// fixed to it, Camera::frame) at each point's frame's state: a pose solved from them is that
/// frame -> camera, one pose for every frame. Throws CalibInputError naming `label` and the first
/// frame without a state (each frame's state comes from --state, --states or a robot log).
Gathered inMountFrame(Gathered gathered, const Model& model, int frame, const std::string& label);

}  // namespace kccd::overlay
