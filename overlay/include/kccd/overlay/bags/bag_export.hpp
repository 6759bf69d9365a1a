// A robot log written as the suite's own files (`kccd bag export`): joint states as a state log
// CSV, camera images as a video with its frame-times file, camera info as an intrinsics file, so
// every other command works on a bag.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/logs/message_value.hpp"

namespace kccd::overlay {

/// Which clock a message's time comes from.
enum class TimeSource {
  Header,  ///< the header stamp (the log time where a stamp is zero, with a warning)
  Log,     ///< the time the recorder logged it
};
/// "header" or "log": the words of --time-source and of the reports.
const char* toString(TimeSource source);
/// The clock a word names ("header" or "log"), or none.
std::optional<TimeSource> timeSourceOf(std::string_view word);

/// What to export and where. Outputs left empty are not written; at least one is needed.
struct BagExportOptions {
  std::string bag;
  std::string states, video, frame_times, camera_info;  ///< .csv, .mp4/.mkv/.avi, .csv, .yaml
  /// Topics; empty: the one topic of the fitting type (an error naming the candidates when there
  /// are several or none).
  std::string joint_topic, image_topic, camera_info_topic;
  TimeSource time_source = TimeSource::Header;
  /// Time 0 of the written files, nanoseconds on the chosen clock; default: the earliest time
  /// exported (of the joint states and the images alike).
  std::optional<std::uint64_t> origin_ns;
  FieldSpelling spell;  ///< how messages name these fields (e.g. "--frame-times"; default: as they are)
};

/// What was written.
struct BagExportReport {
  std::string joint_topic, image_topic, camera_info_topic;
  std::vector<std::string> joints;  ///< the state log's columns, in the first message's order
  bool velocities = false;          ///< NAME.vel columns (every message gave velocities)
  std::size_t states = 0, frames = 0;
  /// Messages left out because their time was not after the previous one's (the files need
  /// strictly increasing times), and zero header stamps replaced by the log time.
  std::size_t dropped_states = 0, dropped_frames = 0, log_time_stamps = 0;
  std::uint64_t origin_ns = 0;  ///< time 0 of the written files, nanoseconds on the chosen clock
  double fps = 0.0;             ///< the video's nominal rate (the median frame interval)
  int width = 0, height = 0;
  std::string damage;                 ///< where the log was cut short, if it was
  std::vector<std::string> warnings;  ///< one line each
};

/// Reads the log twice (what is there, then the outputs) and writes the outputs through staged
/// files, all or none. Throws InputError (the log, a topic, a message) or OutputError.
BagExportReport exportBag(const BagExportOptions& options);

/// A sensor_msgs Image (rgb8, bgr8, rgba8, bgra8, mono8, mono16, bayer_*8) or CompressedImage
/// (any format OpenCV decodes: jpeg, png) as an 8-bit BGR frame. Throws InputError with `where`.
cv::Mat imageOf(const logs::Value& message, bool compressed, const std::string& where);

}  // namespace kccd::overlay
