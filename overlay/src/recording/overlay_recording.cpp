// The frame pipeline: one reader thread decodes frames in order; annotator threads (one Checker
// and one Renderer, hence one GL context, each, at a lower priority) query, render and composite;
// the calling thread hands the frames to the sink in input order. At most `2 x jobs + 2` frames are in flight, so
// memory stays bounded whatever the video's length.
#include "kccd/overlay/recording/overlay_recording.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <thread>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/input_error.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/recording/contact_sheet.hpp"
#include "kccd/overlay/recording/legend_corner.hpp"
#include "kccd/overlay/recording/timeline.hpp"
#include "kccd/overlay/recording/video_source.hpp"
#include "kccd/render/projection.hpp"

namespace kccd::overlay {
namespace {

struct FrameJob {
  std::size_t index = 0;
  cv::Mat bgr;
  FrameRecord record;
};

// The annotators run this many nice levels below the reader and the writer. Decoding and encoding
// are the pipeline's serial stages: on a machine with fewer cores than busy threads (the codec's,
// the annotators', the rasteriser's), a frame's encoding that waits for a core delays every frame
// behind it, while the annotators only need to keep up on average.
constexpr int kAnnotatorNice = 10;

// Lowers the calling thread's priority by `steps` nice levels (Linux: nice is per thread; threads
// it starts, such as the GL rasteriser's, inherit it). Best effort: a refusal changes nothing but speed.
void lowerThreadPriority(int steps) {
  if (steps <= 0) return;
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int now = ::getpriority(PRIO_PROCESS, tid);
  if (errno == 0) (void)::setpriority(PRIO_PROCESS, tid, std::min(19, now + steps));
}

// One run's frames between its three stages, under one mutex: the reader decodes them in order
// (at most `max_in_flight` at a time), the annotators check and draw them in any order, the writer
// (the calling thread) takes them back in input order. The first error stops every stage.
struct Pipeline {
  const OverlayInputs& in;
  const OverlayOptions& opt;
  FrameSource& video;
  const FrameClock& clock;
  const std::string& video_label;
  const std::string& camera_label;
  std::size_t expected;  // frames the video declares (0: unknown)
  std::size_t max_in_flight;

  std::mutex mu;
  std::condition_variable wake;
  std::deque<FrameJob> todo;
  std::map<std::size_t, FrameJob> done;
  std::vector<cv::Mat> spare;  // handed-on frames' buffers, decoded into again (no allocation per frame)
  std::size_t in_flight = 0, decoded = 0;
  bool reader_done = false, abort = false;
  std::exception_ptr error;

  void fail(const std::exception_ptr& e) {
    std::lock_guard lock(mu);
    if (!error) error = e;
    abort = true;
    wake.notify_all();
  }

  // Frame `index` decoded into job.bgr (8-bit BGR of the camera's size) with its time; false at
  // the video's end. Throws when the end comes early or a frame does not fit.
  bool decode(std::size_t index, FrameJob& job) {
    const auto count = [](std::size_t n) { return std::to_string(n); };
    const auto t_decode = std::chrono::steady_clock::now();
    if (!video.read(job.bgr)) {
      if (index == 0) throw VideoError(video_label + ": no frame could be decoded");
      if (expected > 0 && index < expected)
        throw VideoError(video_label + ": the video ends after " + count(index) + " of the " + count(expected) +
                         " frames its header declares (truncated or damaged)");
      if (!in.frame_times.empty() && index < in.frame_times.size())
        throw InputError(in.frame_times_label + ": lists frames up to " + count(in.frame_times.size() - 1) +
                         " but the video ends after " + count(index) + " frames");
      return false;
    }
    const calib::Camera& camera = in.camera;
    if (job.bgr.cols != camera.width || job.bgr.rows != camera.height)
      throw VideoError(video_label + ": frame " + count(index) + " is " + std::to_string(job.bgr.cols) + "x" +
                       std::to_string(job.bgr.rows) + " but " + camera_label + " is calibrated for " +
                       std::to_string(camera.width) + "x" + std::to_string(camera.height));
    if (job.bgr.type() != CV_8UC3) {
      cv::Mat converted;
      if (job.bgr.channels() == 1)
        cv::cvtColor(job.bgr, converted, cv::COLOR_GRAY2BGR);
      else if (job.bgr.channels() == 4)
        cv::cvtColor(job.bgr, converted, cv::COLOR_BGRA2BGR);
      else
        throw VideoError(video_label + ": frame " + count(index) + " is not an 8-bit colour image");
      job.bgr = converted;
    }
    job.record.times.decode = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_decode).count();
    job.record.time = clock(index);
    if (clock.fromFrameTimes() && !std::isfinite(job.record.time))
      throw InputError(in.frame_times_label + ": no time for frame " + count(index));
    job.record.selected = opt.frames.contains(index);
    return true;
  }

