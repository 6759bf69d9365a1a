// `kccd overlay MODEL --camera CAM.yaml --video IN --states LOG.csv -o OUT`: the collision volumes
// at each frame's logged state, coloured by the library's query, composited onto a recorded video.
//
// Pipeline: one reader thread decodes frames in order; worker threads (one Checker and one
// Renderer, hence one GL context, each) query, render and composite; the calling thread writes
// the frames in input order. At most `2 x jobs + 2` frames are in flight, so memory stays bounded
// whatever the video's length.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "cli_args.hpp"
#include "visuals.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "contact_sheet.hpp"
#include "commands.hpp"
#include "kccd/braking.hpp"
#include "kccd/checker.hpp"
#include "kccd/frame_times.hpp"
#include "kccd/overlay/time_offset.hpp"
#include "kccd/overlay/video_source.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

namespace fs = std::filesystem;

struct OverlayArgs {
  std::string model, camera, video, states, output, png_dir, report, frames, frame_times, ignore_columns, codec, contact_sheet;
  int contact_frames = 12;
  std::string time_offset_text = "0";  // seconds, or auto:A:B
  double time_offset = 0.0, max_gap = 0.0, fps = 0.0;
  double latency = 0.01, deceleration = 5.0, max_acceleration = 0.0, position_error = 0.0, velocity_error = 0.0;
  bool swept = false, plain = false, quiet = false, json = false, visuals = false;
  int jobs = 0;  // 0: hardware threads
};

// ---------------------------------------------------------------------------------------------
// Options

// `--frames a:b:step` (Python slice: b exclusive, each part optional) or a single frame `a`.
struct FrameSelection {
  long first = 0, end = -1, step = 1;  // end < 0: to the last frame
  bool contains(std::size_t i) const {
    const long n = static_cast<long>(i);
    return n >= first && (end < 0 || n < end) && (n - first) % step == 0;
  }
};

FrameSelection parseFrames(const std::string& text) {
  FrameSelection s;
  if (text.empty()) return s;
  std::vector<std::string> parts;
  std::size_t at = 0;
  for (;;) {
    const std::size_t colon = text.find(':', at);
    parts.push_back(text.substr(at, colon == std::string::npos ? std::string::npos : colon - at));
    if (colon == std::string::npos) break;
    at = colon + 1;
  }
  auto bad = [&] {
    return UsageError("--frames " + text + ": expected FIRST, FIRST:END or FIRST:END:STEP (frame numbers from 0, END "
                      "exclusive, each part optional, STEP >= 1)");
  };
  if (parts.size() > 3) throw bad();
  auto number = [&](const std::string& p, long fallback) -> long {
    if (p.empty()) return fallback;
    if (p.size() > 12 || p.find_first_not_of("0123456789") != std::string::npos) throw bad();
    return std::stol(p);
  };
  s.first = number(parts[0], 0);
  if (parts.size() == 1) {
    if (parts[0].empty()) throw bad();
    s.end = s.first + 1;
    return s;
  }
  s.end = number(parts[1], -1);
  if (parts.size() == 3) s.step = number(parts[2], 1);
  if (s.step < 1 || (s.end >= 0 && s.end <= s.first)) throw bad();
  return s;
}

// `--frame-times FILE` (kccd/frame_times.hpp), its mistakes named as the option's.
std::vector<double> frameTimes(const std::string& path) {
  try {
    return loadFrameTimes(path);
  } catch (const FrameTimesError& e) {
    throw UsageError(std::string("--frame-times ") + e.what());
  }
}

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// ---------------------------------------------------------------------------------------------
// One frame

enum class FrameStatus : std::uint8_t { Clear, WithinMargin, Colliding, NoState };

const char* toString(FrameStatus s) {
  switch (s) {
    case FrameStatus::Clear: return "clear";
    case FrameStatus::WithinMargin: return "within_margin";
    case FrameStatus::Colliding: return "colliding";
    default: return "no_state";
  }
}

const char* stateName(StateMatch m) {
  switch (m) {
    case StateMatch::Exact: return "exact";
    case StateMatch::Interpolated: return "interpolated";
    default: return "none";
  }
}

// What the report says about one input frame.
struct FrameRecord {
  double time = 0.0;  // video clock (index / fps or --frame-times)
  StateMatch match = StateMatch::None;
  FrameStatus status = FrameStatus::NoState;
  Status query = Status::Ok;
  bool braking_failed = false;   // a non-finite position or velocity: no braking box (unsafe)
  bool not_finite = false;       // a volume could not be drawn (overflow): unsafe
  double min_distance = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::array<int, 2>> pairs;  // within the margin (body indices)
  std::vector<double> values;             // the state used (empty without one)
  bool selected = false, written = false;
  bool unsafe() const { return query != Status::Ok || braking_failed || not_finite; }
};

