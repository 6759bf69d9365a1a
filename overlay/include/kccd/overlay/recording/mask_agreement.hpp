// A recording's robot masks (one image per frame, any segmentation tool's output) and each frame's
// agreement with the robot drawn at its logged state: the IoU of the mask with the model's
// silhouette through the camera (its visuals when it has them, as calibration draws it). A frame whose logged state
// does not match the video (a wrong clock offset, a joint offset, a moved camera) stands out as low agreement.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "kccd/calib/background.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/calibration/calib_refine.hpp"
#include "kccd/overlay/recording/frame_annotator.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// The masks of a recording's frames: a folder holding frame_NNNNNN.png (frame index from 0, six
/// digits, as kccd synth writes them; a frame without a file has no agreement; non-zero = robot),
/// or masks made from a fixed camera's recording itself: what differs from its background
/// (calib/background.hpp), learnt over the recording away from the robot drawn at its states.
class MaskAgreement {
 public:
  /// Masks made from the recording: only the bodies (of `bodies`; empty: all) that move are drawn.
  /// learnBackground() must be called before at(). Throws InputError when none moves.
  MaskAgreement(const calib::Camera& camera, const Model& model, std::vector<int> bodies, std::string label);
  /// Checks the folder (it exists and holds at least one frame_NNNNNN.png) and the bodies drawn
  /// (model body indices; empty: all). `label` names the folder in errors (e.g. "--masks m/").
  /// Throws InputError.
  MaskAgreement(const std::string& folder, const calib::Camera& camera, const Model& model, std::vector<int> bodies,
                std::string label);

  /// Masks made from the recording: the background from about 40 frames spread over `frames` (one
  /// pass to its end), each at its state at `log_time(index)` (bridging gaps up to `max_gap`),
  /// with the robot's drawing widened by 1.5 % of the image's diagonal left out. Throws
  /// InputError naming the label when fewer than 8 of them have a state or they are not the
  /// camera's size.
  void learnBackground(FrameSource& frames, const std::function<double(std::size_t)>& log_time, const StateLog& log,
                       double max_gap);
  bool fromRecording() const { return folder_.empty(); }

  /// The IoU of frame `index`'s mask with the robot drawn at `state`; none when the frame has no
  /// mask file or `state` is empty. With masks made from the recording, the mask is `picture`'s
  /// (the frame, 8-bit BGR, before anything is drawn on it) against the background, and the IoU is
  /// taken where the background is known (none when less than a quarter of the drawn robot is). Safe to call from
  /// several threads. Throws calib::MaskError for a mask that cannot be read or is not the camera's size.
  std::optional<double> at(std::size_t index, std::span<const double> state, const cv::Mat& picture = cv::Mat()) const;

  /// How many frames have a mask file (with masks made from the recording: the frames the
  /// background was learnt from).
  std::size_t count() const { return indices_.size(); }
  const std::string& label() const { return label_; }
  /// What is drawn: "visual meshes" or "collision volumes" (RobotDrawing::drawn).
  const std::string& drawn() const { return robot_.drawn(); }

 private:
  std::string folder_, label_;
  const calib::Camera& camera_;
  RobotDrawing robot_;
  std::vector<std::size_t> indices_;  // sorted frame indices with a file (from the recording: the samples')
  // From the recording: where the robot may be at `state`, its (moving) bodies' volumes widened by
  // 1.5 % of the image's diagonal; the background leaves it out.
  cv::Mat regionAt(std::span<const double> state) const;
  std::optional<calib::Background> background_;
};

/// The run's agreement in summary: frames with an IoU, their mean and smallest, and the frames
/// below `low_share` x the median IoU ("low": the state and the video disagree there), lowest first.
struct AgreementSummary {
  std::size_t frames = 0;
  double mean = 0.0, median = 0.0, min = 0.0;
  double low_below = 0.0;        ///< the IoU under which a frame is low
  std::vector<std::size_t> low;  ///< report positions of the low frames, the lowest first
};
AgreementSummary summariseAgreement(std::span<const FrameRecord> frames, double low_share = 0.8);

}  // namespace kccd::overlay