  // The reader thread: every frame decoded and queued for the annotators.
  void read() {
    try {
      for (std::size_t index = 0;; ++index) {
        FrameJob job;
        job.index = index;
        {
          std::unique_lock lock(mu);
          wake.wait(lock, [&] { return abort || in_flight < max_in_flight; });
          if (abort) return;
          if (!spare.empty()) {
            job.bgr = std::move(spare.back());
            spare.pop_back();
          }
        }
        if (!decode(index, job)) break;
        std::lock_guard lock(mu);
        todo.push_back(std::move(job));
        ++in_flight;
        decoded = index + 1;
        wake.notify_all();
      }
      std::lock_guard lock(mu);
      reader_done = true;
      wake.notify_all();
    } catch (...) {
      fail(std::current_exception());
    }
  }

  // An annotator thread (its own GL context): queued frames checked and drawn until none is left.
  void annotate(const AnnotatorScene& scene, const MaskAgreement* masks) {
    try {
      lowerThreadPriority(kAnnotatorNice);
      std::optional<FrameAnnotator> annotator;
      try {
        annotator.emplace(scene);
      } catch (const calib::CameraError& e) {
        throw InputError(e.messageFrom(camera_label));
      }
      for (;;) {
        FrameJob job;
        {
          std::unique_lock lock(mu);
          wake.wait(lock, [&] { return abort || !todo.empty() || reader_done; });
          if (abort || todo.empty()) return;
          job = std::move(todo.front());
          todo.pop_front();
        }
        const cv::Mat picture =
            masks && masks->fromRecording() ? job.bgr.clone() : cv::Mat();  // before anything is drawn
        annotator->annotate(job.bgr, job.record);
        if (masks) job.record.mask_iou = masks->at(job.index, job.record.values, picture);
        std::lock_guard lock(mu);
        done.emplace(job.index, std::move(job));
        wake.notify_all();
      }
    } catch (...) {
      fail(std::current_exception());
    }
  }

  // The writer: frame `index` once drawn, into `job`; false when every frame was handed on or a
  // stage failed.
  bool next(std::size_t index, FrameJob& job) {
    std::unique_lock lock(mu);
    wake.wait(lock, [&] { return abort || done.count(index) > 0 || (reader_done && index >= decoded); });
    if (abort || done.count(index) == 0) return false;
    job = std::move(done.at(index));
    done.erase(index);
    return true;
  }

  // A frame handed on: its buffer decoded into again when nothing else holds it.
  void handedOn(cv::Mat&& bgr) {
    std::lock_guard lock(mu);
    if (bgr.u != nullptr && bgr.u->refcount == 1) spare.push_back(std::move(bgr));
    --in_flight;
    wake.notify_all();
  }
};

// A drawn frame on the contact sheet, captioned; the most critical frame always makes it there:
// colliding first, then the nearest.
void addToSheet(ContactSheet& sheet, const FrameJob& job, const cv::Mat& frame) {
  const FrameRecord& r = job.record;
  std::string caption = "#" + std::to_string(job.index) + "  " + messageNumber(r.time, 4) + " s  " + toString(r.status);
  if (std::isfinite(r.min_distance)) caption += "  " + messageNumber(r.min_distance * 1000, 3) + " mm";
  if (r.mask_iou) caption += "  IoU " + messageNumber(*r.mask_iou, 3);
  const double priority = r.unsafe() || r.status == SafetyStatus::Colliding ? -1.0
                          : std::isfinite(r.min_distance)                   ? r.min_distance
                                                                            : std::numeric_limits<double>::infinity();
  sheet.add(job.index, frame, caption, priority);
}

}  // namespace

bool FrameRange::contains(std::size_t i) const {
  const long n = static_cast<long>(i);
  return n >= first && (end < 0 || n < end) && (n - first) % step == 0;
}

FrameRange parseFrameRange(const std::string& text, const std::string& label) {
  FrameRange s;
  if (text.empty()) return s;
  std::vector<std::string> parts;
  std::size_t at = 0;
  for (;;) {
    const std::size_t colon = text.find(':', at);
    parts.push_back(text.substr(at, colon == std::string::npos ? std::string::npos : colon - at));
    if (colon == std::string::npos) break;
    at = colon + 1;
  }
  const InputError bad(label + " " + text +
                       ": expected FIRST, FIRST:END or FIRST:END:STEP (frame numbers from 0, END exclusive, each part "
                       "optional, STEP >= 1)");
  if (parts.size() > 3) throw bad;
  auto number = [&](const std::string& p, long fallback) -> long {
    if (p.empty()) return fallback;
    if (p.size() > 12 || p.find_first_not_of("0123456789") != std::string::npos) throw bad;
    return std::stol(p);
  };
  s.first = number(parts[0], 0);
  if (parts.size() == 1) {
    if (parts[0].empty()) throw bad;
    s.end = s.first + 1;
    return s;
  }
  s.end = number(parts[1], -1);
  if (parts.size() == 3) s.step = number(parts[2], 1);
  if (s.step < 1 || (s.end >= 0 && s.end <= s.first)) throw bad;
  return s;
}