struct FrameJob {
  std::size_t index = 0;
  cv::Mat bgr;
  FrameRecord record;
};

// What every worker reads.
struct Shared {
  const OverlayArgs& args;
  const Model& model;
  const calib::Camera& camera;
  const StateLog& log;
  double max_gap = 0.0;
  std::vector<BrakingParams> braking;  // per state value (with --swept)
  render::RenderOptions render_options;
  std::optional<render::Projection> projection;  // made once, copied by every worker's Renderer
  std::vector<LoadedVisual> visuals;              // with --visuals
};

// Queries, renders and composites frames; one per thread (its Renderer's GL context is current
// on the thread that made it).
class FrameWorker {
 public:
  explicit FrameWorker(const Shared& s)
      : s_(s),
        checker_(s.model),
        q_(s.model.stateSize()),
        v_(s.model.stateSize()),
        lo_(s.model.stateSize()),
        hi_(s.model.stateSize()) {
    try {
      renderer_ = std::make_unique<render::Renderer>(*s.projection, s.render_options);
    } catch (const calib::CameraError& e) {
      std::string msg = e.what();
      if (msg.rfind("camera: ", 0) == 0) msg = msg.substr(8);
      throw UsageError(s.args.camera + ": " + msg);
    }
    style_.labels = false;
    style_.legend = !s.args.plain;
    for (std::size_t i = 0; i < s.model.bodies.size(); ++i)
      if (s.model.bodies[i].frame == kWorld) fixed_.push_back(static_cast<int>(i));
  }

