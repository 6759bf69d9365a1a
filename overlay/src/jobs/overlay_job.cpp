#include "kccd/overlay/jobs/overlay_job.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <span>

#include "kccd/input_error.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/recording/frame_times.hpp"
#include "kccd/overlay/recording/mask_agreement.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {
namespace {

// A problem with one field, spelled as the front end spells it.
InputError fieldError(const std::string& spelled, const std::string& problem) {
  return InputError(InputLocation{{}, 0, 0, spelled}, problem);
}

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
      throw fieldError("time_offset",
                       "expected auto:A:B with A < B (seconds, the range searched), got '" + printable(text) + "'");
    r.time_offset_search = {lo, hi};
    return;
  }
  if (!seconds(text, r.time_offset))
    throw fieldError("time_offset", "expected seconds or auto:A:B, got '" + printable(text) + "'");
}

namespace {

// The request's checks, each field spelled as the front end spells it.
struct Checker {
  const OverlayRequest& r;
  const Model* model;
  const FieldSpelling& spell;

  std::string named(const std::string& field) const { return spelledField(spell, field); }
  InputError problem(const std::string& field, const std::string& text) const { return fieldError(named(field), text); }
  double range(double value, double lo, double hi, const std::string& field) const {
    if (const std::optional<std::string> wrong = rangeProblem(value, lo, hi)) throw problem(field, *wrong);
    return value;
  }
  void recording() const;
  OverlayOptions options() const;
  std::vector<int> maskBodies() const;
};

// Which recording: a video with its log, or a robot log, and only the fields that go with it.
void Checker::recording() const {
  if (!r.bag.empty()) {
    for (const auto& [given, field] : {std::pair{!r.video.empty(), "video"},
                                       {!r.states.empty(), "states"},
                                       {!r.frame_times.empty(), "frame_times"},
                                       {!r.ignore_columns.empty(), "ignore_columns"}})
      if (given)
        throw problem(field, "not with " + named("bag") + " (the log gives the frames, their times and the states)");
    if (r.fps != 0.0) throw problem("fps", "not with " + named("bag") + " (each frame has its own time)");
  } else {
    if (r.video.empty() || r.states.empty())
      throw InputError("give " + named("video") + " and " + named("states") + ", or " + named("bag") +
                       " (a robot log)");
    for (const auto& [given, field] : {std::pair{!r.image_topic.empty(), "image_topic"},
                                       {!r.joint_topic.empty(), "joint_topic"},
                                       {!r.joint_map.empty(), "joint_map"}})
      if (given) throw problem(field, "goes with " + named("bag"));
  }
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
    range(b.latency, 0, 1e3, "braking.latency");
    range(b.deceleration, 1e-9, 1e9, "braking.deceleration");
    range(b.max_acceleration, 0, 1e9, "braking.max_acceleration");
    range(b.position_error, 0, 1e3, "braking.position_error");
    range(b.velocity_error, 0, 1e6, "braking.velocity_error");
    o.braking = b;
  }
  o.plain = r.plain;
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
  std::optional<BagRecording> bag;
  StateLog log;
  std::vector<double> frame_times;
  std::optional<MaskAgreement> masks;
  bool ran = false;

  std::string named(const std::string& field) const { return spelledField(spell, field); }
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

  const std::string recording = r.bag.empty() ? r.video : r.bag;
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
                                                          r.bag, r.joint_map});

  if (!r.bag.empty()) {
    s.bag = readBagRecording({.bag = r.bag,
                              .joint_topic = r.joint_topic,
                              .image_topic = r.image_topic,
                              .time_source = *timeSourceOf(r.time_source),
                              .joint_map = r.joint_map.empty() ? JointMap{} : loadJointMap(r.joint_map, model),
                              .spell = s.spell},
                             model);
    s.log = std::move(s.bag->log);
    s.frame_times = s.bag->frame_times;
  } else {
    s.log = loadStateLog(r.states, model, r.ignore_columns);
    if (!r.frame_times.empty()) try {
        s.frame_times = loadFrameTimes(r.frame_times);
      } catch (const FrameTimesError& e) {
        throw InputError(s.named("frame_times") + " " + e.what());
      }
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

const std::vector<std::string>& OverlayJob::warnings() const {
  static const std::vector<std::string> none;
  return s_->bag ? s_->bag->warnings : none;
}

OverlayJob::Result OverlayJob::run(const std::function<void(const OverlayProgress&)>& progress) {
  State& s = *s_;
  if (s.ran) throw std::logic_error("OverlayJob::run: a job runs once");
  s.ran = true;
  const OverlayRequest& r = s.request;
  OverlayInputs in{
      s.model,
      s.camera,
      s.log,
      s.bag ? r.bag : r.video,
      s.frame_times,
      s.bag ? s.named("bag") + " " + r.bag + " (topic " + s.bag->image_topic + ")" : s.named("video") + " " + r.video,
      r.camera_file.empty() ? s.named("camera") : r.camera_file,
      s.named("frame_times") + " " + r.frame_times};
  in.no_rate_hint = "give " + s.named("fps") + " or " + s.named("frame_times");
  if (s.bag) in.open_frames = s.bag->open_frames;
  if (s.masks) in.masks = &*s.masks;

  VideoSink sink({.video = r.output,
                  .codec = r.codec,
                  .video_label = s.named("output") + " " + r.output,
                  .png_dir = r.png_dir,
                  .png_label = s.named("png_dir") + " " + r.png_dir});
  Result result;
  result.report = overlayRecording(in, s.options, sink.active() ? &sink : nullptr, progress);
  if (s.bag) result.report.source = s.bag->source();
  result.json = writeOverlayOutputs(s.outputs, result.report, s.model, sink);
  return result;
}

}  // namespace kccd::overlay
