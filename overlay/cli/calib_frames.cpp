#include "calib_frames.hpp"

#include <algorithm>

#include "cli_args.hpp"
#include "cli_output.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

// About `a.recording_samples` frames spread over the recording (`bag`, else --video) with their
// states in `log` (for masks made from the recording); those without a state left out.
std::vector<overlay::RecordingSample> recordingSamples(const FrameOptions& a, const overlay::BagRecording* bag,
                                                       const StateLog* log, const Model& model, double max_gap,
                                                       const std::string& log_name) {
  std::vector<overlay::RecordingSample> out;
  if (a.video.empty() && !bag)
    throw UsageError("--masks auto: makes the masks from a recording: give --video (with --states) or --bag");
  if (!log)
    throw UsageError("--masks auto: needs each frame's state: give --states LOG.csv (or --bag with joint states)");
  std::vector<int> indices;
  std::vector<cv::Mat> pictures;
  std::vector<double> sample_times;
  if (bag) {
    const std::size_t frames = bag->frame_times.size();
    for (std::size_t k = 0; k < std::min(frames, a.recording_samples); ++k)
      indices.push_back(static_cast<int>(k * frames / std::min(frames, a.recording_samples)));
    pictures = overlay::framesAt(*bag, std::vector<long>(indices.begin(), indices.end()), "--masks auto");
    for (const int i : indices) sample_times.push_back(bag->frame_times[static_cast<std::size_t>(i)]);
  } else {
    overlay::RecordingFrames r =
        overlay::sampleRecordingFrames(a.video, a.recording_samples, indices, "--video " + a.video);
    if (!(r.fps > 0.0))
      throw UsageError("--masks auto: --video " + a.video + " declares no frame rate, so its frames have no times");
    pictures = std::move(r.frames);
    // The frames' --time, when given, says where the log's clock stands against frame / fps.
    const double offset = a.times.empty() ? 0.0 : a.times.front() - a.video_frames.front() / r.fps;
    for (const int i : indices) sample_times.push_back(i / r.fps + offset);
  }
  for (std::size_t k = 0; k < pictures.size(); ++k) {
    std::vector<double> state(static_cast<std::size_t>(model.stateSize()), 0.0);
    if (stateAt(*log, sample_times[k], max_gap, state) != StateMatch::None)
      out.push_back({pictures[k], std::move(state)});
  }
  if (out.size() < 8)
    throw UsageError("--masks auto: only " + std::to_string(out.size()) + " of " + std::to_string(pictures.size()) +
                     " frames spread over the recording have a state in " + log_name + " (8 or more needed)");
  return out;
}

// --lerobot's --frame N of --episode E: the pictures, their names and times on the episode's clock,
// and the episode's rows as the state log (with --model).
StateLog lerobotFrames(const FrameOptions& a, const std::optional<Model>& model, std::vector<cv::Mat>& pictures,
                       std::vector<std::string>& names, std::vector<double>& times,
                       std::vector<std::string>& warnings) {
  if (!a.images.empty() || !a.video.empty() || !a.bag.empty())
    throw UsageError("--lerobot: give --image files, --video, --bag or --lerobot, one of them");
  if (a.video_frames.empty())
    throw UsageError("--lerobot: say which frames of the episode with --frame N (repeat for several)");
  if (!a.state_log.empty() || !a.times.empty() || !a.ignore_columns.empty())
    throw UsageError("--states, --time and --ignore-columns: not with --lerobot (its rows give each frame's state)");
  if (!model) throw UsageError("--lerobot: needs --model (the episode's rows are read as the model's states)");
  if (!a.image_topic.empty() || !a.joint_topic.empty())
    throw UsageError("--image-topic and --joint-topic go with --bag");
  const overlay::LerobotRecording rec = overlay::readLerobotRecording(
      {.dataset = a.lerobot,
       .episode = a.episode,
       .camera_key = a.camera_key,
       .state_key = a.state_key,
       .joint_map = a.joint_map.empty() ? overlay::JointMap{} : overlay::loadJointMap(a.joint_map, *model),
       .spell = [](const std::string& field) { return optionSpelling(field); }},
      *model);
  for (const std::string& w : rec.warnings) warnings.push_back(w);
  pictures =
      overlay::lerobotFramesAt(rec, std::vector<long>(a.video_frames.begin(), a.video_frames.end()), "--frame", times);
  for (const int f : a.video_frames)
    names.push_back(a.lerobot + "#" + std::to_string(a.episode) + "/" + std::to_string(f));
  return rec.log;
}

}  // namespace

