#include "kccd/overlay/jobs/overlay_job.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <span>

#include "kccd/input_error.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "kccd/overlay/recording/frame_times.hpp"
#include "kccd/overlay/recording/mask_agreement.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {
namespace {

bool seconds(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(out);
}

std::string filename(const std::string& path) { return std::filesystem::path(path).filename().string(); }

}  // namespace

void parseTimeOffset(const std::string& text, OverlayRequest& r) {
  if (text.rfind("auto:", 0) == 0) {
    const std::string rest = text.substr(5);
    const std::size_t colon = rest.find(':');
    double lo = 0, hi = 0;
    if (colon == std::string::npos || !seconds(rest.substr(0, colon), lo) || !seconds(rest.substr(colon + 1), hi) ||
        !(lo < hi))
      throw requestFieldError(
          "time_offset", "expected auto:A:B with A < B (seconds, the range searched), got '" + printable(text) + "'");
    r.time_offset_search = {lo, hi};
    return;
  }
  if (!seconds(text, r.time_offset))
    throw requestFieldError("time_offset", "expected seconds or auto:A:B, got '" + printable(text) + "'");
}

namespace {

// The request's checks, each field spelled as the front end spells it.
struct Checker {
  const OverlayRequest& r;
  const Model* model;
  const FieldSpelling& spell;

  std::string named(const std::string& field) const { return spelledField(spell, field); }
  InputError problem(const std::string& field, const std::string& text) const {
    return requestFieldError(named(field), text);
  }
  double range(double value, double lo, double hi, const std::string& field) const {
    if (const std::optional<std::string> wrong = rangeProblem(value, lo, hi)) throw problem(field, *wrong);
    return value;
  }
  void recording() const;
  OverlayOptions options() const;
  std::vector<int> maskBodies() const;
};

// Which recording: a video with its log, a robot log or a dataset's episode, and only the fields
// that go with it.
void Checker::recording() const {
  const std::vector<std::pair<bool, const char*>> video_fields{{!r.video.empty(), "video"},
                                                               {!r.states.empty(), "states"},
                                                               {!r.frame_times.empty(), "frame_times"},
                                                               {!r.ignore_columns.empty(), "ignore_columns"}};
  const std::vector<std::pair<bool, const char*>> bag_fields{{!r.image_topic.empty(), "image_topic"},
                                                             {!r.joint_topic.empty(), "joint_topic"}};
  const std::vector<std::pair<bool, const char*>> lerobot_fields{{r.episode != -1, "episode"},
                                                                 {!r.camera_key.empty(), "camera_key"},
                                                                 {r.state_key != "observation.state", "state_key"},
                                                                 {r.frame_by != "auto", "frame_by"}};
  const auto refuse = [&](const std::vector<std::pair<bool, const char*>>& fields, const std::string& why) {
    for (const auto& [given, field] : fields)
      if (given) throw problem(field, why);
  };
  if (!r.bag.empty() && !r.lerobot.empty()) throw problem("lerobot", "not with " + named("bag") + " (one recording)");
  if (!r.bag.empty() || !r.lerobot.empty()) {
    const std::string what = r.bag.empty() ? "lerobot" : "bag";
    refuse(video_fields, "not with " + named(what) + " (the " + (r.bag.empty() ? "dataset" : "log") +
                             " gives the frames, their times and the states)");
    if (r.fps != 0.0) throw problem("fps", "not with " + named(what) + " (each frame has its own time)");
  } else if (r.video.empty() || r.states.empty()) {
    throw InputError("give " + named("video") + " and " + named("states") + ", " + named("bag") + " (a robot log) or " +
                     named("lerobot") + " (a LeRobot dataset)");
  } else if (!r.joint_map.empty()) {
    throw problem("joint_map", "goes with " + named("bag") + " or " + named("lerobot"));
  }
  if (r.bag.empty()) refuse(bag_fields, "goes with " + named("bag"));
  if (r.lerobot.empty()) refuse(lerobot_fields, "goes with " + named("lerobot"));
  if (!r.lerobot.empty()) {
    if (r.episode < 0)
      throw problem("episode", r.episode == -1 ? "give the episode (its episode_index)" : "must be >= 0");
    if (r.state_key.empty()) throw problem("state_key", "must name a feature");
    if (!frameByOf(r.frame_by))
      throw problem("frame_by", "expected 'auto', 'timestamp' or 'index', got '" + printable(r.frame_by) + "'");
  }
  if (r.time_source != "header" && r.bag.empty()) throw problem("time_source", "goes with " + named("bag"));
  if (!timeSourceOf(r.time_source))
    throw problem("time_source", "expected 'header' or 'log', got '" + printable(r.time_source) + "'");
}

// Every number and switch, in the order the fields are listed.
OverlayOptions Checker::options() const {
  OverlayOptions o;
  if (r.fps != 0.0) o.fps = range(r.fps, 1e-6, 1e6, "fps");
  o.time_offset = range(r.time_offset, -1e9, 1e9, "time_offset");
  if (r.time_offset_search) {
    const auto [lo, hi] = *r.time_offset_search;
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi && std::fabs(lo) <= 1e9 && std::fabs(hi) <= 1e9))
      throw problem("time_offset", "the search needs A < B (seconds, within 1e9)");
    o.time_offset_search = r.time_offset_search;
    o.time_offset_label = named("time_offset") + " auto:" + messageNumber(lo) + ":" + messageNumber(hi);
  }
  o.max_gap = range(r.max_gap, 0, 1e300, "max_gap");
  o.swept = r.swept;
  if (r.braking) {
    if (!r.swept) throw problem("braking", "only with " + named("swept") + " (static volumes do not brake)");
    const BrakingParams& b = *r.braking;
    if (const auto wrong = brakingRangeProblem(b)) throw problem("braking." + wrong->first, wrong->second);
    o.braking = b;
  }
  o.plain = r.plain;
  const std::optional<LegendPlace> legend = legendPlaceOf(r.legend);
  if (!legend) throw problem("legend", "expected " + legendPlaceWords() + ", got '" + printable(r.legend) + "'");
  if (r.plain && *legend != LegendPlace::Auto)
    throw problem("legend", "not with " + named("plain") + " (volumes only: no legend is drawn)");
  o.legend = *legend;
  if (r.visuals && model) {
    if (model->visuals.empty()) throw problem("visuals", "the model has no visuals:");
    if (model->visuals.size() + model->bodies.size() > 255)
      throw problem("visuals", "more than 255 bodies and visuals to draw");
  }
  o.visuals = r.visuals;
  if (r.masks.empty() && !r.mask_bodies.empty()) throw problem("mask_bodies", "goes with " + named("masks"));
  o.frames = parseFrameRange(r.frames, named("frames"));
  o.jobs = static_cast<int>(range(r.jobs, 0, 256, "jobs"));
  o.timings = r.timings;
  if (!r.codec.empty() && r.codec.size() != 4)
    throw problem("codec", "a FourCC is 4 characters (e.g. mp4v, avc1, MJPG, FFV1), got '" + printable(r.codec) + "'");
  range(r.contact_frames, 1, 64, "contact_frames");
  o.contact_frames = r.contact_sheet.empty() ? 0 : static_cast<std::size_t>(r.contact_frames);
  return o;
}