void OverlayReport::count(const FrameRecord& r) {
  no_state += r.status == SafetyStatus::NoState;
  colliding += r.status == SafetyStatus::Colliding;
  within_margin += r.status == SafetyStatus::WithinMargin;
  clear += r.status == SafetyStatus::Clear;
  unsafe += r.unsafe();
}

std::optional<std::size_t> OverlayReport::firstUnsafe() const {
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].unsafe()) return i;
  return std::nullopt;
}

OverlayReport overlayRecording(const OverlayInputs& in, const OverlayOptions& opt, FrameSink* sink,
                               const std::function<void(const OverlayProgress&)>& progress) {
  const Model& model = in.model;
  const calib::Camera& camera = in.camera;
  const std::string video_label = in.video_label.empty() ? in.video : in.video_label;
  const std::string camera_label = in.camera_label.empty() ? "camera" : in.camera_label;
  const auto t_setup = std::chrono::steady_clock::now();
  OverlayReport report;
  report.timings = opt.timings;
  report.max_gap = opt.max_gap > 0.0 ? opt.max_gap : 1.5 * in.log.medianPeriod();
  report.swept = opt.swept;
  report.margin = model.safety_margin;
  report.time_offset = opt.time_offset;
  report.time_offset_search = opt.time_offset_search;

  std::vector<render::LoadedVisual> visuals;
  if (opt.visuals) {
    if (model.visuals.empty()) throw InputError("visuals: the model has no visuals:");
    if (model.visuals.size() + model.bodies.size() > 255)
      throw InputError("visuals: more than 255 bodies and visuals to draw");
    visuals = render::loadVisuals(model);
  }
  AnnotatorSettings settings;
  settings.max_gap = report.max_gap;
  settings.swept = opt.swept;
  // The status line and the legend, drawn by the writer; the annotators count the volumes' pixels
  // under each corner the legend may take.
  const FrameDecoration decoration(cv::Size(camera.width, camera.height), opt.plain ? LegendPlace::Off : opt.legend,
                                   !opt.plain);
  if (decoration.corners().size() > 1) settings.legend_corners = decoration.corners();
  if (opt.swept) settings.braking.assign(static_cast<std::size_t>(model.stateSize()), opt.braking);

  // No mask is drawn: its finer pinhole image (and its per-pixel distortion map) is not built. The
  // colour pass's map is built once here for every annotator.
  render::RenderOptions render_options;
  render_options.mask_supersample = render_options.supersample;
  std::optional<render::Projection> projection;
  try {
    projection.emplace(camera, render_options.supersample);
  } catch (const calib::CameraError& e) {
    throw InputError(e.messageFrom(camera_label));
  }

  auto open = [&]() -> std::unique_ptr<FrameSource> {
    return in.open_frames ? in.open_frames() : std::make_unique<VideoSource>(in.video, video_label);
  };
  const std::unique_ptr<FrameSource> source = open();
  FrameSource& video = *source;
  report.fps = opt.fps > 0.0 ? opt.fps : video.fps();
  if (in.frame_times.empty() && !(report.fps > 0.0 && report.fps < 1e6))
    throw VideoError(video_label + ": the video gives no frame rate: " + in.no_rate_hint);
  const FrameClock clock(in.frame_times, report.fps);
  if (opt.time_offset_search) {  // a first pass over the video
    const std::unique_ptr<FrameSource> first_pass = open();
    const auto [lo, hi] = *opt.time_offset_search;
    report.time_offset_found =
        findTimeOffset(*first_pass, clock, in.log, report.max_gap, lo, hi,
                       opt.time_offset_label.empty() ? "time offset search" : opt.time_offset_label);
    report.time_offset = report.time_offset_found.offset;
  }
  settings.time_offset = report.time_offset;
  // Masks made from the recording: its background learnt first (another pass over the frames).
  std::optional<MaskAgreement> learnt;
  if (in.masks && in.masks->fromRecording()) {
    learnt.emplace(*in.masks);
    const std::unique_ptr<FrameSource> sampling = open();
    learnt->learnBackground(
        *sampling, [&](std::size_t i) { return clock(i) + report.time_offset; }, in.log, report.max_gap);
  }
  const MaskAgreement* masks = learnt ? &*learnt : in.masks;
  const std::size_t expected = video.declaredFrames();
  if (sink) sink->begin(clock.nominalFps(), decoration.frameSize().width, decoration.frameSize().height);

  const AnnotatorScene scene{model, in.log, *projection, render_options, visuals, settings};
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  report.jobs = opt.jobs > 0 ? opt.jobs : static_cast<int>(hw);

  Pipeline pipe{in,          opt,          video,    clock,
                video_label, camera_label, expected, 2 * static_cast<std::size_t>(report.jobs) + 2};
  std::thread reader([&] { pipe.read(); });
  std::vector<std::thread> annotators;
  for (int w = 0; w < report.jobs; ++w) annotators.emplace_back([&] { pipe.annotate(scene, masks); });

  // The writer: frames in input order.
  ContactSheet sheet(std::max<std::size_t>(opt.contact_frames, 1), opt.contact_tile_width);
  const auto t_frames = std::chrono::steady_clock::now();
  report.setup_seconds = std::chrono::duration<double>(t_frames - t_setup).count();
  LegendCorner corner(decoration.corners().empty() ? 1 : decoration.corners().front().area());
  cv::Mat tall;  // a frame with the strip under the picture (LegendPlace::Outside)
  try {
    FrameJob job;
    for (std::size_t next = 0; pipe.next(next, job); ++next) {
      FrameRecord& r = job.record;
      if (r.selected) {
        const auto t_decorate = std::chrono::steady_clock::now();
        const std::size_t corners = settings.legend_corners.size();
        const int at = corners > 1 ? corner.next(std::span<const int>(r.legend_cover.data(), corners)) : 0;
        const cv::Mat& frame = decorateFrame(job.bgr, tall, decoration, r, model, settings, at);
        r.times.composite = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_decorate).count();
        if (sink) {
          const auto t_encode = std::chrono::steady_clock::now();
          sink->write(job.index, frame);
          r.times.encode = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_encode).count();
          r.written = true;
          ++report.written;
        }
        if (opt.contact_frames > 0) addToSheet(sheet, job, frame);
      }
      report.frames.push_back(std::move(job.record));
      pipe.handedOn(std::move(job.bgr));
      if (progress) {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();
        progress(OverlayProgress{next + 1, expected, elapsed > 0 ? static_cast<double>(next + 1) / elapsed : 0.0});
      }
    }
  } catch (...) {
    pipe.fail(std::current_exception());
  }
  reader.join();
  for (std::thread& t : annotators) t.join();
  if (pipe.error) std::rethrow_exception(pipe.error);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();
  for (const FrameRecord& r : report.frames) {
    report.count(r);
    report.stages += r.times;
    report.reused += r.reused;
  }
  if (opt.contact_frames > 0) {
    report.contact_sheet = sheet.compose();
    report.contact_sheet_frames = sheet.frames();
  }
  return report;
}