GivenFrames givenFrames(const FrameOptions& a, std::size_t labels, bool tags, const std::optional<Model>& model,
                        bool refined) {
  std::vector<std::string> picture_names = a.images;
  std::vector<cv::Mat> video_pictures;
  std::vector<double> times = a.times;
  std::optional<overlay::BagRecording> bag;
  std::vector<std::string> warnings;
  bool episode = false;  // --lerobot: the episode's states are in `log`
  std::optional<StateLog> episode_log;
  if (!a.bag.empty()) {
    if (!a.images.empty() || !a.video.empty())
      throw UsageError("--bag: give --image files, --video or --bag, one of them");
    if (a.video_frames.empty())
      throw UsageError("--bag: say which frames of its image topic with --frame N (repeat for several)");
    if (!a.state_log.empty() || !a.times.empty() || !a.ignore_columns.empty())
      throw UsageError(
          "--states, --time and --ignore-columns: not with --bag (its joint states give each frame's state at the "
          "frame's time)");
    const overlay::BagRecordingOptions bo{
        .bag = a.bag,
        .joint_topic = a.joint_topic,
        .image_topic = a.image_topic,
        .time_source = *overlay::timeSourceOf(a.time_source),  // checked by the option
        .joint_map = a.joint_map.empty() || !model ? overlay::JointMap{} : overlay::loadJointMap(a.joint_map, *model),
        .spell = [](const std::string& field) { return optionSpelling(field); }};
    if (!a.joint_map.empty() && !model) throw UsageError("--joint-map: needs --model");
    // With a model (and no --state) the joint states give each frame's state; else the images alone.
    bag = model && a.states.empty() ? overlay::readBagRecording(bo, *model) : overlay::readBagImages(bo);
    for (const std::string& w : bag->warnings) warnings.push_back("--bag " + a.bag + ": " + w);
    video_pictures =
        overlay::framesAt(*bag, std::vector<long>(a.video_frames.begin(), a.video_frames.end()), "--frame");
    for (const int f : a.video_frames) {
      picture_names.push_back(a.bag + "#" + std::to_string(f));
      if (bag->log.rows() > 0) times.push_back(bag->frame_times[static_cast<std::size_t>(f)]);
    }
  } else if (!a.lerobot.empty()) {
    if (a.episode < 0) throw UsageError("--lerobot: give --episode N (its episode_index)");
    episode_log = lerobotFrames(a, model, video_pictures, picture_names, times, warnings);
    episode = true;
  } else if (!a.image_topic.empty() || !a.joint_topic.empty() || !a.joint_map.empty()) {
    throw UsageError("--image-topic, --joint-topic and --joint-map go with --bag");
  }
  if (a.lerobot.empty() && (a.episode != -1 || !a.camera_key.empty() || a.state_key != "observation.state"))
    throw UsageError("--episode, --camera-key and --state-key go with --lerobot");
  if (!a.video.empty()) {
    if (!a.images.empty()) throw UsageError("--video: give --image files or --video with --frame, not both");
    if (a.video_frames.empty()) throw UsageError("--video: say which frames with --frame N (repeat for several)");
    overlay::RecordingFrames recording = overlay::readRecordingFrames(a.video, a.video_frames, "--video " + a.video);
    video_pictures = std::move(recording.frames);
    for (int f : a.video_frames) picture_names.push_back(a.video + "#" + std::to_string(f));
    if (!a.state_log.empty() && times.empty()) {
      if (!(recording.fps > 0.0))
        throw UsageError("--video " + a.video + ": no frame rate: give each frame's time with --time");
      for (int f : a.video_frames) times.push_back(f / recording.fps);
    }
  } else if (!a.video_frames.empty() && a.bag.empty() && !episode) {
    throw UsageError("--frame: needs --video, --bag or --lerobot");
  }
  const std::size_t n = picture_names.empty() ? labels : picture_names.size();
  if (n == 0)
    throw UsageError("give --image FRAME (with --tags and/or --labels) or --labels LABELS (see kccd calib --help)");
  if (!picture_names.empty() && labels != 0 && labels != picture_names.size())
    throw UsageError("--labels: given " + std::to_string(labels) + " times for " +
                     std::to_string(picture_names.size()) +
                     " images: give one labels file per --image, in the same order");
  if (tags && picture_names.empty()) throw UsageError("--tags: needs --image (tags are detected in the images)");
  if (!picture_names.empty() && !tags && labels == 0 && !refined)
    throw UsageError(
        "--image: give --tags LAYOUT, --labels LABELS and/or --masks MASK (or --refine edges) to say what the image "
        "shows");
  if (!a.states.empty() && a.states.size() != 1 && a.states.size() != n)
    throw UsageError("--state: given " + std::to_string(a.states.size()) + " times for " + std::to_string(n) +
                     " frames: give it once (all frames) or once per frame");
  if (!a.states.empty() && !model) throw UsageError("--state: needs --model");
  if (!a.state_log.empty() && !model) throw UsageError("--states: needs --model");
  if (!a.state_log.empty() && !a.states.empty()) throw UsageError("--state and --states: give one of them");
  if (a.state_log.empty() != times.empty() && !bag && !episode)
    throw UsageError(a.state_log.empty() ? "--time: needs --states LOG.csv"
                                         : "--states: give each frame's time with --time");
  if (!times.empty() && times.size() != n)
    throw UsageError("--time: given " + std::to_string(times.size()) + " times for " + std::to_string(n) +
                     " frames: give one per frame");
  std::optional<StateLog> log;
  double max_gap = a.max_gap;
  if (!a.state_log.empty()) log = loadStateLog(a.state_log, *model, splitCommas(a.ignore_columns));
  if (bag && bag->log.rows() > 0) log = std::move(bag->log);
  if (episode_log && a.states.empty()) log = std::move(episode_log);
  if (log && max_gap == 0.0) max_gap = 1.5 * log->medianPeriod();
  const std::string log_name = bag ? "--bag " + a.bag : episode ? "--lerobot " + a.lerobot : a.state_log;

  GivenFrames out;
  if (a.recording_samples > 0)
    out.recording = recordingSamples(a, bag ? &*bag : nullptr, log ? &*log : nullptr, *model, max_gap, log_name);
  out.names = std::move(picture_names);
  out.pictures = std::move(video_pictures);
  out.count = n;
  out.warnings = std::move(warnings);
  out.states.resize(n);
  for (std::size_t f = 0; f < n; ++f) {
    if (!a.states.empty()) {
      out.states[f] = parseStateBox(*model, a.states[a.states.size() == 1 ? 0 : f], "", "", "", true).lower;
    } else if (log) {
      std::vector<double> state(static_cast<std::size_t>(model->stateSize()), 0.0);
      if (stateAt(*log, times[f], max_gap, state) == StateMatch::None)
        throw UsageError(
            (bag || episode ? "--frame " + std::to_string(a.video_frames[f]) + " (at " + format(times[f]) + " s)"
                            : "--time " + format(times[f])) +
            ": " + log_name + " has no sample within --max-gap " + format(max_gap) + " s of it (the log covers " +
            format(log->times.front()) + " ... " + format(log->times.back()) + " s)");
      out.states[f] = std::move(state);
    }
  }
  return out;
}

