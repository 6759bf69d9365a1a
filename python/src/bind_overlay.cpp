// The main job from Python: kccd.overlay_recording (a recording and its state log checked and drawn
// frame by frame) and kccd.synthesize_recording (a synthetic recording with ground truth).
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "bindings.hpp"
#include "progress_relay.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/overlay/contact_sheet.hpp"
#include "kccd/overlay/overlay_recording.hpp"
#include "kccd/overlay/staged_output.hpp"
#include "kccd/overlay/synth.hpp"
#include "kccd/overlay/video_sink.hpp"
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
         int contact_frames, const py::object& progress, double progress_every) {
        const Model& model = *h->model;
        if (!(progress_every >= 0.0) || !std::isfinite(progress_every))
          throw py::value_error("progress_every: must be a finite number of seconds >= 0");
        const StateLog log = loadStateLog(states, model);
        overlay::OverlayInputs in{model, camera, log, video, {}, "video " + video, "camera", ""};
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
                                              .frames_option = "frames"};
        overlay::checkOverlayOutputs(outputs, std::vector<std::string>{video, states, h->source});
        overlay::VideoSink sink({.video = output, .codec = "", .video_label = "output " + output, .png_dir = "", .png_label = ""});
        ProgressRelay relay{progress, {}};
        nlohmann::json full;
        relay.run([&] {
          const overlay::OverlayReport r = overlay::overlayRecording(
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
          full = overlay::writeOverlayOutputs(outputs, r, model, sink);
        });
        return toPython(full);
      },
      py::arg("model"), py::arg("camera"), py::arg("video"), py::arg("states"), py::kw_only(), py::arg("output") = "",
      py::arg("report") = "", py::arg("contact_sheet") = "", py::arg("time_offset") = 0.0, py::arg("swept") = false,
      py::arg("braking") = py::none(), py::arg("jobs") = 0, py::arg("frames") = "", py::arg("contact_frames") = 12, py::arg("progress") = py::none(),
      py::arg("progress_every") = 0.0,
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
per-frame records under 'frames'). Raises InputError naming the input and place.)doc");

  m.def(
      "synthesize_recording",
      [](const std::string& model, const std::string& output, const std::string& camera, double seconds, double fps,
         double log_rate, double time_offset, std::uint64_t seed, const std::string& codec, bool collision, bool replace,
         const py::object& progress) {
        overlay::SynthOptions o;
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
      py::arg("codec") = "ffv1", py::arg("collision") = true, py::arg("replace") = false, py::arg("progress") = py::none(),
      R"doc(A synthetic recording with ground truth, as `kccd synth`: in the new folder `output`, the video, the state
log states.csv, the true camera camera_true.yaml, tags, masks and synth.json (the folder appears only when
complete). model: a model file. progress(fraction) is called after each frame with the GIL held. Returns
a dict with the files' paths and the truth: per-frame 'min_distance' (metres), 'colliding_frames',
'near_frames', 'collision_intervals' ([first, last] frames).)doc");
}

}  // namespace kccd::python