std::vector<int> Checker::maskBodies() const {
  std::vector<int> bodies;
  if (!model) return bodies;
  for (const std::string& name : r.mask_bodies) {
    const int b = model->bodyIndex(name);
    if (b < 0)
      throw problem("mask_bodies", "'" + printable(name) + "' is not a body of " +
                                       (r.model_file.empty() ? std::string("the model") : r.model_file));
    bodies.push_back(b);
  }
  return bodies;
}

}  // namespace

void checkOverlayRequest(const OverlayRequest& request, const Model* model, const FieldSpelling& spell) {
  const Checker check{request, model, spell};
  check.recording();
  check.options();
  check.maskBodies();
}

struct OverlayJob::State {
  OverlayRequest request;
  const Model& model;
  const calib::Camera& camera;
  FieldSpelling spell;
  OverlayOutputs outputs;
  OverlayOptions options;
  // The recording as read: its state log, frames and how it was read (a robot log's or a dataset's).
  StateLog log;
  std::vector<double> frame_times;
  std::function<std::unique_ptr<FrameSource>()> open_frames;  ///< a robot log's or a dataset's frames
  std::string recording_label;                                ///< how errors name the frames
  std::vector<std::pair<std::string, std::string>> source;    ///< the report's "source"
  std::vector<std::string> warnings;
  std::optional<MaskAgreement> masks;
  bool ran = false;

  std::string named(const std::string& field) const { return spelledField(spell, field); }
  // A robot log's or a dataset's recording as the job reads it.
  template <class Recording>
  void take(Recording& recording, std::string label) {
    log = std::move(recording.log);
    frame_times = recording.frame_times;
    open_frames = recording.open_frames;
    recording_label = std::move(label);
    source = recording.source();
    warnings = recording.warnings;
  }
};