  void process(FrameJob& job) {
    FrameRecord& rec = job.record;
    const Model& m = s_.model;
    const double t = rec.time + s_.args.time_offset;
    rec.match = s_.args.swept ? stateAt(s_.log, t, s_.max_gap, q_, v_) : stateAt(s_.log, t, s_.max_gap, q_);
    std::vector<render::Volume> volumes;
    if (rec.match == StateMatch::None) {
      rec.status = FrameStatus::NoState;
      if (!rec.selected) return;
      // No state: only the bodies fixed in the world are known; they are drawn grey.
      for (int i : fixed_) {
        const Body& b = m.bodies[static_cast<std::size_t>(i)];
        volumes.push_back(render::Volume{b.points, b.radius * (1.0 + 1e-9) + 1e-9, SafetyStatus::NoState, b.name});
      }
    } else {
      rec.values.assign(q_.begin(), q_.end());
      bool box_ok = true;
      if (s_.args.swept) {
        box_ok = brakingIntervals(m, q_, v_, s_.braking, lo_, hi_);
        if (!box_ok) {
          rec.braking_failed = true;
          lo_ = q_;
          hi_ = q_;
        }
      } else {
        lo_ = q_;
        hi_ = q_;
      }
      // From scratch every frame: the answer does not depend on which worker had which frame.
      checker_.reset();
      const QueryResult& r = checker_.query(lo_, hi_, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
      rec.query = r.status;
      // A bound only for the box the run is about: none for an unsafe status or a missing braking box.
      if (r.status == Status::Ok && box_ok) rec.min_distance = r.min_distance;
      for (const PairDistance& pd : r.pairs)
        if (pd.distance <= r.margin) rec.pairs.push_back({m.pairs[pd.pair].a, m.pairs[pd.pair].b});
      if (r.status != Status::Ok || !box_ok || r.min_distance <= 0.0)
        rec.status = FrameStatus::Colliding;
      else if (r.min_distance <= r.margin)
        rec.status = FrameStatus::WithinMargin;
      else
        rec.status = FrameStatus::Clear;
      if (!rec.selected) return;
      std::vector<SafetyStatus> status = render::bodyStatus(m, r);
      if (!box_ok) status.assign(m.bodies.size(), SafetyStatus::Colliding);
      volumes = s_.args.swept && box_ok ? render::sceneVolumes(m, checker_, status)
                                        : render::staticSceneVolumes(m, checker_, q_, status);
    }
    const std::size_t checked = volumes.size();  // the volumes; the visuals come after them
    if (!s_.visuals.empty() && rec.match != StateMatch::None) {
      // The robot's appearance at the logged state, drawn with the volumes (its own colours).
      std::vector<render::Volume> look = visualVolumes(m, s_.visuals, q_);
      volumes.insert(volumes.end(), std::make_move_iterator(look.begin()), std::make_move_iterator(look.end()));
    }
    const render::Frame layer = renderer_->render(volumes, style_, true, false);
    for (std::size_t i = 0; i < checked; ++i) rec.not_finite |= layer.visibility[i] == render::Visibility::NotFinite;
    if (rec.not_finite) rec.status = FrameStatus::Colliding;  // an overflowed volume is unsafe
    render::compositeOver(job.bgr, layer.bgra);
    if (!s_.args.plain) drawStatusLine(job.bgr, rec);
  }

 private:
  void drawStatusLine(cv::Mat& bgr, const FrameRecord& rec) const {
    std::ostringstream s;
    char buf[64];
    std::snprintf(buf, sizeof buf, "t %.3f s", rec.time + s_.args.time_offset);
    s << buf;
    if (rec.match == StateMatch::None) {
      s << "  NO STATE (outside the log or in a gap longer than " << format(s_.max_gap, 3) << " s)";
    } else {
      s << " (" << stateName(rec.match) << ")" << (s_.args.swept ? "  swept" : "");
      if (rec.unsafe()) {
        s << "  UNSAFE: " << (rec.braking_failed ? "no braking box" : rec.not_finite ? "volume not finite" : toString(rec.query));
      } else {
        if (std::isfinite(rec.min_distance)) {
          std::snprintf(buf, sizeof buf, "  min distance %.4f m", rec.min_distance);
          s << buf;
        } else {
          s << "  no checked pairs";
        }
        if (!rec.pairs.empty()) {
          s << "  within margin: ";
          for (std::size_t i = 0; i < rec.pairs.size() && i < 3; ++i)
            s << (i ? ", " : "") << s_.model.bodies[rec.pairs[i][0]].name << "-" << s_.model.bodies[rec.pairs[i][1]].name;
          if (rec.pairs.size() > 3) s << " +" << rec.pairs.size() - 3;
        }
      }
    }
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    const double scale = std::clamp(bgr.rows / 900.0, 0.35, 1.0);
    const int thick = std::max(1, static_cast<int>(std::lround(scale * 2)));
    int baseline = 0;
    const std::string text = s.str();
    const cv::Size size = cv::getTextSize(text, font, scale, thick, &baseline);
    const int pad = std::max(3, size.height / 2);
    const cv::Rect box = cv::Rect(pad, bgr.rows - size.height - baseline - 3 * pad, size.width + 2 * pad,
                                  size.height + baseline + 2 * pad) &
                         cv::Rect(0, 0, bgr.cols, bgr.rows);
    if (box.empty()) return;
    cv::Mat roi = bgr(box);
    roi.convertTo(roi, -1, 0.35, 0);  // darkened background keeps the text readable on any frame
    const cv::Point at(box.x + pad, box.y + pad + size.height);
    const cv::Scalar colour = rec.status == FrameStatus::Clear ? cv::Scalar(255, 255, 255)
                                                               : render::statusColour(static_cast<SafetyStatus>(rec.status));
    cv::putText(bgr, text, at, font, scale, colour, thick, cv::LINE_AA);
  }

  const Shared& s_;
  Checker checker_;
  std::unique_ptr<render::Renderer> renderer_;
  render::Style style_;
  std::vector<double> q_, v_, lo_, hi_;
  std::vector<int> fixed_;
};

int fourccFor(const std::string& output, const std::string& codec) {
  if (!codec.empty()) {
    if (codec.size() != 4) throw UsageError("--codec " + codec + ": a FourCC is 4 characters (e.g. mp4v, avc1, MJPG, FFV1)");
    return cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]);
  }
  const std::string ext = lowerExtension(output);
  if (ext == ".mkv") return cv::VideoWriter::fourcc('F', 'F', 'V', '1');
  if (ext == ".avi") return cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  return cv::VideoWriter::fourcc('m', 'p', '4', 'v');
}

// ---------------------------------------------------------------------------------------------
// --time-offset auto:A:B

struct AutoOffset {
  double lo = 0.0, hi = 0.0;
};

