// The main job from Python: kccd.overlay_recording (a recording and its state log checked and drawn
// frame by frame) and kccd.synthesize_recording (a synthetic recording with ground truth).
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <cmath>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "progress_relay.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"
#include "kccd/overlay/bags/bag_info.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/recording/contact_sheet.hpp"
#include "kccd/overlay/recording/mask_agreement.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/synth/synth.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/state_log.hpp"

namespace kccd::python {

namespace {

py::object toPython(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

}  // namespace

void bindOverlay(py::module_& m) {
  m.def("overlay_braking", [] { return overlay::kOverlayBraking; },
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


  m.def(
      "overlay_recording",
      [](const std::shared_ptr<ModelHandle>& h, const calib::Camera& camera, const std::string& video,
         const std::string& states, const std::string& output, const std::string& report, const std::string& contact_sheet,
         double time_offset, bool swept, const std::optional<BrakingParams>& braking, int jobs, const std::string& frames,
         int contact_frames, const py::object& progress, double progress_every, const std::string& bag, const std::string& image_topic,
         const std::string& joint_topic, const std::string& time_source, const std::string& joint_map, const std::string& timeline,
         const std::string& masks, const std::vector<std::string>& mask_bodies) {
        const Model& model = *h->model;
        if (!(progress_every >= 0.0) || !std::isfinite(progress_every))
          throw py::value_error("progress_every: must be a finite number of seconds >= 0");
        if (bag.empty() == (video.empty() || states.empty()) || (!bag.empty() && (!video.empty() || !states.empty())))
          throw py::value_error("give video and states, or bag (a robot log), not both");
        if (bag.empty() && (!image_topic.empty() || !joint_topic.empty() || !joint_map.empty()))
          throw py::value_error("image_topic, joint_topic and joint_map go with bag");
        const std::optional<overlay::TimeSource> clock = overlay::timeSourceOf(time_source);
        if (!clock) throw py::value_error("time_source: expected 'header' or 'log'");
        std::optional<overlay::BagRecording> rec;
        if (!bag.empty())
          rec = overlay::readBagRecording({.bag = bag, .joint_topic = joint_topic, .image_topic = image_topic,
                                           .time_source = *clock,
                                           .joint_map = joint_map.empty() ? overlay::JointMap{} : overlay::loadJointMap(joint_map, model)},
                                          model);
        if (rec)
          for (const std::string& w : rec->warnings)
            if (PyErr_WarnEx(PyExc_UserWarning, ("bag " + bag + ": " + w).c_str(), 1) < 0) throw py::error_already_set();
        const StateLog log = rec ? rec->log : loadStateLog(states, model);
        overlay::OverlayInputs in{model, camera, log, rec ? bag : video, {}, rec ? "bag " + bag + " (topic " + rec->image_topic + ")" : "video " + video,
                                  "camera", ""};
        if (rec) {
          in.frame_times = rec->frame_times;
          in.open_frames = rec->open_frames;
        }
        std::optional<overlay::MaskAgreement> agreement;
        if (!masks.empty()) {
          std::vector<int> bodies;
          for (const std::string& name : mask_bodies) {
            const int b = model.bodyIndex(name);
            if (b < 0) throw py::value_error("mask_bodies: '" + name + "' is not a body of the model");
            bodies.push_back(b);
          }
          if (masks == "auto") agreement.emplace(camera, model, std::move(bodies), "masks auto");
          else agreement.emplace(masks, camera, model, std::move(bodies), "masks " + masks);
          in.masks = &*agreement;
        } else if (!mask_bodies.empty()) {
          throw py::value_error("mask_bodies: goes with masks");
        }
        overlay::OverlayOptions o;
        o.time_offset = time_offset;
        o.swept = swept;
        if (braking) {
          if (!swept) throw py::value_error("braking: only with swept=True (static volumes do not brake)");
          const BrakingParams& b = *braking;
          for (const auto& [field, value] : {std::pair{"position_error", b.position_error}, {"velocity_error", b.velocity_error},
                                             {"latency", b.latency}, {"max_acceleration", b.max_acceleration}})
            if (!(value >= 0.0) || !std::isfinite(value))
              throw py::value_error(std::string("braking: ") + field + " must be a finite number >= 0");
          if (!(b.deceleration > 0.0) || !std::isfinite(b.deceleration))
            throw py::value_error("braking: deceleration must be a finite number > 0");
          o.braking = b;
        }
        o.jobs = jobs;
        o.frames = overlay::parseFrameRange(frames, "frames");
        if (contact_frames < 1 || contact_frames > 64) throw py::value_error("contact_frames: expected 1 to 64");
        o.contact_frames = contact_sheet.empty() ? 0 : static_cast<std::size_t>(contact_frames);
        const overlay::OverlayOutputs outputs{.video = output,
                                              .report = report,
                                              .contact_sheet = contact_sheet,
                                              .video_option = "output",
                                              .report_option = "report",
                                              .contact_sheet_option = "contact_sheet",
                                              .frames_option = "frames",
                                              .timeline = timeline,
                                              .timeline_option = "timeline",
                                              .timeline_title = std::filesystem::path(rec ? bag : video).filename().string()};
        overlay::checkOverlayOutputs(outputs, std::vector<std::string>{video, states, bag, joint_map, h->source});
        overlay::VideoSink sink({.video = output, .codec = "", .video_label = "output " + output, .png_dir = "", .png_label = ""});
        ProgressRelay relay{progress, {}};
        nlohmann::json full;
        relay.run([&] {
          overlay::OverlayReport r = overlay::overlayRecording(
              in, o, sink.active() ? &sink : nullptr,
              [&, last = std::chrono::steady_clock::time_point{}](const overlay::OverlayProgress& p) mutable {
                // Throttled before the GIL is asked for: each acquisition may wait for Python's
                // switch interval while other Python threads run (a Dask worker's event loop).
                const auto now = std::chrono::steady_clock::now();
                const bool last_frame = p.frames_expected > 0 && p.frames_done >= p.frames_expected;
                if (!last_frame && last.time_since_epoch().count() != 0 &&
                    std::chrono::duration<double>(now - last).count() < progress_every)
                  return;
                last = now;
                relay(p.frames_done, p.frames_expected, p.frames_per_second);
              });
          if (rec) r.source = rec->source();
          full = overlay::writeOverlayOutputs(outputs, r, model, sink);
        });
        return toPython(full);
      },
      py::arg("model"), py::arg("camera"), py::arg("video") = "", py::arg("states") = "", py::kw_only(), py::arg("output") = "",
      py::arg("report") = "", py::arg("contact_sheet") = "", py::arg("time_offset") = 0.0, py::arg("swept") = false,
      py::arg("braking") = py::none(), py::arg("jobs") = 0, py::arg("frames") = "", py::arg("contact_frames") = 12, py::arg("progress") = py::none(),
      py::arg("progress_every") = 0.0, py::arg("bag") = "", py::arg("image_topic") = "", py::arg("joint_topic") = "",
      py::arg("time_source") = "header", py::arg("joint_map") = "", py::arg("timeline") = "", py::arg("masks") = "",
      py::arg("mask_bodies") = std::vector<std::string>{},
      R"doc(The main job, as `kccd overlay`: every frame of `video` (a file or an image-sequence pattern) checked at
the state the log `states` (CSV) gives at its time (log time = frame time + time_offset, seconds), the
volumes drawn and composited. Outputs, checked before any frame is decoded (extension, an existing
folder, not one of the inputs) and each written under a temporary name and renamed when complete:
`output` (.mp4, .mkv or .avi), `report` (.json, the format of `kccd overlay --report`), `contact_sheet`
(.png of contact_frames frames). swept: braking-interval volumes, with `braking` (a BrakingParams for every
joint; None: kccd overlay's defaults, latency 0.01 s and deceleration 5). jobs: drawing threads (0: all cores).
frames: 'FIRST:END:STEP' of the frames drawn (all are checked). progress(frames_done, frames_expected,
frames_per_second) is called after each frame with the GIL held (progress_every: at most once per that many
seconds, and after the last frame). Returns the report as a dict (with
per-frame records under 'frames'). Instead of video and states, bag: a robot log (MCAP, rosbag2 .db3 or
folder, ROS 1 .bag) whose image topic gives the frames at their own times and whose joint states give
the states, as `kccd overlay --bag` (image_topic, joint_topic: default the only one of the type;
time_source 'header' or 'log'; joint_map: a joint map file; warnings as UserWarning). timeline: a .png of
the run over time (`kccd overlay --timeline`). masks: a folder of robot masks (frame_000000.png, ...) or
'auto' (made from the recording's own background), as `kccd overlay --masks`: each frame's 'mask_iou' and the
report's 'mask_agreement'; mask_bodies: the bodies the masks show (default all). Raises InputError naming the
input and place.)doc");

  m.def(
      "read_bag",
      [](const std::string& path, const std::shared_ptr<ModelHandle>& h, const std::string& image_topic, const std::string& joint_topic,
         const std::string& time_source, const std::string& joint_map, const std::vector<long>& frames) {
        const std::optional<overlay::TimeSource> clock = overlay::timeSourceOf(time_source);
        if (!clock) throw py::value_error("time_source: expected 'header' or 'log'");
        if (!h && (!joint_topic.empty() || !joint_map.empty())) throw py::value_error("joint_topic and joint_map need a model");
        for (const long f : frames)
          if (f < 0) throw py::value_error("frames: indices from 0");
        py::dict d;
        const overlay::BagRecordingOptions o{
            .bag = path, .joint_topic = joint_topic, .image_topic = image_topic,
            .time_source = *clock,
            .joint_map = joint_map.empty() || !h ? overlay::JointMap{} : overlay::loadJointMap(joint_map, *h->model)};
        nlohmann::json info;
        overlay::BagRecording rec;
        std::vector<cv::Mat> images;
        {
          py::gil_scoped_release release;
          info = overlay::bagInfoJson(logs::summarizeBag(path));
          if (h || !frames.empty() || !image_topic.empty()) rec = h ? overlay::readBagRecording(o, *h->model) : overlay::readBagImages(o);
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
          d["state_names"] = rec.log.names;
          d["times"] = floatArray(rec.log.times);
          py::array_t<double> states({static_cast<py::ssize_t>(rec.log.rows()), static_cast<py::ssize_t>(rec.log.stateSize())});
          std::copy(rec.log.values.begin(), rec.log.values.end(), states.mutable_data());
          d["states"] = states;
        }
        if (!frames.empty()) {
          py::list list;
          for (const cv::Mat& img : images) {
            py::array_t<std::uint8_t> a({img.rows, img.cols, 3});
            for (int y = 0; y < img.rows; ++y) std::memcpy(a.mutable_data(y, 0, 0), img.ptr(y), static_cast<std::size_t>(img.cols) * 3);
            list.append(a);
          }
          d["images"] = list;
        }
        return d;
      },
      py::arg("path"), py::arg("model") = nullptr, py::kw_only(), py::arg("image_topic") = "", py::arg("joint_topic") = "",
      py::arg("time_source") = "header", py::arg("joint_map") = "", py::arg("frames") = std::vector<long>{},
      R"doc(What a robot log (MCAP, rosbag2 .db3 or folder, ROS 1 .bag) holds, as `kccd bag info --json` under 'info'.
With a model, also what `kccd overlay --bag` reads: 'state_names', 'times' (s, from 'origin_ns' on the chosen
clock), 'states' (one row per joint state, the model's state values matched by name or by joint_map),
'joint_topic'; with a model or frames: 'image_topic', 'frame_times' (s, same clock), 'fps' (the median
interval's rate), 'warnings'. frames: indices of the image topic's frames returned under 'images' as uint8
(H, W, 3) RGB. time_source: 'header' (header stamps) or 'log' (the recorder's times). Raises InputError
naming the file, topic and place.)doc");

  m.def(
      "synthesize_recording",
      [](const std::string& model, const std::string& output, const std::string& camera, double seconds, double fps,
         double log_rate, double time_offset, std::uint64_t seed, const std::string& codec, bool collision, bool replace,
         const std::optional<int>& width, const std::optional<int>& height, const std::string& appearance,
         const std::optional<double>& visible_scale, double blur, double noise, const py::object& progress) {
        overlay::SynthOptions o;
        o.width = width, o.height = height, o.visible_scale = visible_scale, o.blur = blur, o.noise = noise;
        if (appearance == "auto") o.appearance = overlay::SynthAppearance::Auto;
        else if (appearance == "volumes") o.appearance = overlay::SynthAppearance::Volumes;
        else if (appearance == "visuals") o.appearance = overlay::SynthAppearance::Visuals;
        else throw py::value_error("appearance: 'auto', 'volumes' or 'visuals', got '" + appearance + "'");
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
        ProgressRelay relay{progress, {}};
        overlay::SynthResult r;
        relay.run([&] { r = overlay::synthesizeRecording(o, [&](double fraction) { relay(fraction); }); });
        py::dict d;
        d["folder"] = r.folder.string();
        d["video"] = (r.folder / r.video_file).string();
        d["states"] = (r.folder / "states.csv").string();
        d["camera"] = (r.folder / "camera_true.yaml").string();
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
      py::arg("codec") = "ffv1", py::arg("collision") = true, py::arg("replace") = false, py::arg("width") = py::none(),
      py::arg("height") = py::none(), py::arg("appearance") = "auto", py::arg("visible_scale") = py::none(), py::arg("blur") = 0.7,
      py::arg("noise") = 2.5, py::arg("progress") = py::none(),
      R"doc(A synthetic recording with ground truth, as `kccd synth`: in the new folder `output`, the video, the state
log states.csv, the true camera camera_true.yaml, tags, masks and synth.json (the folder appears only when
complete). model: a model file. Every option of `kccd synth` under its own name: width and height (the default
camera's image size, not with camera), appearance ('auto', 'volumes' or 'visuals'), visible_scale (the volumes'
drawn radius fraction), blur and noise (sigmas). An option out of range raises InputError naming it ("fps: must be
1 ... 240"). progress(fraction) is called after each frame with the GIL held. Returns
a dict with the files' paths and the truth: per-frame 'min_distance' (metres), 'colliding_frames',
'near_frames', 'collision_intervals' ([first, last] frames).)doc");
}

}  // namespace kccd::python
