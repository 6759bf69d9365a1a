// `kccd overlay MODEL --camera CAM.yaml --video IN --states LOG.csv -o OUT`: the collision volumes
// at each frame's logged state, coloured by the library's query, composited onto a recorded video
// (kccd::overlay::overlayRecording does the work; this file reads the options and prints).
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/recording/frame_times.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {


struct OverlayArgs {
  std::string model, camera, video, states, output, png_dir, report, frames, frame_times, ignore_columns, codec, contact_sheet, timeline;
  std::string bag, image_topic, joint_topic, joint_map, time_source = "header", masks, mask_bodies;
  int contact_frames = 12;
  std::string time_offset_text = "0";  // seconds, or auto:A:B
  double max_gap = 0.0, fps = 0.0;
  double latency = overlay::kOverlayBraking.latency, deceleration = overlay::kOverlayBraking.deceleration,
         max_acceleration = overlay::kOverlayBraking.max_acceleration,
         position_error = overlay::kOverlayBraking.position_error, velocity_error = overlay::kOverlayBraking.velocity_error;
  bool swept = false, plain = false, quiet = false, json = false, visuals = false, timings = false;
  int jobs = 0;  // 0: hardware threads
};

// "S" (seconds) sets the offset; "auto:A:B" asks for a search of [A, B].
void parseTimeOffset(const std::string& text, overlay::OverlayOptions& o) {
  auto num = [&](const std::string& t, double& out) {
    char* end = nullptr;
    out = std::strtod(t.c_str(), &end);
    return !t.empty() && end == t.c_str() + t.size() && std::isfinite(out) && std::fabs(out) <= 1e9;
  };
  if (text.rfind("auto:", 0) == 0) {
    const std::string rest = text.substr(5);
    const std::size_t colon = rest.find(':');
    double lo = 0, hi = 0;
    if (colon == std::string::npos || !num(rest.substr(0, colon), lo) || !num(rest.substr(colon + 1), hi) || !(lo < hi))
      throw UsageError("--time-offset " + text + ": expected auto:A:B with A < B (seconds, the range searched)");
    o.time_offset_search = {lo, hi};
    o.time_offset_label = "--time-offset auto:" + format(lo) + ":" + format(hi);
    return;
  }
  if (!num(text, o.time_offset)) throw UsageError("--time-offset " + text + ": expected seconds (within 1e9) or auto:A:B");
}

Exit runOverlay(const OverlayArgs& a) {
  const auto t_start = std::chrono::steady_clock::now();
  // Every input and option is checked before any frame is decoded.
  const Model model = loadOrExplain(a.model);
  const calib::Camera camera = calib::loadCamera(a.camera);
  if (a.output.empty() && a.png_dir.empty() && a.report.empty() && a.contact_sheet.empty() && a.timeline.empty())
    throw UsageError("nothing to write: give -o VIDEO, --png-dir DIR, --report FILE, --contact-sheet FILE and/or --timeline FILE");
  const overlay::OverlayOutputs outputs{
      .video = a.output, .png_dir = a.png_dir, .report = a.report, .contact_sheet = a.contact_sheet, .timeline = a.timeline,
      .timeline_title = std::filesystem::path(a.bag.empty() ? a.video : a.bag).filename().string() + "  (" +
                        std::filesystem::path(a.model).filename().string() + ")"};
  overlay::checkOverlayOutputs(outputs, std::vector<std::string>{a.video, a.states, a.model, a.camera, a.frame_times, a.bag, a.joint_map});
  if (!a.bag.empty()) {
    for (const auto& [given, name] : {std::pair{a.video, "--video"}, {a.states, "--states"}, {a.frame_times, "--frame-times"}, {a.ignore_columns, "--ignore-columns"}})
      if (!given.empty()) throw UsageError(std::string(name) + ": not with --bag (the log gives the frames, their times and the states)");
    if (a.fps > 0.0) throw UsageError("--fps: not with --bag (each frame has its own time)");
  } else {
    if (a.video.empty() || a.states.empty()) throw UsageError("give --video and --states, or --bag (a robot log)");
    if (!a.image_topic.empty() || !a.joint_topic.empty() || !a.joint_map.empty())
      throw UsageError("--image-topic, --joint-topic and --joint-map go with --bag");
  }
  if (!a.codec.empty() && a.codec.size() != 4)
    throw UsageError("--codec " + a.codec + ": a FourCC is 4 characters (e.g. mp4v, avc1, MJPG, FFV1)");
  overlay::OverlayOptions o;
  o.frames = overlay::parseFrameRange(a.frames, "--frames");
  parseTimeOffset(a.time_offset_text, o);
  std::optional<overlay::BagRecording> bag;
  if (!a.bag.empty()) {
    bag = overlay::readBagRecording({.bag = a.bag, .joint_topic = a.joint_topic, .image_topic = a.image_topic,
                                     .time_source = *overlay::timeSourceOf(a.time_source),  // checked by the option
                                     .joint_map = a.joint_map.empty() ? overlay::JointMap{} : overlay::loadJointMap(a.joint_map, model)},
                                    model);
    for (const std::string& w : bag->warnings) std::cerr << "kccd overlay: warning: --bag " << a.bag << ": " << w << "\n";
  }
  const StateLog log = bag ? std::move(bag->log) : loadStateLog(a.states, model, splitCommas(a.ignore_columns));
  overlay::OverlayInputs in{model, camera, log, bag ? a.bag : a.video, {},
                            bag ? "--bag " + a.bag + " (topic " + bag->image_topic + ")" : "--video " + a.video, a.camera,
                            "--frame-times " + a.frame_times};
  if (bag) {
    in.frame_times = bag->frame_times;
    in.open_frames = bag->open_frames;
  }
  if (!a.frame_times.empty()) try {
      in.frame_times = overlay::loadFrameTimes(a.frame_times);
    } catch (const overlay::FrameTimesError& e) {
      throw UsageError(std::string("--frame-times ") + e.what());
    }
  std::optional<overlay::MaskAgreement> masks;
  if (!a.masks.empty()) {
    std::vector<int> bodies;
    for (const std::string& name : splitCommas(a.mask_bodies)) {
      const int b = model.bodyIndex(name);
      if (b < 0) throw UsageError("--mask-bodies: '" + name + "' is not a body of " + a.model + " (kccd info lists them)");
      bodies.push_back(b);
    }
    if (a.masks == "auto") masks.emplace(camera, model, std::move(bodies), "--masks auto");
    else masks.emplace(a.masks, camera, model, std::move(bodies), "--masks " + a.masks);
    in.masks = &*masks;
  } else if (!a.mask_bodies.empty()) {
    throw UsageError("--mask-bodies: goes with --masks");
  }
  if (a.visuals && model.visuals.empty()) throw UsageError("--visuals: " + a.model + " has no visuals:");
  if (a.visuals && model.visuals.size() + model.bodies.size() > 255)
    throw UsageError("--visuals: " + a.model + ": more than 255 bodies and visuals to draw");
  o.max_gap = a.max_gap;
  o.fps = a.fps;
  o.swept = a.swept;
  o.braking = BrakingParams{.position_error = a.position_error, .velocity_error = a.velocity_error, .latency = a.latency,
                            .max_acceleration = a.max_acceleration, .deceleration = a.deceleration};
  o.plain = a.plain;
  o.visuals = a.visuals;
  o.jobs = a.jobs;
  o.timings = a.timings;
  o.contact_frames = a.contact_sheet.empty() ? 0 : static_cast<std::size_t>(a.contact_frames);

  // Outputs under temporary names, moved into place only when every frame is done.
  overlay::VideoSink sink({.video = a.output, .codec = a.codec, .video_label = "-o " + a.output, .png_dir = a.png_dir,
                           .png_label = "--png-dir " + a.png_dir});
  Progress progress("overlay", a.quiet);
  overlay::OverlayReport r =
      overlay::overlayRecording(in, o, sink.active() ? &sink : nullptr, [&](const overlay::OverlayProgress& p) {
        const std::size_t n = p.frames_done, expected = p.frames_expected;
        std::string detail = std::to_string(n) + (expected ? "/" + std::to_string(expected) : "") + " frames, " +
                             format(p.frames_per_second, 3) + " fps";
        if (expected > n && p.frames_per_second > 0)
          detail += ", ETA " + std::to_string(std::lround((expected - n) / p.frames_per_second)) + " s";
        progress.update(expected ? static_cast<double>(n) / static_cast<double>(expected) : 0.0, detail);
      });
  progress.finish();
  if (bag) r.source = bag->source();

  nlohmann::json j = overlay::writeOverlayOutputs(outputs, r, model, sink);
  j.erase("frames");  // the summary printed by --json

  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  const std::size_t frames = r.frames.size();
  if (a.json) {
    j["seconds"] = total;
    j["frames_per_second"] = r.seconds > 0 ? static_cast<double>(frames) / r.seconds : 0.0;
    j["jobs"] = r.jobs;
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::cout << "overlay: " << frames << " frames, " << r.written << " written";
    if (!a.output.empty()) std::cout << " to " << a.output;
    if (!a.png_dir.empty()) std::cout << (a.output.empty() ? " to " : " and ") << a.png_dir;
    std::cout << "; clear " << r.clear << ", within margin " << r.within_margin << ", colliding " << r.colliding
              << ", no state " << r.no_state << "; "
              << (o.time_offset_search ? "time offset " + format(r.time_offset, 6) + " s (auto, correlation " +
                                             format(r.time_offset_found.correlation, 3) + "); "
                                       : "")
              << format(frames / std::max(r.seconds, 1e-9), 3) << " frames/s with " << r.jobs << " jobs\n";
    if (const overlay::AgreementSummary m = overlay::summariseAgreement(r.frames); m.frames > 0) {
      std::cout << "masks: IoU with the drawn robot over " << m.frames << " frames: mean " << format(m.mean, 3) << ", smallest "
                << format(m.min, 3) << "; " << m.low.size() << " frame(s) below " << format(m.low_below, 3)
                << " (0.8 x the median)";
      for (std::size_t k = 0; k < std::min<std::size_t>(m.low.size(), 5); ++k)
        std::cout << (k ? ", " : ": lowest ") << m.low[k] << " (" << format(*r.frames[m.low[k]].mask_iou, 3) << ")";
      std::cout << "\n";
    }
  }
  if (a.timings) {
    const overlay::StageTimes& t = r.stages;
    const double n = std::max<double>(1.0, static_cast<double>(frames));
    std::cerr << "overlay timings: set-up " << format(r.setup_seconds, 3) << " s, frames " << format(r.seconds, 3)
              << " s with " << r.jobs << " jobs, " << r.reused
              << " frame(s) reused (the same state as their annotator's last); per frame (ms, each on its own thread):\n";
    const std::pair<const char*, double> rows[] = {{"decode", t.decode},   {"state", t.state},         {"query", t.query},
                                                   {"render", t.render},   {"read_back", t.read_back}, {"warp", t.warp},
                                                   {"composite", t.composite}, {"encode", t.encode}};
    for (const auto& [name, seconds] : rows) std::cerr << "  " << name << " " << format(1000.0 * seconds / n, 3) << "\n";
  }
  if (const std::optional<std::size_t> first = r.firstUnsafe()) {
    const overlay::FrameRecord& f = r.frames[*first];
    std::cerr << "kccd: " << r.unsafe << " frame(s) with an unsafe query status, first frame " << *first << ": "
              << (f.braking_failed ? "no braking box (non-finite state or velocity)"
                  : f.not_finite   ? "volume not finite"
                                   : toString(f.query))
              << " (unsafe; everything was written)\n";
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
  sub->add_option("--video", a->video, "Input video (any OpenCV reads) or image sequence (e.g. frames/frame_%06d.png); or --bag");
  sub->add_option("--states", a->states, "State log (CSV: time and one column per state value, see kccd info); or --bag");
  sub->add_option("--bag", a->bag,
                  "A robot log instead of --video, --states and --frame-times (MCAP, rosbag2 .db3 or folder, ROS 1 .bag): "
                  "the image topic's frames at their own times, the joint states matched to the model's joints by name");
  sub->add_option("--image-topic", a->image_topic, "With --bag: the sensor_msgs/Image or CompressedImage topic (default: the only one)");
  sub->add_option("--joint-topic", a->joint_topic, "With --bag: the sensor_msgs/JointState topic (default: the only one)");
  sub->add_option("--time-source", a->time_source,
                  "With --bag: header (the messages' header stamps; the log time where one is zero) or log (the recorder's times)")
      ->check(CLI::IsMember({"header", "log"}))
      ->default_str("header");
  sub->add_option("--joint-map", a->joint_map,
                  "With --bag: YAML (kccd_joint_map: 1) saying which logged joint each state value is read from, with a scale, "
                  "an offset or degrees, or a constant (see docs/formats.md); values it does not list are read by their own name");
  sub->add_option("-o,--output", a->output, "Output video (.mp4: mp4v, .mkv: FFV1 lossless, .avi: MJPG; see --codec)");
  sub->add_option("--png-dir", a->png_dir, "Also (or only) write frame_%06d.png (input frame numbers) into this new or empty folder");
  sub->add_option("--frames", a->frames, "Frames to draw and write: FIRST:END:STEP (from 0, END exclusive; all frames are still checked and reported)");
  sub->add_option("--contact-sheet", a->contact_sheet,
                  "A .png of --contact-frames drawn frames spread over the run, the most critical one included, captioned");
  sub->add_option("--timeline", a->timeline,
                  "A .png of the run over time: the smallest distance bound and the margin, the spans within the margin, colliding "
                  "or without a state shaded and listed with the link pairs responsible, the contact sheet's frames marked");
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
  sub->add_option("--masks", a->masks,
                  "Folder of robot masks, frame_000000.png ... (one per frame, any segmentation tool's output, non-zero = robot; "
                  "frames without a file are skipped): each frame's IoU with the robot drawn at its logged state goes into the "
                  "report, the summary, the timeline and the contact sheet's captions; frames far below the run's median stand "
                  "out (a wrong clock offset, a joint offset, a moved camera). --masks auto: each frame's mask made from the "
                  "recording itself (a fixed camera): what differs from its background, learnt over 40 frames spread over it "
                  "away from the robot drawn at their logged states, taken where the background is known (not where the robot "
                  "never moves away); only the bodies that move are drawn");
  sub->add_option("--mask-bodies", a->mask_bodies, "Comma-separated bodies of the model that the masks show (default: all bodies)");
  sub->add_option("--codec", a->codec, "FourCC of the output video (default by extension)");
  sub->add_option("-j,--jobs", a->jobs, "Worker threads (each with its own GL context; default: hardware threads)")->check(CLI::Range(1, 256));
  sub->add_flag("--json", a->json, "Print the summary as JSON");
  sub->add_flag("--timings", a->timings,
                "Where the time went: set-up and per frame decode, state, query, render, read-back, warp, composite and encode "
                "(ms per frame on stderr; \"timings\" in --report and --json)");
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
