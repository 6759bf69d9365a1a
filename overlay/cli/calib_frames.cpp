#include "calib_frames.hpp"

#include "cli_args.hpp"
#include "cli_output.hpp"
#include "kccd/overlay/calib_gather.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {

GivenFrames givenFrames(const FrameOptions& a, std::size_t labels, bool tags, const std::optional<Model>& model) {
  std::vector<std::string> picture_names = a.images;
  std::vector<cv::Mat> video_pictures;
  std::vector<double> times = a.times;
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
  } else if (!a.video_frames.empty()) {
    throw UsageError("--frame: needs --video");
  }
  const std::size_t n = picture_names.empty() ? labels : picture_names.size();
  if (n == 0) throw UsageError("give --image FRAME (with --tags and/or --labels) or --labels LABELS (see kccd calib --help)");
  if (!picture_names.empty() && labels != 0 && labels != picture_names.size())
    throw UsageError("--labels: given " + std::to_string(labels) + " times for " + std::to_string(picture_names.size()) +
                     " images: give one labels file per --image, in the same order");
  if (tags && picture_names.empty()) throw UsageError("--tags: needs --image (tags are detected in the images)");
  if (!picture_names.empty() && !tags && labels == 0)
    throw UsageError("--image: give --tags LAYOUT and/or --labels LABELS to say what the image shows");
  if (!a.states.empty() && a.states.size() != 1 && a.states.size() != n)
    throw UsageError("--state: given " + std::to_string(a.states.size()) + " times for " + std::to_string(n) +
                     " frames: give it once (all frames) or once per frame");
  if (!a.states.empty() && !model) throw UsageError("--state: needs --model");
  if (!a.state_log.empty() && !model) throw UsageError("--states: needs --model");
  if (!a.state_log.empty() && !a.states.empty()) throw UsageError("--state and --states: give one of them");
  if (a.state_log.empty() != times.empty())
    throw UsageError(a.state_log.empty() ? "--time: needs --states LOG.csv" : "--states: give each frame's time with --time");
  if (!times.empty() && times.size() != n)
    throw UsageError("--time: given " + std::to_string(times.size()) + " times for " + std::to_string(n) + " frames: give one per frame");
  std::optional<StateLog> log;
  double max_gap = a.max_gap;
  if (!a.state_log.empty()) {
    log = loadStateLog(a.state_log, *model, splitCommas(a.ignore_columns));
    if (max_gap == 0.0) max_gap = 1.5 * log->medianPeriod();
  }

  GivenFrames out;
  out.names = std::move(picture_names);
  out.pictures = std::move(video_pictures);
  out.count = n;
  out.states.resize(n);
  for (std::size_t f = 0; f < n; ++f) {
    if (!a.states.empty()) {
      out.states[f] = parseStateBox(*model, a.states[a.states.size() == 1 ? 0 : f], "", "", "", true).lower;
    } else if (log) {
      std::vector<double> state(static_cast<std::size_t>(model->stateSize()), 0.0);
      if (stateAt(*log, times[f], max_gap, state) == StateMatch::None)
        throw UsageError("--time " + format(times[f]) + ": " + a.state_log + " has no sample within --max-gap " + format(max_gap) +
                         " s of it (the log covers " + format(log->times.front()) + " ... " + format(log->times.back()) + " s)");
      out.states[f] = std::move(state);
    }
  }
  return out;
}

}  // namespace kccd::cli