void checkOverlayOutputs(const OverlayOutputs& out, std::span<const std::string> inputs) {
  if (!out.contact_sheet.empty()) checkOutputPath(out.contact_sheet, out.contact_sheet_option, ".png");
  if (!out.timeline.empty()) checkOutputPath(out.timeline, out.timeline_option, ".png");
  if (!out.video.empty()) {
    const std::string ext = lowerExtension(out.video);
    if (ext != ".mp4" && ext != ".mkv" && ext != ".avi")
      throw OutputError(out.video_option + " " + out.video + ": the output must be a .mp4, .mkv or .avi file");
    checkOutputPath(out.video, out.video_option, ext);
  }
  if (!out.report.empty()) checkOutputPath(out.report, out.report_option, ".json");
  for (const std::string& in : inputs)
    for (const std::string& written : {out.video, out.report, out.contact_sheet, out.timeline})
      if (!in.empty() && !written.empty() && sameFile(in, written))
        throw OutputError(written + ": is an input of this run (" + in + "); write the output elsewhere");
}

nlohmann::json writeOverlayOutputs(const OverlayOutputs& out, const OverlayReport& report, const Model& model,
                                   VideoSink& sink) {
  nlohmann::json j = reportJson(report, model, true);
  if (!out.video.empty()) j["video"] = out.video;
  if (!out.png_dir.empty()) j["png_dir"] = out.png_dir;
  if (!out.contact_sheet.empty()) {
    const std::string name = out.contact_sheet_option + " " + out.contact_sheet;
    if (report.contact_sheet.empty()) throw OutputError(name + ": no frame was drawn (see " + out.frames_option + ")");
    writePngAtomically(out.contact_sheet, report.contact_sheet, name);
    j["contact_sheet"] = out.contact_sheet;
  }
  if (!out.timeline.empty()) {
    writePngAtomically(out.timeline,
                       drawTimeline(report, model, out.timeline_title.empty() ? out.timeline : out.timeline_title),
                       out.timeline_option + " " + out.timeline);
    j["timeline"] = out.timeline;
  }
  sink.commit();
  if (!out.report.empty()) writeFileAtomically(out.report, j.dump(1) + "\n", out.report_option + " " + out.report);
  return j;
}

}  // namespace kccd::overlay