// "S" (seconds) or "auto:A:B"; returns the range for auto, and sets `offset` otherwise.
std::optional<AutoOffset> parseTimeOffset(const std::string& text, double& offset) {
  auto num = [&](const std::string& t, double& out) {
    char* end = nullptr;
    out = std::strtod(t.c_str(), &end);
    return !t.empty() && end == t.c_str() + t.size() && std::isfinite(out) && std::fabs(out) <= 1e9;
  };
  if (text.rfind("auto:", 0) == 0) {
    const std::string rest = text.substr(5);
    const std::size_t colon = rest.find(':');
    AutoOffset r;
    if (colon == std::string::npos || !num(rest.substr(0, colon), r.lo) || !num(rest.substr(colon + 1), r.hi) || !(r.lo < r.hi))
      throw UsageError("--time-offset " + text + ": expected auto:A:B with A < B (seconds, the range searched)");
    return r;
  }
  if (!num(text, offset)) throw UsageError("--time-offset " + text + ": expected seconds (within 1e9) or auto:A:B");
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// The run

Exit runOverlay(OverlayArgs& a) {
  const auto t_start = std::chrono::steady_clock::now();
  // Every input and option is checked before any frame is decoded.
  const Model model = loadOrExplain(a.model);
  const calib::Camera camera = calib::loadCamera(a.camera);
  if (a.output.empty() && a.png_dir.empty() && a.report.empty() && a.contact_sheet.empty())
    throw UsageError("nothing to write: give -o VIDEO, --png-dir DIR, --report FILE and/or --contact-sheet FILE");
  if (!a.contact_sheet.empty()) checkOutputPath(a.contact_sheet, "--contact-sheet", ".png");
  if (!a.output.empty()) {
    const std::string ext = lowerExtension(a.output);
    if (ext != ".mp4" && ext != ".mkv" && ext != ".avi")
      throw UsageError("-o " + a.output + ": the output must be a .mp4, .mkv or .avi file");
    checkOutputPath(a.output, "-o", ext);
  }
  if (!a.report.empty()) checkOutputPath(a.report, "--report", ".json");
  {  // inputs stay untouched: no output may replace one
    std::error_code ec;
    for (const std::string& in : {a.video, a.states, a.model, a.camera, a.frame_times})
      for (const std::string& outp : {a.output, a.report})
        if (!in.empty() && !outp.empty() && fs::equivalent(in, outp, ec))
          throw UsageError(outp + ": is an input of this run (" + in + "); write the output elsewhere");
  }
  const FrameSelection selection = parseFrames(a.frames);
  const std::optional<AutoOffset> auto_offset = parseTimeOffset(a.time_offset_text, a.time_offset);
  double auto_score = 0.0;
  const std::vector<std::string> ignore = splitCommas(a.ignore_columns);
  const StateLog log = loadStateLog(a.states, model, ignore);
  double max_gap = a.max_gap > 0.0 ? a.max_gap : 1.5 * log.medianPeriod();
  std::vector<double> frame_times;
  if (!a.frame_times.empty()) frame_times = frameTimes(a.frame_times);

  Shared shared{a, model, camera, log, max_gap, {}};
  if (a.visuals) {
    if (model.visuals.empty()) throw UsageError("--visuals: " + a.model + " has no visuals:");
    if (model.visuals.size() + model.bodies.size() > 255)
      throw UsageError("--visuals: " + a.model + ": more than 255 bodies and visuals to draw");
    shared.visuals = loadVisuals(model);
  }
  if (a.swept) {
    BrakingParams p;
    p.latency = a.latency;
    p.deceleration = a.deceleration;
    p.max_acceleration = a.max_acceleration;
    p.position_error = a.position_error;
    p.velocity_error = a.velocity_error;
    shared.braking.assign(static_cast<std::size_t>(model.stateSize()), p);
  }

  // Errors are reported once, by kccd: FFmpeg's and OpenCV's own log lines are silenced (set
  // OPENCV_FFMPEG_LOGLEVEL to see FFmpeg's). FFmpeg reads videos, OpenCV's image reader sequences.
  setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  // No mask is drawn: its finer pinhole image (and its per-pixel distortion map) is not built. The
  // colour pass's map is built once here for every worker.
  shared.render_options.mask_supersample = shared.render_options.supersample;
  try {
    shared.projection.emplace(camera, shared.render_options.supersample);
  } catch (const calib::CameraError& e) {
    std::string msg = e.what();
    if (msg.rfind("camera: ", 0) == 0) msg = msg.substr(8);
    throw UsageError(a.camera + ": " + msg);
  }

  overlay::VideoSource video(a.video, "--video " + a.video);
  double fps = a.fps > 0.0 ? a.fps : video.fps();
  if (frame_times.empty() && !(fps > 0.0 && fps < 1e6))
    throw UsageError("--video " + a.video + ": the video gives no frame rate: give --fps or --frame-times");
  const overlay::FrameClock clock(frame_times, fps);
  const double writer_fps = clock.nominalFps();
  if (auto_offset) {  // a first pass over the video
    overlay::VideoSource first_pass(a.video, "--video " + a.video);
    const overlay::TimeOffset found =
        overlay::findTimeOffset(first_pass, clock, log, max_gap, auto_offset->lo, auto_offset->hi,
                                "--time-offset auto:" + format(auto_offset->lo) + ":" + format(auto_offset->hi));
    a.time_offset = found.offset;
    auto_score = found.correlation;
  }
  const std::size_t expected = video.declaredFrames();

  // Outputs under temporary names, moved into place only when every frame is done.
  std::optional<overlay::StagedOutput> video_out, png_out;
  cv::VideoWriter writer;
  if (!a.output.empty()) {
    video_out.emplace(a.output, overlay::StagedOutput::Kind::File, "-o " + a.output);
    const std::string tmp = video_out->path().string();
    const int fourcc = fourccFor(a.output, a.codec);
    bool ok = false;
    try {
      ok = writer.open(tmp, cv::CAP_FFMPEG, fourcc, writer_fps, cv::Size(camera.width, camera.height), true);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) throw UsageError("-o " + a.output + ": cannot open a video writer for this container and codec");
  }
  std::string png_tmp;
  if (!a.png_dir.empty()) {
    png_out.emplace(a.png_dir, overlay::StagedOutput::Kind::Folder, "--png-dir " + a.png_dir);
    png_tmp = png_out->path().string();
  }
  const auto commit = [&] {
    if (video_out) video_out->commit();
    if (png_out) png_out->commit();
  };

  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const int jobs = a.jobs > 0 ? a.jobs : static_cast<int>(hw);
  const std::size_t max_in_flight = 2 * static_cast<std::size_t>(jobs) + 2;

  // Shared between the reader, the workers and the writer (this thread), under one mutex.
  std::mutex mu;
  std::condition_variable cv;
  std::deque<FrameJob> todo;
  std::map<std::size_t, FrameJob> done;
  std::vector<cv::Mat> spare;  // written frames' buffers, decoded into again (no allocation per frame)
  std::size_t in_flight = 0, decoded = 0;
  bool reader_done = false, abort = false;
  std::exception_ptr error;
  auto fail = [&](std::exception_ptr e) {
    std::lock_guard lock(mu);
    if (!error) error = e;
    abort = true;
    cv.notify_all();
  };

  std::thread reader([&] {
    try {
      for (std::size_t index = 0;; ++index) {
        {
          std::unique_lock lock(mu);
          cv.wait(lock, [&] { return abort || in_flight < max_in_flight; });
          if (abort) return;
        }
        FrameJob job;
        job.index = index;
        {
          std::lock_guard lock(mu);
          if (!spare.empty()) {
            job.bgr = std::move(spare.back());
            spare.pop_back();
          }
        }
        if (!video.read(job.bgr)) {
          if (index == 0) throw UsageError("--video " + a.video + ": no frame could be decoded");
          if (expected > 0 && index < expected)
            throw UsageError("--video " + a.video + ": the video ends after " + std::to_string(index) + " of the " +
                             std::to_string(expected) + " frames its header declares (truncated or damaged)");
          if (!frame_times.empty() && index < frame_times.size())
            throw UsageError("--frame-times " + a.frame_times + ": lists frames up to " + std::to_string(frame_times.size() - 1) +
                             " but the video ends after " + std::to_string(index) + " frames");
          break;
        }
        if (job.bgr.cols != camera.width || job.bgr.rows != camera.height)
          throw UsageError("--video " + a.video + ": frame " + std::to_string(index) + " is " + std::to_string(job.bgr.cols) + "x" +
                           std::to_string(job.bgr.rows) + " but " + a.camera + " is calibrated for " + std::to_string(camera.width) +
                           "x" + std::to_string(camera.height));
        if (job.bgr.type() != CV_8UC3) {
          cv::Mat converted;
          if (job.bgr.channels() == 1) cv::cvtColor(job.bgr, converted, cv::COLOR_GRAY2BGR);
          else if (job.bgr.channels() == 4) cv::cvtColor(job.bgr, converted, cv::COLOR_BGRA2BGR);
          else throw UsageError("--video " + a.video + ": frame " + std::to_string(index) + " is not an 8-bit colour image");
          job.bgr = converted;
        }
        job.record.time = clock(index);
        if (clock.fromFrameTimes() && !std::isfinite(job.record.time))
          throw UsageError("--frame-times " + a.frame_times + ": no time for frame " + std::to_string(index));
        job.record.selected = selection.contains(index);
        std::lock_guard lock(mu);
        todo.push_back(std::move(job));
        ++in_flight;
        decoded = index + 1;
        cv.notify_all();
      }
      std::lock_guard lock(mu);
      reader_done = true;
      cv.notify_all();
    } catch (...) {
      fail(std::current_exception());
    }
  });

  std::vector<std::thread> workers;
  for (int w = 0; w < jobs; ++w)
    workers.emplace_back([&] {
      try {
        FrameWorker worker(shared);
        for (;;) {
          FrameJob job;
          {
            std::unique_lock lock(mu);
            cv.wait(lock, [&] { return abort || !todo.empty() || reader_done; });
            if (abort || todo.empty()) return;
            job = std::move(todo.front());
            todo.pop_front();
          }
          worker.process(job);
          std::lock_guard lock(mu);
          done.emplace(job.index, std::move(job));
          cv.notify_all();
        }
      } catch (...) {
        fail(std::current_exception());
      }
    });

  // The writer: frames in input order.
  std::vector<FrameRecord> records;
  std::size_t written = 0;
  ContactSheet sheet(static_cast<std::size_t>(a.contact_frames), 320);
  Progress progress("overlay", a.quiet);
  const auto t_frames = std::chrono::steady_clock::now();
  try {
    for (std::size_t next = 0;; ++next) {
      FrameJob job;
      {
        std::unique_lock lock(mu);
        cv.wait(lock, [&] { return abort || done.count(next) > 0 || (reader_done && next >= decoded); });
        if (abort) break;
        if (done.count(next) == 0) break;  // every frame written
        job = std::move(done.at(next));
        done.erase(next);
      }
      if (job.record.selected) {
        if (writer.isOpened()) {
          // VideoWriter drops a frame of another size or type without a word: never hand it one.
          if (job.bgr.type() != CV_8UC3 || job.bgr.cols != camera.width || job.bgr.rows != camera.height)
            throw std::logic_error("overlay frame of the wrong size or type");
          writer.write(job.bgr);
        }
        if (!png_tmp.empty()) {
          char name[32];
          std::snprintf(name, sizeof name, "frame_%06zu.png", job.index);
          const std::string path = (fs::path(png_tmp) / name).string();
          bool ok = false;
          try {
            ok = cv::imwrite(path, job.bgr);
          } catch (const cv::Exception&) {
            ok = false;
          }
          if (!ok) throw UsageError("--png-dir " + a.png_dir + ": cannot write " + name);
        }
        if (writer.isOpened() || !png_tmp.empty()) {
          job.record.written = true;
          ++written;
        }
        if (!a.contact_sheet.empty()) {
          const FrameRecord& r = job.record;
          std::string caption = "#" + std::to_string(job.index) + "  " + format(r.time, 4) + " s  " + toString(r.status);
          if (std::isfinite(r.min_distance)) caption += "  " + format(r.min_distance * 1000, 3) + " mm";
          // The most critical frame is always on the sheet: colliding first, then the nearest.
          const double priority = r.unsafe() || r.status == FrameStatus::Colliding ? -1.0
                                  : std::isfinite(r.min_distance)                  ? r.min_distance
                                                                                   : std::numeric_limits<double>::infinity();
          sheet.add(job.index, job.bgr, caption, priority);
        }
      }
      records.push_back(std::move(job.record));
      {
        std::lock_guard lock(mu);
        if (job.bgr.u != nullptr && job.bgr.u->refcount == 1) spare.push_back(std::move(job.bgr));
        --in_flight;
        cv.notify_all();
      }
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();
      const double rate = elapsed > 0 ? static_cast<double>(next + 1) / elapsed : 0.0;
      std::string detail = std::to_string(next + 1) + (expected ? "/" + std::to_string(expected) : "") + " frames, " +
                           format(rate, 3) + " fps";
      if (expected > next + 1 && rate > 0) detail += ", ETA " + std::to_string(std::lround((expected - next - 1) / rate)) + " s";
      progress.update(expected ? static_cast<double>(next + 1) / static_cast<double>(expected) : 0.0, detail);
    }
  } catch (...) {
    fail(std::current_exception());
  }
  reader.join();
  for (std::thread& t : workers) t.join();
  progress.finish();
  if (error) std::rethrow_exception(error);  // the temporary outputs are removed on the way out
  writer.release();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();

  // The report.
  std::size_t no_state = 0, colliding = 0, within = 0, unsafe = 0;
  for (const FrameRecord& r : records) {
    no_state += r.status == FrameStatus::NoState;
    colliding += r.status == FrameStatus::Colliding;
    within += r.status == FrameStatus::WithinMargin;
    unsafe += r.unsafe();
  }
  nlohmann::json j;
  j["frames_total"] = records.size();
  j["frames_written"] = written;
  j["no_state"] = no_state;
  j["colliding"] = colliding;
  j["within_margin"] = within;
  j["unsafe"] = unsafe;
  j["volumes"] = a.swept ? "swept" : "static";
  j["time_offset"] = a.time_offset;
  if (auto_offset) j["time_offset_auto"] = {{"range", {auto_offset->lo, auto_offset->hi}}, {"correlation", auto_score}};
  j["max_gap"] = max_gap;
  j["fps"] = fps > 0 ? nlohmann::json(fps) : nlohmann::json(nullptr);
  j["margin"] = model.safety_margin;
  if (!a.output.empty()) j["video"] = a.output;
  if (!a.png_dir.empty()) j["png_dir"] = a.png_dir;
  if (!a.contact_sheet.empty()) {
    const cv::Mat picture = sheet.compose();
    if (picture.empty()) throw UsageError("--contact-sheet " + a.contact_sheet + ": no frame was drawn (see --frames)");
    writePngAtomically(a.contact_sheet, picture, "--contact-sheet");
    j["contact_sheet"] = a.contact_sheet;
  }
  if (!a.report.empty()) {
    nlohmann::json frames = nlohmann::json::array();
    for (std::size_t i = 0; i < records.size(); ++i) {
      const FrameRecord& r = records[i];
      nlohmann::json f;
      f["index"] = i;
      f["time"] = r.time;
      f["log_time"] = r.time + a.time_offset;
      f["state"] = stateName(r.match);
      f["status"] = toString(r.status);
      f["min_distance"] = number(r.min_distance);
      f["state_values"] = nlohmann::json::array();
      for (double v : r.values) f["state_values"].push_back(number(v));
      f["pairs_within_margin"] = nlohmann::json::array();
      for (const auto& p : r.pairs) f["pairs_within_margin"].push_back({model.bodies[p[0]].name, model.bodies[p[1]].name});
      if (r.match != StateMatch::None)
        f["query_status"] = r.braking_failed ? "no_braking_box" : r.not_finite ? "volume_not_finite" : toString(r.query);
      f["written"] = r.written;
      frames.push_back(std::move(f));
    }
    nlohmann::json full = j;
    full["frames"] = std::move(frames);
    commit();
    writeFileAtomically(a.report, full.dump(1) + "\n", "--report " + a.report);
  } else {
    commit();
  }

  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if (a.json) {
    j["seconds"] = total;
    j["frames_per_second"] = seconds > 0 ? static_cast<double>(records.size()) / seconds : 0.0;
    j["jobs"] = jobs;
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::cout << "overlay: " << records.size() << " frames, " << written << " written";
    if (!a.output.empty()) std::cout << " to " << a.output;
    if (!a.png_dir.empty()) std::cout << (a.output.empty() ? " to " : " and ") << a.png_dir;
    std::cout << "; clear " << records.size() - no_state - colliding - within << ", within margin " << within << ", colliding "
              << colliding << ", no state " << no_state << "; "
              << (auto_offset ? "time offset " + format(a.time_offset, 6) + " s (auto, correlation " + format(auto_score, 3) + "); " : "")
              << ""<< format(records.size() / std::max(seconds, 1e-9), 3)
              << " frames/s with " << jobs << " jobs\n";
  }
  if (unsafe > 0) {
    for (std::size_t i = 0; i < records.size(); ++i)
      if (records[i].unsafe()) {
        const FrameRecord& r = records[i];
        std::cerr << "kccd: " << unsafe << " frame(s) with an unsafe query status, first frame " << i << ": "
                  << (r.braking_failed ? "no braking box (non-finite state or velocity)"
                      : r.not_finite   ? "volume not finite"
                                       : toString(r.query))
                  << " (unsafe; everything was written)\n";
        break;
      }
    return Exit::Unsafe;
  }
  return Exit::Ok;
}

}  // namespace

