// A robot log read as the overlay's recording (`kccd overlay --bag`): its joint states as a state
// log of the model's joints, matched by name, and its image topic as frames with their times.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kccd/model.hpp"
#include "kccd/overlay/bags/bag_export.hpp"
#include "kccd/overlay/bags/joint_map.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// Which log, topics (empty: the one of the fitting type) and clock.
struct BagRecordingOptions {
  std::string bag;
  std::string joint_topic, image_topic;
  TimeSource time_source = TimeSource::Header;
  /// Where each state value comes from; empty (no states): every state value by its own name.
  JointMap joint_map;
  FieldSpelling spell;  ///< how messages name these fields (e.g. "--joint-topic"; default: as they are)
  bool frames = true;   ///< false: the joint states alone (kccd check), no image topic chosen
};

/// The recording: what OverlayInputs takes, and what was found.
struct BagRecording {
  StateLog log;                     ///< the model's state values over time (seconds from origin_ns)
  std::vector<double> frame_times;  ///< each frame's time on the same clock
  /// Opens the frames (a pass over the log's image topic, decoded to BGR): OverlayInputs::open_frames.
  std::function<std::unique_ptr<FrameSource>()> open_frames;
  std::string bag;  ///< the log read
  std::string joint_topic, image_topic;
  std::uint64_t origin_ns = 0;
  double fps = 0.0;  ///< the median frame interval's rate
  std::vector<std::string> warnings;
  /// How the log was read, as the overlay report's "source" (OverlayReport::source): the bag, the
  /// topics, the clock, time 0 in nanoseconds and the joint map's file.
  std::vector<std::pair<std::string, std::string>> source() const;
  TimeSource time_source = TimeSource::Header;
  std::string joint_map;  ///< the joint map's file ("" when none)
};

/// Reads what the overlay needs from the log. Every state value of `model` must be given by the
/// joint states, by its own name or as the joint map says (an InputError naming the joint and the
/// names the log has); logged joints not read are left out with one warning. Images and joint states whose time is not
/// after the previous one's on their topic are left out (a warning). Throws InputError.
BagRecording readBagRecording(const BagRecordingOptions& options, const Model& model);

/// The image topic's frames at `indices` (any order, repeats allowed), in that order: one pass over
/// the log, up to the last index. Throws InputError "`option` N: BAG has K images on TOPIC (frames 0
/// ... K-1)" for an index beyond them (`option` names where the index was given, e.g. "--frame").
std::vector<cv::Mat> framesAt(const BagRecording& recording, const std::vector<long>& indices,
                              const std::string& option);

/// The log's images alone, for a command without a model: `frame_times`, `open_frames`, `fps`,
/// `image_topic` and `origin_ns` (time 0: the first image's time); no joint topic is chosen and
/// `log` is left empty. Throws InputError.
BagRecording readBagImages(const BagRecordingOptions& options);

}  // namespace kccd::overlay
