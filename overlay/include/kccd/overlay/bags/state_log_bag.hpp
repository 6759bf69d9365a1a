// A state log written as a robot log: a ROS 2 bag (one MCAP file) of sensor_msgs/msg/JointState,
// one message per sample, and optionally the camera's frames as sensor_msgs/msg/CompressedImage
// (JPEG, as image_transport's compressed plugin publishes them) added as they are made, so that
// what reads bags (`kccd check --bag`, `bag info`, `bag export`, `overlay --bag`, `calib --bag`)
// runs on a log the suite made.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "kccd/state_log.hpp"

namespace cv {
class Mat;
}

namespace kccd::overlay {

/// Where the samples and frames go and on which clock.
struct StateLogBagOptions {
  std::string topic = "/joint_states";  ///< the JointState channel's topic
  /// The header stamp (and log time) of log time 0, nanoseconds since the epoch; the default is
  /// 2023-11-14 22:13:20 UTC, a clock's time where a reader takes 0 for a stamp left unset.
  std::int64_t origin_ns = 1'700'000'000'000'000'000;
  std::string label;                                         ///< names the output in errors (default: the path)
  std::string image_topic = "/camera/image_raw/compressed";  ///< the CompressedImage channel's topic
  std::string image_frame_id = "camera";                     ///< the frames' header.frame_id
  int jpeg_quality = 90;                                     ///< OpenCV's IMWRITE_JPEG_QUALITY (1 ... 100)
};

/// The format field of the frames: the image's encoding and what it was compressed to, as
/// image_transport's compressed plugin writes it ("bgr8; jpeg compressed bgr8").
inline constexpr char kBagImageFormat[] = "bgr8; jpeg compressed bgr8";

/// Writes a state log as an MCAP file at `path` through a StagedOutput (it appears whole or not at
/// all), with camera frames added one at a time (only one frame is held at a time). Per sample a
/// JointState stamped, and logged and published at, origin_ns + its time rounded to the
/// nanosecond, naming the state values, their positions, and their velocities when the log has
/// every NAME.vel column (none otherwise); per frame a CompressedImage (its JPEG bytes) stamped,
/// logged and published the same way at the time it was given on the log's clock. Messages are in
/// log-time order across both topics (a sample before a frame of the same nanosecond); the image
/// channel is added with the first frame. Not thread-safe: one thread at a time.
class StateLogBagWriter {
 public:
  /// Opens the file and the JointState channel. Throws InputError when a sample's stamp falls
  /// outside 1970 ... 2038 or two samples round to one nanosecond, OutputError when the file cannot
  /// be created; std::invalid_argument for a JPEG quality outside 1 ... 100. `log` must outlive
  /// the writer.
  StateLogBagWriter(const StateLog& log, const std::filesystem::path& path, const StateLogBagOptions& options = {});
  ~StateLogBagWriter();  ///< without finish(): nothing is left at `path`
  StateLogBagWriter(const StateLogBagWriter&) = delete;
  StateLogBagWriter& operator=(const StateLogBagWriter&) = delete;

  /// Adds a camera frame (CV_8UC3, BGR) taken at `time` seconds on the log's clock: the samples up
  /// to its stamp, then the frame, JPEG-encoded at options.jpeg_quality. Throws InputError for a
  /// stamp outside 1970 ... 2038 or not after the previous frame's, OutputError when the frame
  /// cannot be encoded; std::invalid_argument for an empty or non-BGR image, or after finish().
  void addImage(double time, const cv::Mat& bgr);

  /// Writes the samples after the last frame, ends the file, checks that every byte was written
  /// and moves it into place. Throws OutputError.
  void finish();

  /// Frames added so far.
  std::size_t images() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes `log` as an MCAP file at `path` with no frames (a StateLogBagWriter finished at once).
/// Throws as StateLogBagWriter does.
void writeStateLogBag(const StateLog& log, const std::filesystem::path& path, const StateLogBagOptions& options = {});

}  // namespace kccd::overlay
