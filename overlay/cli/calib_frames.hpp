// The frames of a calibration as the command line gives them: pictures (--image files, or --frame
// of --video, of a robot log's --bag or of a LeRobot --episode) and each frame's state (--state, --states at --time, or
// the bag's joint states at the frame's time). Shared by `kccd calib` and `kccd calib label`, so both read the same
// options the same way.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/calibration/calib_refine.hpp"

namespace kccd::cli {

/// The options that say which frames and which states.
struct FrameOptions {
  std::vector<std::string> images, states;
  std::string state_log, ignore_columns, video;
  std::string bag, image_topic, joint_topic, joint_map, time_source = "header";  ///< --bag and its options
  std::string lerobot, camera_key, state_key = "observation.state";              ///< --lerobot and its options
  long episode = -1;
  std::vector<double> times;
  std::vector<int> video_frames;
  double max_gap = 0.0;  ///< 0: 1.5 x the log's median period
  std::size_t recording_samples =
      0;  ///< > 0: also about this many frames spread over the --video or --bag, with their states
};

/// The frames the options give, in order.
struct GivenFrames {
  std::vector<std::string> names;  ///< the image files, or "VIDEO#N"; empty: labels only
  std::vector<cv::Mat> pictures;   ///< the decoded frames of --video; empty: read `names` as image files
  std::vector<std::optional<std::vector<double>>> states;  ///< one per frame
  std::size_t count = 0;                                   ///< frames (pictures, or labels files when there are none)
  std::vector<std::string> warnings;                       ///< one line each (e.g. a bag cut short)
  std::vector<overlay::RecordingSample> recording;  ///< with recording_samples: those of them the log has a state for
};

/// Adds --bag, --image-topic, --joint-topic, --time-source and --joint-map to `command`, and
/// --lerobot, --episode, --camera-key and --state-key (a LeRobot episode's frames and states).
void addBagOptions(CLI::App& command, FrameOptions& o);

/// Checks the options against each other (`labels` labels files and `tags` a tag layout given)
/// and reads the recording's frames and the state log; `refined`: masks or edges say what the
/// pictures show. Throws UsageError (also for recording_samples without a recording and a state
/// log, or with fewer than 8 of its frames in the log), or the readers' errors.
GivenFrames givenFrames(const FrameOptions& o, std::size_t labels, bool tags, const std::optional<Model>& model,
                        bool refined = false);

}  // namespace kccd::cli
