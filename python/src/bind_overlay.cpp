// The main job from Python: kccd.overlay_recording (a recording and its state log checked and drawn
// frame by frame) and kccd.synthesize_recording (a synthetic recording with ground truth).
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"
#include "kccd/logs/lerobot_dataset.hpp"
#include "kccd/overlay/bags/bag_info.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/datasets/dataset_info.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "kccd/overlay/jobs/check_job.hpp"
#include "kccd/overlay/jobs/overlay_job.hpp"
#include "kccd/overlay/recording/contact_sheet.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/synth/synth.hpp"
#include "progress_relay.hpp"

namespace kccd::python {

namespace {

py::object toPython(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A recording's state log into `d`: 'state_names', 'times' and 'states' (rows x state values).
void addStateLog(py::dict& d, const StateLog& log) {
  d["state_names"] = log.names;
  d["times"] = floatArray(log.times);
  py::array_t<double> states({static_cast<py::ssize_t>(log.rows()), static_cast<py::ssize_t>(log.stateSize())});
  std::copy(log.values.begin(), log.values.end(), states.mutable_data());
  d["states"] = states;
}

// The keywords of overlay_recording after video and states: the request's fields under their own
// names (and progress, progress_every, read by the caller). An unknown keyword is a TypeError.
overlay::OverlayRequest overlayRequest(const py::kwargs& kwargs) {
  overlay::OverlayRequest q;
  const std::map<std::string, std::function<void(const py::handle&)>> fields = {
      {"bag", [&](const py::handle& v) { q.bag = v.cast<std::string>(); }},
      {"image_topic", [&](const py::handle& v) { q.image_topic = v.cast<std::string>(); }},
      {"joint_topic", [&](const py::handle& v) { q.joint_topic = v.cast<std::string>(); }},
      {"time_source", [&](const py::handle& v) { q.time_source = v.cast<std::string>(); }},
      {"joint_map", [&](const py::handle& v) { q.joint_map = v.cast<std::string>(); }},
      {"lerobot", [&](const py::handle& v) { q.lerobot = v.cast<std::string>(); }},
      {"episode", [&](const py::handle& v) { q.episode = v.cast<long>(); }},
      {"camera_key", [&](const py::handle& v) { q.camera_key = v.cast<std::string>(); }},
      {"state_key", [&](const py::handle& v) { q.state_key = v.cast<std::string>(); }},
      {"frame_by", [&](const py::handle& v) { q.frame_by = v.cast<std::string>(); }},
      {"frame_times", [&](const py::handle& v) { q.frame_times = v.cast<std::string>(); }},
      {"ignore_columns", [&](const py::handle& v) { q.ignore_columns = v.cast<std::vector<std::string>>(); }},
      {"fps", [&](const py::handle& v) { q.fps = v.cast<double>(); }},
      {"time_offset",
       [&](const py::handle& v) {
         if (py::isinstance<py::str>(v))
           overlay::parseTimeOffset(v.cast<std::string>(), q);
         else
           q.time_offset = v.cast<double>();
       }},
      {"max_gap", [&](const py::handle& v) { q.max_gap = v.cast<double>(); }},
      {"swept", [&](const py::handle& v) { q.swept = v.cast<bool>(); }},
      {"braking",
       [&](const py::handle& v) {
         if (!v.is_none()) q.braking = v.cast<BrakingParams>();
       }},
      {"plain", [&](const py::handle& v) { q.plain = v.cast<bool>(); }},
      {"legend", [&](const py::handle& v) { q.legend = v.cast<std::string>(); }},
      {"visuals", [&](const py::handle& v) { q.visuals = v.cast<bool>(); }},
      {"masks", [&](const py::handle& v) { q.masks = v.cast<std::string>(); }},
      {"mask_bodies", [&](const py::handle& v) { q.mask_bodies = v.cast<std::vector<std::string>>(); }},
      {"frames", [&](const py::handle& v) { q.frames = v.cast<std::string>(); }},
      {"jobs", [&](const py::handle& v) { q.jobs = v.cast<int>(); }},
      {"timings", [&](const py::handle& v) { q.timings = v.cast<bool>(); }},
      {"output", [&](const py::handle& v) { q.output = v.cast<std::string>(); }},
      {"codec", [&](const py::handle& v) { q.codec = v.cast<std::string>(); }},
      {"png_dir", [&](const py::handle& v) { q.png_dir = v.cast<std::string>(); }},
      {"report", [&](const py::handle& v) { q.report = v.cast<std::string>(); }},
      {"contact_sheet", [&](const py::handle& v) { q.contact_sheet = v.cast<std::string>(); }},
      {"timeline", [&](const py::handle& v) { q.timeline = v.cast<std::string>(); }},
      {"contact_frames", [&](const py::handle& v) { q.contact_frames = v.cast<int>(); }},
  };
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    if (name == "progress" || name == "progress_every") continue;
    const auto f = fields.find(name);
    if (f == fields.end())
      throw py::type_error("overlay_recording() got an unexpected keyword argument '" + name + "'");
    try {
      f->second(value);
    } catch (const py::cast_error&) {
      throw py::type_error(name + ": expected " +
                           (name == "time_offset" ? "seconds or 'auto:A:B'" : "a value of the default's type") +
                           ", got " + py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>());
    }
  }
  return q;
}

}  // namespace

namespace {

// kccd overlay's braking defaults and contact sheets from frames.
void bindContactSheet(py::module_& m) {
  m.def(
      "overlay_braking", [] { return overlay::kOverlayBraking; },
      "kccd overlay's braking for swept volumes, every joint (latency 0.01 s, deceleration 5): the default of "
      "overlay_recording(braking=) and of kccd.batch. A fresh copy each call.");
  m.def(
      "contact_sheet",
      [](const std::vector<py::array>& frames, const std::vector<std::string>& captions, const std::string& output,
         int tile_width) {
        if (frames.size() != captions.size())
          throw py::value_error("captions: " + std::to_string(captions.size()) + " captions for " +
                                std::to_string(frames.size()) + " frames");
        if (frames.empty()) throw py::value_error("frames: give at least one frame");
        if (tile_width < 16 || tile_width > 4096) throw py::value_error("tile_width: must be 16 ... 4096 pixels");
        if (output.empty() || overlay::lowerExtension(output) != ".png")
          throw py::value_error("output: must be a .png file");
        std::vector<cv::Mat> bgr;
        for (std::size_t i = 0; i < frames.size(); ++i) {
          const py::array& a = frames[i];
          if (a.dtype().kind() != 'u' || a.dtype().itemsize() != 1 || a.ndim() != 3 || a.shape(2) != 3 ||
              a.shape(0) < 1 || a.shape(1) < 1)
            throw py::value_error("frames[" + std::to_string(i) + "]: expected uint8 (H, W, 3) RGB");
          const auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(a);
          const cv::Mat view(static_cast<int>(c.shape(0)), static_cast<int>(c.shape(1)), CV_8UC3,
                             const_cast<std::uint8_t*>(c.data()));
          cv::Mat b;
          cv::cvtColor(view, b, cv::COLOR_RGB2BGR);
          bgr.push_back(b);
        }
        {
          py::gil_scoped_release release;
          // One more than the frames: the sheet then keeps every frame offered (none is thinned out).
          overlay::ContactSheet sheet(bgr.size() + 1, tile_width);
          for (std::size_t i = 0; i < bgr.size(); ++i) sheet.add(i, bgr[i], captions[i], 0.0);
          overlay::writePngAtomically(output, sheet.compose(), "output");
        }
      },
      py::arg("frames"), py::arg("captions"), py::arg("output"), py::kw_only(), py::arg("tile_width") = 320,
      R"doc(Writes a contact sheet, as `kccd overlay --contact-sheet` draws one: `frames` (uint8 (H, W, 3) RGB each)
side by side, in order, on a grid of at most 4 columns, each scaled to tile_width pixels and captioned with its
caption. output: a .png, written under a temporary name and renamed when complete.)doc");
}

// The overlay job: overlay_recording and check_overlay_request (kccd/overlay/jobs/overlay_job.hpp).
void bindOverlayJob(py::module_& m) {
  py::options signature_in_doc;  // overlay_recording's doc starts with its keywords and defaults
  signature_in_doc.disable_function_signatures();
  m.def(
      "overlay_recording",
      [](const std::shared_ptr<ModelHandle>& h, const calib::Camera& camera, const std::string& video,
         const std::string& states, const py::kwargs& kwargs) {
        overlay::OverlayRequest q = overlayRequest(kwargs);
        q.video = video;
        q.states = states;
        q.model_file = h->source;
        const py::object progress =
            kwargs.contains("progress") ? py::object(kwargs["progress"]) : py::object(py::none());
        const double progress_every = kwargs.contains("progress_every") ? kwargs["progress_every"].cast<double>() : 0.0;
        if (!(progress_every >= 0.0) || !std::isfinite(progress_every))
          throw py::value_error("progress_every: must be a finite number of seconds >= 0");
        overlay::OverlayJob job(q, *h->model, camera);
        for (const std::string& w : job.warnings())
          if (PyErr_WarnEx(PyExc_UserWarning, ("bag " + q.bag + ": " + w).c_str(), 1) < 0)
            throw py::error_already_set();
        ProgressRelay relay{progress, {}};
        nlohmann::json full;
        relay.run([&] {
          full =
              job.run([&, last = std::chrono::steady_clock::time_point{}](const overlay::OverlayProgress& p) mutable {
                   // Throttled before the GIL is asked for: each acquisition may wait for Python's
                   // switch interval while other Python threads run (a Dask worker's event loop).
                   const auto now = std::chrono::steady_clock::now();
                   const bool last_frame = p.frames_expected > 0 && p.frames_done >= p.frames_expected;
                   if (!last_frame && last.time_since_epoch().count() != 0 &&
                       std::chrono::duration<double>(now - last).count() < progress_every)
                     return;
                   last = now;
                   relay(p.frames_done, p.frames_expected, p.frames_per_second);
                 })
                  .json;
        });
        return toPython(full);
      },
      py::arg("model"), py::arg("camera"), py::arg("video") = "", py::arg("states") = "",
      R"doc(overlay_recording(model, camera, video='', states='', *, bag='', image_topic='', joint_topic='', time_source='header', joint_map='', lerobot='', episode=-1, camera_key='', state_key='observation.state', frame_by='auto', frame_times='', ignore_columns=[], fps=0.0, time_offset=0.0, max_gap=0.0, swept=False, braking=None, plain=False, legend='auto', visuals=False, masks='', mask_bodies=[], frames='', jobs=0, timings=False, output='', codec='', png_dir='', report='', contact_sheet='', timeline='', contact_frames=12, progress=None, progress_every=0.0)

The main job, as `kccd overlay` (every option of it under its own name, with its default and its checks):
every frame of `video` (a file or an image-sequence pattern) checked at the state the log `states` (CSV)
gives at its time (log time = frame time + time_offset, seconds; time_offset 'auto:A:B' searches [A, B];
frame_times: a CSV 'frame,time' instead of index / fps; max_gap: the largest log gap bridged), the volumes
drawn and composited. Outputs, checked before any frame is decoded (extension, an existing folder, not one
of the inputs) and each written under a temporary name and renamed when complete: `output` (.mp4, .mkv or
.avi; codec: a FourCC), `png_dir` (frame_NNNNNN.png), `report` (.json, the format of `kccd overlay
--report`), `contact_sheet` (.png of contact_frames frames), `timeline` (.png of the run over time).
swept: braking-interval volumes, with `braking` (a BrakingParams for every joint; None: kccd overlay's
defaults, latency 0.01 s and deceleration 5). plain: no legend or status line; legend: where the legend
goes, 'auto' (the corner hiding the fewest volume pixels), 'top-left', 'top-right', 'bottom-left',
'bottom-right', 'outside' (a strip under the picture with the status line: taller frames) or 'off';
visuals: the model's visual geometry too. jobs: drawing threads (0: all cores). frames: 'FIRST:END:STEP' of the frames drawn
(all are checked). progress(frames_done, frames_expected, frames_per_second) is called after each frame
with the GIL held (progress_every: at most once per that many seconds, and after the last frame). Returns
the report as a dict (with per-frame records under 'frames'). Instead of video and states, bag: a robot
log (MCAP, rosbag2 .db3 or folder, ROS 1 .bag) whose image topic gives the frames at their own times and
whose joint states give the states, as `kccd overlay --bag` (image_topic, joint_topic: default the only
one of the type; time_source 'header' or 'log'; joint_map: a joint map file; warnings as UserWarning). Or
lerobot: a LeRobot dataset's folder with episode (its episode_index), as `kccd overlay --lerobot` (camera_key:
default its only camera; state_key: the vector feature read; frame_by 'auto', 'timestamp' or 'index').
masks: a folder of robot masks (frame_000000.png, ...) or 'auto' (made from the recording's own
background): each frame's 'mask_iou' and the report's 'mask_agreement'; mask_bodies: the bodies the masks
show (default all). An unknown keyword raises TypeError; a bad value InputError naming the keyword
("fps: must be in ..."), a bad file InputError naming the file and place.)doc");
  m.def(
      "check_overlay_request",
      [](const std::shared_ptr<ModelHandle>& h, const std::string& video, const std::string& states,
         const py::kwargs& kwargs) {
        overlay::OverlayRequest q = overlayRequest(kwargs);
        q.video = video;
        q.states = states;
        if (h) q.model_file = h->source;
        overlay::checkOverlayRequest(q, h ? h->model.get() : nullptr);
      },
      py::arg("model") = nullptr, py::arg("video") = "", py::arg("states") = "",
      R"doc(check_overlay_request(model=None, video='', states='', **keywords)

Checks overlay_recording's keywords as overlay_recording does before it reads anything, opening no file
(without a model, visuals and mask_bodies are not checked): raises the first problem as InputError naming
the keyword ("fps: must be in ...", field in e.field), TypeError for an unknown keyword. kccd.batch checks
each recording of a manifest with it before any starts.)doc");
  signature_in_doc.enable_function_signatures();
}

// What a robot log holds, and what kccd overlay --bag reads of it.
void bindReadBag(py::module_& m) {
  m.def(
      "read_bag",
      [](const std::string& path, const std::shared_ptr<ModelHandle>& h, const std::string& image_topic,
         const std::string& joint_topic, const std::string& time_source, const std::string& joint_map,
         const std::vector<long>& frames) {
        const std::optional<overlay::TimeSource> clock = overlay::timeSourceOf(time_source);
        if (!clock) throw py::value_error("time_source: expected 'header' or 'log'");
        if (!h && (!joint_topic.empty() || !joint_map.empty()))
          throw py::value_error("joint_topic and joint_map need a model");
        for (const long f : frames)
          if (f < 0) throw py::value_error("frames: indices from 0");
        py::dict d;
        const overlay::BagRecordingOptions o{
            .bag = path,
            .joint_topic = joint_topic,
            .image_topic = image_topic,
            .time_source = *clock,
            .joint_map = joint_map.empty() || !h ? overlay::JointMap{} : overlay::loadJointMap(joint_map, *h->model)};
        nlohmann::json info;
        overlay::BagRecording rec;
        std::vector<cv::Mat> images;
        {
          py::gil_scoped_release release;
          info = overlay::bagInfoJson(logs::summarizeBag(path));
          if (h || !frames.empty() || !image_topic.empty())
            rec = h ? overlay::readBagRecording(o, *h->model) : overlay::readBagImages(o);
          images = overlay::framesAt(rec, frames, "frame");
          for (cv::Mat& image : images) cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
        }
        d["info"] = toPython(info);
        if (rec.frame_times.empty()) return d;
        d["image_topic"] = rec.image_topic;
        d["frame_times"] = floatArray(rec.frame_times);
        d["fps"] = rec.fps;
        d["origin_ns"] = rec.origin_ns;
        d["warnings"] = rec.warnings;
        if (h) {
          d["joint_topic"] = rec.joint_topic;
          addStateLog(d, rec.log);
        }
        if (!frames.empty()) {
          py::list list;
          for (const cv::Mat& img : images) {
            py::array_t<std::uint8_t> a({img.rows, img.cols, 3});
            for (int y = 0; y < img.rows; ++y)
              std::memcpy(a.mutable_data(y, 0, 0), img.ptr(y), static_cast<std::size_t>(img.cols) * 3);
            list.append(a);
          }
          d["images"] = list;
        }
        return d;
      },
      py::arg("path"), py::arg("model") = nullptr, py::kw_only(), py::arg("image_topic") = "",
      py::arg("joint_topic") = "", py::arg("time_source") = "header", py::arg("joint_map") = "",
      py::arg("frames") = std::vector<long>{},
      R"doc(What a robot log (MCAP, rosbag2 .db3 or folder, ROS 1 .bag) holds, as `kccd bag info --json` under 'info'.
With a model, also what `kccd overlay --bag` reads: 'state_names', 'times' (s, from 'origin_ns' on the chosen
clock), 'states' (one row per joint state, the model's state values matched by name or by joint_map),
'joint_topic'; with a model or frames: 'image_topic', 'frame_times' (s, same clock), 'fps' (the median
interval's rate), 'warnings'. frames: indices of the image topic's frames returned under 'images' as uint8
(H, W, 3) RGB. time_source: 'header' (header stamps) or 'log' (the recorder's times). Raises InputError
naming the file, topic and place.)doc");
}

// What a LeRobot dataset holds, and what kccd overlay --lerobot reads of an episode.
void bindReadLerobot(py::module_& m) {
  m.def(
      "read_lerobot",
      [](const std::string& path, const std::shared_ptr<ModelHandle>& h, long episode, const std::string& state_key,
         const std::string& frame_by, const std::string& joint_map) {
        const std::optional<overlay::FrameBy> by = overlay::frameByOf(frame_by);
        if (!by) throw py::value_error("frame_by: expected 'auto', 'timestamp' or 'index'");
        if (!h && (episode != -1 || !joint_map.empty())) throw py::value_error("episode and joint_map need a model");
        if (h && episode < 0) throw py::value_error("episode: give the episode (its episode_index) with a model");
        py::dict d;
        nlohmann::json info;
        overlay::LerobotRecording rec;
        {
          py::gil_scoped_release release;
          info = overlay::datasetInfoJson(logs::openLerobotDataset(path));
          if (h)
            rec = overlay::readLerobotRecording(
                {.dataset = path,
                 .episode = episode,
                 .state_key = state_key,
                 .frame_by = *by,
                 .joint_map = joint_map.empty() ? overlay::JointMap{} : overlay::loadJointMap(joint_map, *h->model),
                 .frames = false},
                *h->model);
        }
        d["info"] = toPython(info);
        if (!h) return d;
        addStateLog(d, rec.log);
        d["frame_by"] = rec.frame_by == overlay::FrameBy::Index ? "index" : "timestamp";
        d["data_file"] = rec.data_file;
        d["warnings"] = rec.warnings;
        return d;
      },
      py::arg("path"), py::arg("model") = nullptr, py::kw_only(), py::arg("episode") = -1,
      py::arg("state_key") = "observation.state", py::arg("frame_by") = "auto", py::arg("joint_map") = "",
      R"doc(What a LeRobot dataset (v2.0, v2.1 or v3.0 folder) holds, as `kccd dataset info --json` under 'info'.
With a model and an episode, also what `kccd overlay --lerobot` reads of it: 'state_names', 'times' (s: each
row's frame time, by timestamp or frame_index as 'frame_by' says), 'states' (one row per dataset row, the model's
state values matched by name, NAME.pos or joint_map), 'data_file', 'warnings'. Raises InputError naming the
file and place.)doc");
}

// A joint log checked without a camera (kccd check).
void bindCheckLog(py::module_& m) {
  m.def(
      "check_log",
      [](const std::shared_ptr<ModelHandle>& h, const std::string& states, const std::string& bag,
         const std::string& lerobot, long episode, const std::string& state_key, const std::string& joint_topic,
         const std::string& time_source, const std::string& joint_map, const std::vector<std::string>& ignore_columns,
         double rate, double max_gap, const std::string& query, bool swept, const std::optional<BrakingParams>& braking,
         int jobs, const std::string& report, const std::string& timeline) {
        const overlay::CheckRequest q{.states = states,
                                      .ignore_columns = ignore_columns,
                                      .bag = bag,
                                      .joint_topic = joint_topic,
                                      .time_source = time_source,
                                      .joint_map = joint_map,
                                      .lerobot = lerobot,
                                      .episode = episode,
                                      .state_key = state_key,
                                      .rate = rate,
                                      .max_gap = max_gap,
                                      .query = query,
                                      .swept = swept,
                                      .braking = braking,
                                      .jobs = jobs,
                                      .report = report,
                                      .timeline = timeline,
                                      .model_file = h->source};
        overlay::CheckResult result;
        {
          py::gil_scoped_release release;
          result = overlay::runCheck(q, *h->model);
        }
        for (const std::string& w : result.warnings) PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1);
        return toPython(result.json);
      },
      py::arg("model"), py::arg("states") = "", py::kw_only(), py::arg("bag") = "", py::arg("lerobot") = "",
      py::arg("episode") = -1, py::arg("state_key") = "observation.state", py::arg("joint_topic") = "",
      py::arg("time_source") = "header", py::arg("joint_map") = "",
      py::arg("ignore_columns") = std::vector<std::string>{}, py::arg("rate") = 0.0, py::arg("max_gap") = 0.0,
      py::arg("query") = "distances", py::arg("swept") = false, py::arg("braking") = std::nullopt, py::arg("jobs") = 0,
      py::arg("report") = "", py::arg("timeline") = "",
      R"doc(A joint log checked without a camera, as `kccd check`: every sample of `states` (CSV), of a robot log's
joint states (bag) or of a LeRobot episode (lerobot, episode) queried (rate: a grid of that many samples per
second instead), static or swept (braking: a BrakingParams for every joint, None: kccd overlay's defaults);
query 'distances' (the overlay's) or 'collision' (faster). Writes report (.json, the overlay's format) and
timeline (.png) when given, staged. Returns the summary as a dict ('samples', 'clear', 'within_margin',
'colliding', 'no_state', 'unsafe', ...); the log's warnings as UserWarning. Raises InputError naming the
keyword or the file and place.)doc");
}

// Synthetic recordings with ground truth (kccd synth).
void bindSynth(py::module_& m) {
  m.def(
      "synthesize_recording",
      [](const std::string& model, const std::string& output, const std::string& camera, double seconds, double fps,
         double log_rate, double time_offset, std::uint64_t seed, const std::string& codec, bool collision,
         bool replace, bool bag, const std::optional<int>& width, const std::optional<int>& height,
         const std::string& appearance, const std::optional<double>& visible_scale, double blur, double noise,
         const py::object& progress) {
        overlay::SynthOptions o;
        o.width = width, o.height = height, o.visible_scale = visible_scale, o.blur = blur, o.noise = noise;
        if (appearance == "auto")
          o.appearance = overlay::SynthAppearance::Auto;
        else if (appearance == "volumes")
          o.appearance = overlay::SynthAppearance::Volumes;
        else if (appearance == "visuals")
          o.appearance = overlay::SynthAppearance::Visuals;
        else
          throw py::value_error("appearance: 'auto', 'volumes' or 'visuals', got '" + appearance + "'");
        o.model = model;
        o.output = output;
        o.camera = camera;
        o.seconds = seconds;
        o.fps = fps;
        o.log_rate = log_rate;
        o.time_offset = time_offset;
        o.seed = seed;
        o.codec = codec;
        o.collision = collision;
        o.replace = replace;
        o.bag = bag;
        o.spell = [](const std::string& field) -> std::string {
          return field == "collision" ? "collision=False" : field == "replace" ? "replace=True" : field;
        };
        ProgressRelay relay{progress, {}};
        overlay::SynthResult r;
        relay.run([&] { r = overlay::synthesizeRecording(o, [&](double fraction) { relay(fraction); }); });
        py::dict d;
        d["folder"] = r.folder.string();
        d["video"] = (r.folder / r.video_file).string();
        d["states"] = (r.folder / "states.csv").string();
        d["camera"] = (r.folder / "camera_true.yaml").string();
        d["bag"] = r.bag_file.empty() ? py::object(py::none()) : py::str((r.folder / r.bag_file).string());
        d["frames"] = r.frames;
        d["width"] = r.width;
        d["height"] = r.height;
        d["fps"] = r.fps;
        d["log_rate"] = r.log_rate;
        d["time_offset"] = r.time_offset;
        d["log_rows"] = r.log_rows;
        d["min_distance"] = r.min_distance;
        d["colliding_frames"] = r.colliding_frames;
        d["near_frames"] = r.near_frames;
        d["collision_intervals"] = r.collision_intervals;
        d["seconds"] = r.seconds;
        return d;
      },
      py::arg("model"), py::arg("output"), py::kw_only(), py::arg("camera") = "", py::arg("seconds") = 5.0,
      py::arg("fps") = 25.0, py::arg("log_rate") = 125.0, py::arg("time_offset") = 0.137, py::arg("seed") = 1,
      py::arg("codec") = "ffvhuff", py::arg("collision") = true, py::arg("replace") = false, py::arg("bag") = false,
      py::arg("width") = py::none(), py::arg("height") = py::none(), py::arg("appearance") = "auto",
      py::arg("visible_scale") = py::none(), py::arg("blur") = 0.7, py::arg("noise") = 2.5,
      py::arg("progress") = py::none(),
      R"doc(A synthetic recording with ground truth, as `kccd synth`: in the new folder `output`, the video, the state
log states.csv, the true camera camera_true.yaml, tags, masks and synth.json (the folder appears only when
complete). model: a model file. Every option of `kccd synth` under its own name: width and height (the default
camera's image size, not with camera), appearance ('auto', 'volumes' or 'visuals'), visible_scale (the volumes'
drawn radius fraction), blur and noise (sigmas), bag (also states.mcap: the recording as a ROS 2 bag, JointState
on /joint_states and each frame as a JPEG CompressedImage on /camera/image_raw/compressed, both on the log's
clock, so overlay_recording(..., bag=...) pairs them with no time_offset). An option out of range raises
InputError naming it ("fps: must be 1 ... 240"). progress(fraction) is called after each frame with the GIL
held. Returns a dict with the files' paths ('bag': None without bag) and the truth: per-frame 'min_distance'
(metres), 'colliding_frames', 'near_frames', 'collision_intervals' ([first, last] frames).)doc");
}

}  // namespace

void bindOverlay(py::module_& m) {
  bindContactSheet(m);
  bindOverlayJob(m);
  bindReadBag(m);
  bindReadLerobot(m);
  bindCheckLog(m);
  bindSynth(m);
}

}  // namespace kccd::python