OverlayJob::OverlayJob(const OverlayRequest& request, const Model& model, const calib::Camera& camera,
                       FieldSpelling spell)
    : s_(std::make_unique<State>(
          State{.request = request, .model = model, .camera = camera, .spell = std::move(spell)})) {
  State& s = *s_;
  const OverlayRequest& r = s.request;
  const Checker check{r, &model, s.spell};
  check.recording();
  s.options = check.options();
  const std::vector<int> mask_bodies = check.maskBodies();
  // A camera fixed to the robot names a frame of this model; its masks cannot be compared (they
  // are drawn from a camera fixed in the world).
  try {
    render::cameraFrame(model, camera, r.camera_file.empty() ? s.named("camera") : r.camera_file);
  } catch (const calib::CameraError& e) {
    throw InputError(e.what());
  }
  if (!camera.frame.empty() && !r.masks.empty())
    throw check.problem(
        "masks", "not with a camera fixed to the robot (the camera file's frame: " + printable(camera.frame, 60) + ")");

  const std::string recording = !r.bag.empty() ? r.bag : !r.lerobot.empty() ? r.lerobot : r.video;
  s.outputs =
      OverlayOutputs{.video = r.output,
                     .png_dir = r.png_dir,
                     .report = r.report,
                     .contact_sheet = r.contact_sheet,
                     .video_option = s.named("output"),
                     .report_option = s.named("report"),
                     .contact_sheet_option = s.named("contact_sheet"),
                     .frames_option = s.named("frames"),
                     .timeline = r.timeline,
                     .timeline_option = s.named("timeline"),
                     .timeline_title = filename(recording) +
                                       (r.model_file.empty() ? std::string() : "  (" + filename(r.model_file) + ")")};
  checkOverlayOutputs(s.outputs, std::vector<std::string>{r.video, r.states, r.model_file, r.camera_file, r.frame_times,
                                                          r.bag, r.joint_map, r.lerobot});

  const JointMap joint_map = r.joint_map.empty() ? JointMap{} : loadJointMap(r.joint_map, model);
  if (!r.bag.empty()) {
    BagRecording bag = readBagRecording({.bag = r.bag,
                                         .joint_topic = r.joint_topic,
                                         .image_topic = r.image_topic,
                                         .time_source = *timeSourceOf(r.time_source),
                                         .joint_map = joint_map,
                                         .spell = s.spell},
                                        model);
    s.take(bag, s.named("bag") + " " + r.bag + " (topic " + bag.image_topic + ")");
  } else if (!r.lerobot.empty()) {
    LerobotRecording episode = readLerobotRecording({.dataset = r.lerobot,
                                                     .episode = r.episode,
                                                     .camera_key = r.camera_key,
                                                     .state_key = r.state_key,
                                                     .frame_by = *frameByOf(r.frame_by),
                                                     .joint_map = joint_map,
                                                     .spell = s.spell},
                                                    model);
    s.take(episode, s.named("lerobot") + " " + r.lerobot + " episode " + std::to_string(r.episode) + " (" +
                        episode.camera_key + ")");
    s.source.insert(s.source.begin(), {{"lerobot", r.lerobot}, {"episode", std::to_string(r.episode)}});
  } else {
    s.log = loadStateLog(r.states, model, r.ignore_columns);
    if (!r.frame_times.empty()) try {
        s.frame_times = loadFrameTimes(r.frame_times);
      } catch (const FrameTimesError& e) {
        throw InputError(s.named("frame_times") + " " + e.what());
      }
    s.recording_label = s.named("video") + " " + r.video;
  }
  if (!r.masks.empty()) {
    const std::string label = s.named("masks") + " " + r.masks;
    if (r.masks == "auto")
      s.masks.emplace(camera, model, mask_bodies, label);
    else
      s.masks.emplace(r.masks, camera, model, mask_bodies, label);
  }
}

OverlayJob::~OverlayJob() = default;

const std::vector<std::string>& OverlayJob::warnings() const { return s_->warnings; }

OverlayJob::Result OverlayJob::run(const std::function<void(const OverlayProgress&)>& progress) {
  State& s = *s_;
  if (s.ran) throw std::logic_error("OverlayJob::run: a job runs once");
  s.ran = true;
  const OverlayRequest& r = s.request;
  OverlayInputs in{s.model,
                   s.camera,
                   s.log,
                   r.video,
                   s.frame_times,
                   s.recording_label,
                   r.camera_file.empty() ? s.named("camera") : r.camera_file,
                   s.named("frame_times") + " " + r.frame_times};
  in.no_rate_hint = "give " + s.named("fps") + " or " + s.named("frame_times");
  in.open_frames = s.open_frames;
  if (s.masks) in.masks = &*s.masks;

  VideoSink sink({.video = r.output,
                  .codec = r.codec,
                  .video_label = s.named("output") + " " + r.output,
                  .png_dir = r.png_dir,
                  .png_label = s.named("png_dir") + " " + r.png_dir});
  Result result;
  result.report = overlayRecording(in, s.options, sink.active() ? &sink : nullptr, progress);
  result.report.source = s.source;
  result.json = writeOverlayOutputs(s.outputs, result.report, s.model, sink);
  return result;
}

}  // namespace kccd::overlay