void addBagOptions(CLI::App& command, FrameOptions& o) {
  command.add_option("--bag", o.bag,
                     "A robot log (MCAP, rosbag2 .db3 or folder, ROS 1 .bag) whose image topic's --frame N are the "
                     "frames; with --model "
                     "(and no --state) its joint states give each frame's state at the frame's time");
  command.add_option("--image-topic", o.image_topic,
                     "With --bag: the sensor_msgs/Image or CompressedImage topic (default: the only one)");
  command.add_option("--joint-topic", o.joint_topic,
                     "With --bag: the sensor_msgs/JointState topic (default: the only one)");
  command
      .add_option("--time-source", o.time_source,
                  "With --bag: header (the messages' header stamps) or log (the recorder's times)")
      ->check(CLI::IsMember({"header", "log"}))
      ->default_str("header");
  command.add_option("--joint-map", o.joint_map,
                     "With --bag or --lerobot: which logged joint each state value is read from (see kccd overlay "
                     "--help)");
  command.add_option("--lerobot", o.lerobot,
                     "A LeRobot dataset's folder: --frame N of --episode's camera are the frames, its rows (read "
                     "against --model) each frame's state");
  command.add_option("--episode", o.episode, "With --lerobot: the episode (its episode_index)");
  command.add_option("--camera-key", o.camera_key, "With --lerobot: the camera feature (default: the only one)");
  command.add_option("--state-key", o.state_key, "With --lerobot: the vector feature read as the state")
      ->capture_default_str();
}

}  // namespace kccd::cli
