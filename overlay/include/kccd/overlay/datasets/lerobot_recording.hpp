// One episode of a LeRobot dataset read as the overlay's recording (`kccd overlay --lerobot DIR
// --episode N`): its state rows as a state log of the model's values, and one camera's frames with
// their times. A row and a frame go together as LeRobot's own loader pairs them: the video frame
// nearest the row's timestamp (+ the episode's start in a v3.0 video) within 1e-4 s; rows whose
// timestamps are off the video's frame grid are paired by frame_index instead, with a warning.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "kccd/input_error.hpp"
#include "kccd/logs/lerobot_dataset.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/bags/joint_map.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// How a row finds its frame: by timestamp (LeRobot's rule, 1e-4 s), by frame_index, or by
/// timestamp when every row is on the frame grid and by frame_index otherwise (auto).
enum class FrameBy : std::uint8_t { Auto, Timestamp, Index };
/// "auto", "timestamp" or "index"; none otherwise.
std::optional<FrameBy> frameByOf(const std::string& word);

/// Which dataset, episode, camera and state.
struct LerobotRecordingOptions {
  std::string dataset;                          ///< the dataset's folder
  long episode = -1;                            ///< its episode_index
  std::string camera_key;                       ///< a camera feature (default: the only one, else an error)
  std::string state_key = "observation.state";  ///< the vector feature read as the state
  FrameBy frame_by = FrameBy::Auto;
  JointMap joint_map;   ///< how the state's values become the model's (empty: by name)
  bool frames = true;   ///< false: the state alone (kccd check), no camera chosen or opened
  FieldSpelling spell;  ///< how messages name these fields (e.g. "--camera-key")
};

/// The episode as a recording.
struct LerobotRecording {
  StateLog log;                     ///< the model's state values, at each row's frame time
  std::vector<double> frame_times;  ///< each frame's time (s from the episode's first frame)
  /// Opens the episode's frames of the camera (decoded to BGR), once per pass.
  std::function<std::unique_ptr<FrameSource>()> open_frames;
  double fps = 0.0;  ///< the dataset's
  std::string camera_key, data_file, video_file;
  FrameBy frame_by = FrameBy::Timestamp;  ///< how the rows were paired with frames
  std::vector<std::string> warnings;      ///< what does not match the format, and what was done
  /// How the recording was read, as the overlay report's "source".
  std::vector<std::pair<std::string, std::string>> source() const;
};

/// The episode's frames at `indices` (from 0, any order, repeats allowed), in that order, with
/// their times on the state log's clock in `times`: one pass over the frames up to the last index.
/// Throws InputError "`option` N: the episode has K frames (0 ... K-1)" for an index beyond them.
std::vector<cv::Mat> lerobotFramesAt(const LerobotRecording& recording, const std::vector<long>& indices,
                                     const std::string& option, std::vector<double>& times);

/// Reads episode `options.episode`: its rows, its camera's video (or images in the table), and
/// checks that the video holds a frame for every row. Throws InputError naming the file and
/// place (a missing video, an episode out of range, timestamps the video does not hold).
LerobotRecording readLerobotRecording(const LerobotRecordingOptions& options, const Model& model);

}  // namespace kccd::overlay