Runner addOverlay(CLI::App& app) {
  auto a = std::make_shared<OverlayArgs>();
  CLI::App* sub = app.add_subcommand(
      "overlay", "Batch overlay: the collision volumes at each frame's logged state, coloured by the query, on a recorded video");
  sub->add_option("model", a->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--camera", a->camera, "Camera file (OpenCV YAML: intrinsics, distortion, rvec/tvec); its image size must be the video's")
      ->required();
  sub->add_option("--video", a->video, "Input video (any OpenCV reads) or image sequence (e.g. frames/frame_%06d.png)")->required();
  sub->add_option("--states", a->states, "State log (CSV: time and one column per state value, see kccd info)")->required();
  sub->add_option("-o,--output", a->output, "Output video (.mp4: mp4v, .mkv: FFV1 lossless, .avi: MJPG; see --codec)");
  sub->add_option("--png-dir", a->png_dir, "Also (or only) write frame_%06d.png (input frame numbers) into this new or empty folder");
  sub->add_option("--frames", a->frames, "Frames to draw and write: FIRST:END:STEP (from 0, END exclusive; all frames are still checked and reported)");
  sub->add_option("--contact-sheet", a->contact_sheet,
                  "A .png of --contact-frames drawn frames spread over the run, the most critical one included, captioned");
  sub->add_option("--contact-frames", a->contact_frames, "Frames on the contact sheet")->check(CLI::Range(1, 64))->capture_default_str();
  sub->add_option("--report", a->report, "Per-frame report (.json): state match, status, min distance, pairs within the margin");
  sub->add_option("--frame-times", a->frame_times, "CSV 'frame,time': each frame's time in seconds (default: index / fps)");
  sub->add_option("--fps", a->fps, "Frame rate of the input (default: the video's own)")->check(finiteIn(1e-6, 1e6));
  sub->add_option("--time-offset", a->time_offset_text,
                  "Added to each frame's time to get the state log's time (s); auto:A:B searches [A, B] for the offset at which "
                  "the image motion best follows the logged motion")
      ->capture_default_str();
  sub->add_option("--max-gap", a->max_gap, "No state when no two log samples this close bracket the time (s; default 1.5 x the log's median period)")
      ->check(finiteIn(0, 1e300));
  sub->add_option("--ignore-columns", a->ignore_columns, "Comma-separated state log columns to skip (an unknown column is an error)");
  sub->add_flag("--swept", a->swept, "Draw the braking-interval swept volumes (from logged or differenced velocities) instead of the static ones");
  sub->add_option("--latency", a->latency, "Braking: reaction latency t_l (s), every joint")->capture_default_str()->check(finiteIn(0, 1e3));
  sub->add_option("--deceleration", a->deceleration, "Braking: guaranteed deceleration (rad/s^2 or m/s^2), every joint")
      ->capture_default_str()
      ->check(finiteIn(1e-9, 1e9));
  sub->add_option("--max-acceleration", a->max_acceleration, "Braking: worst-case acceleration during the latency")
      ->capture_default_str()
      ->check(finiteIn(0, 1e9));
  sub->add_option("--position-error", a->position_error, "Braking: position measurement error bound")->capture_default_str()->check(finiteIn(0, 1e3));
  sub->add_option("--velocity-error", a->velocity_error, "Braking: velocity measurement error bound")->capture_default_str()->check(finiteIn(0, 1e6));
  sub->add_flag("--plain", a->plain, "Volumes only: no legend, no status line");
  sub->add_flag("--visuals", a->visuals,
                "Also draw the model's visual geometry (visuals:) at the logged state, tinted in its own colours: "
                "where it misses the robot in the video, the camera, the log's clock or the model is off");
  sub->add_option("--codec", a->codec, "FourCC of the output video (default by extension)");
  sub->add_option("-j,--jobs", a->jobs, "Worker threads (each with its own GL context; default: hardware threads)")->check(CLI::Range(1, 256));
  sub->add_flag("--json", a->json, "Print the summary as JSON");
  sub->add_flag("-q,--quiet", a->quiet, "No progress and no summary");
  sub->footer(
      "Each frame's time (index / fps, or --frame-times) plus --time-offset is looked up in the state log: a sample\n"
      "(exact), a linear interpolation between two samples at most --max-gap apart, or no state. Without a state only\n"
      "the bodies fixed in the world are drawn (grey); the frame is counted and reported as no_state.\n"
      "Colours: green clear, amber within the safety margin, red colliding or unsafe, grey no state.\n"
      "Outputs are written under temporary names and moved into place only when every frame is done.\n"
      "Exit status: 0 written, 2 bad input (nothing written), 3 a frame's query status is unsafe (everything still written).");
  return [a] { return runOverlay(*a); };
}

}  // namespace kccd::cli
