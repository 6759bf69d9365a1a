// `kccd overlay MODEL --camera CAM.yaml --video IN --states LOG.csv -o OUT`: the collision volumes
// at each frame's logged state, coloured by the library's query, composited onto a recorded video
// (kccd::overlay::OverlayJob does the work; this file reads the options into its request and prints).
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/overlay/jobs/overlay_job.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"
#include "kccd/overlay/recording/video_file.hpp"
#include "kccd/render/gl_context.hpp"

namespace kccd::cli {
namespace {

struct OverlayArgs {
  overlay::OverlayRequest request;
  std::string model, camera, ignore_columns, mask_bodies;
  std::string time_offset_text = "0";  // seconds, or auto:A:B
  BrakingParams braking = overlay::kOverlayBraking;
  bool braking_given = false;  // any braking option on the command line
  bool quiet = false, json = false;
};

// The command line's spelling of the request's fields: --field-name, but for these.
const std::map<std::string, std::string> kSpelling = {
    {"output", "-o"},
    {"braking", "--latency, --deceleration, --max-acceleration, --position-error and --velocity-error"}};
std::string spelled(const std::string& field) { return optionSpelling(field, kSpelling); }

Exit runOverlay(OverlayArgs& a) {
  const auto t_start = std::chrono::steady_clock::now();
  const render::GlPreparation gl;  // Mesa's driver loads on a thread of its own while the inputs are read
  const overlay::VideoLibraryPreparation video_libraries;  // and FFmpeg's libraries on another
  overlay::OverlayRequest& q = a.request;
  const Model model = loadOrExplain(a.model);
  const calib::Camera camera = calib::loadCamera(a.camera);
  if (q.output.empty() && q.png_dir.empty() && q.report.empty() && q.contact_sheet.empty() && q.timeline.empty())
    throw UsageError(
        "nothing to write: give -o VIDEO, --png-dir DIR, --report FILE, --contact-sheet FILE and/or --timeline FILE");
  q.model_file = a.model;
  q.camera_file = a.camera;
  q.ignore_columns = splitCommas(a.ignore_columns);
  q.mask_bodies = splitCommas(a.mask_bodies);
  if (a.braking_given) q.braking = a.braking;
  try {
    overlay::parseTimeOffset(a.time_offset_text, q);
  } catch (const InputError& e) {
    rethrowAsOption(e, kSpelling);
  }
  // Every input and option is checked before any frame is decoded.
  overlay::OverlayJob job(q, model, camera, spelled);
  for (const std::string& w : job.warnings())
    std::cerr << "kccd overlay: warning: " << (q.bag.empty() ? "" : "--bag " + q.bag + ": ") << w << "\n";

  // Outputs under temporary names, moved into place only when every frame is done.
  Progress progress("overlay", a.quiet);
  overlay::OverlayJob::Result result = job.run([&](const overlay::OverlayProgress& p) {
    const std::size_t n = p.frames_done, expected = p.frames_expected;
    std::string detail = std::to_string(n) + (expected ? "/" + std::to_string(expected) : "") + " frames, " +
                         format(p.frames_per_second, 3) + " fps";
    if (expected > n && p.frames_per_second > 0)
      detail += ", ETA " + std::to_string(std::lround((expected - n) / p.frames_per_second)) + " s";
    progress.update(expected ? static_cast<double>(n) / static_cast<double>(expected) : 0.0, detail);
  });
  progress.finish();
  const overlay::OverlayReport& r = result.report;
  nlohmann::json& j = result.json;
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
    if (!q.output.empty()) std::cout << " to " << q.output;
    if (!q.png_dir.empty()) std::cout << (q.output.empty() ? " to " : " and ") << q.png_dir;
    std::cout << "; clear " << r.clear << ", within margin " << r.within_margin << ", colliding " << r.colliding
              << ", no state " << r.no_state << "; "
              << (q.time_offset_search ? "time offset " + format(r.time_offset, 6) + " s (auto, correlation " +
                                             format(r.time_offset_found.correlation, 3) + "); "
                                       : "")
              << format(frames / std::max(r.seconds, 1e-9), 3) << " frames/s with " << r.jobs << " jobs\n";
    if (const overlay::AgreementSummary m = overlay::summariseAgreement(r.frames); m.frames > 0) {
      std::cout << "masks: IoU with the drawn robot over " << m.frames << " frames: mean " << format(m.mean, 3)
                << ", smallest " << format(m.min, 3) << "; " << m.low.size() << " frame(s) below "
                << format(m.low_below, 3) << " (0.8 x the median)";
      for (std::size_t k = 0; k < std::min<std::size_t>(m.low.size(), 5); ++k)
        std::cout << (k ? ", " : ": lowest ") << m.low[k] << " (" << format(*r.frames[m.low[k]].mask_iou, 3) << ")";
      std::cout << "\n";
    }
  }
  if (q.timings) {
    const overlay::StageTimes& t = r.stages;
    const double n = std::max<double>(1.0, static_cast<double>(frames));
    std::cerr
        << "overlay timings: set-up " << format(r.setup_seconds, 3) << " s, frames " << format(r.seconds, 3)
        << " s with " << r.jobs << " jobs, " << r.reused
        << " frame(s) reused (the same state as their annotator's last); per frame (ms, each on its own thread):\n";
    const std::pair<const char*, double> rows[] = {
        {"decode", t.decode},       {"state", t.state}, {"query", t.query},         {"render", t.render},
        {"read_back", t.read_back}, {"warp", t.warp},   {"composite", t.composite}, {"encode", t.encode}};
    for (const auto& [name, seconds] : rows)
      std::cerr << "  " << name << " " << format(1000.0 * seconds / n, 3) << "\n";
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
      "overlay",
      "Batch overlay: the collision volumes at each frame's logged state, coloured by the query, on a recorded video");
  sub->add_option("model", a->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--camera", a->camera,
                  "Camera file (OpenCV YAML: intrinsics, distortion, rvec/tvec); its image size must be the video's")
      ->required();
  sub->add_option("--video", a->request.video,
                  "Input video (any OpenCV reads) or image sequence (e.g. frames/frame_%06d.png); or --bag");
  sub->add_option("--states", a->request.states,
                  "State log (CSV: time and one column per state value, see kccd info); or --bag");
  sub->add_option(
      "--bag", a->request.bag,
      "A robot log instead of --video, --states and --frame-times (MCAP, rosbag2 .db3 or folder, ROS 1 .bag): "
      "the image topic's frames at their own times, the joint states matched to the model's joints by name");
  sub->add_option("--image-topic", a->request.image_topic,
                  "With --bag: the sensor_msgs/Image or CompressedImage topic (default: the only one)");
  sub->add_option("--joint-topic", a->request.joint_topic,
                  "With --bag: the sensor_msgs/JointState topic (default: the only one)");
  sub->add_option("--time-source", a->request.time_source,
                  "With --bag: header (the messages' header stamps; the log time where one is zero) or log (the "
                  "recorder's times)")
      ->capture_default_str();
  addLerobotOptions(*sub, a->request.lerobot, a->request.episode, a->request.state_key, &a->request.frame_by);
  sub->add_option("--camera-key", a->request.camera_key,
                  "With --lerobot: the camera feature drawn on (default: the dataset's only camera)");
  sub->add_option(
      "--joint-map", a->request.joint_map,
      "With --bag or --lerobot: YAML (kccd_joint_map: 1) saying which logged joint each state value is read from, "
      "with a scale, an offset, degrees or a range (LeRobot's -100 ... 100), or a constant (see docs/formats.md); "
      "values it does not list are read by their own name (or NAME.pos)");
  sub->add_option("-o,--output", a->request.output,
                  "Output video (.mp4: mp4v, .mkv: FFV1 lossless, .avi: MJPG; see --codec)");
  sub->add_option("--png-dir", a->request.png_dir,
                  "Also (or only) write frame_%06d.png (input frame numbers) into this new or empty folder");
  sub->add_option(
      "--frames", a->request.frames,
      "Frames to draw and write: FIRST:END:STEP (from 0, END exclusive; all frames are still checked and reported)");
  sub->add_option(
      "--contact-sheet", a->request.contact_sheet,
      "A .png of --contact-frames drawn frames spread over the run, the most critical one included, captioned");
  sub->add_option(
      "--timeline", a->request.timeline,
      "A .png of the run over time: the smallest distance bound and the margin, the spans within the margin, colliding "
      "or without a state shaded and listed with the link pairs responsible, the contact sheet's frames marked");
  sub->add_option("--contact-frames", a->request.contact_frames, "Frames on the contact sheet (1 ... 64)")
      ->capture_default_str();
  sub->add_option("--report", a->request.report,
                  "Per-frame report (.json): state match, status, min distance, pairs within the margin");
  sub->add_option("--frame-times", a->request.frame_times,
                  "CSV 'frame,time': each frame's time in seconds (default: index / fps)");
  sub->add_option("--fps", a->request.fps, "Frame rate of the input, 1e-6 ... 1e6 (0: the video's own)")
      ->capture_default_str();
  sub->add_option(
         "--time-offset", a->time_offset_text,
         "Added to each frame's time to get the state log's time (s); auto:A:B searches [A, B] for the offset at which "
         "the image motion best follows the logged motion")
      ->capture_default_str();
  sub->add_option("--max-gap", a->request.max_gap,
                  "No state when no two log samples this close bracket the time (s; 0: 1.5 x the log's median period)")
      ->capture_default_str();
  sub->add_option("--ignore-columns", a->ignore_columns,
                  "Comma-separated state log columns to skip (an unknown column is an error)");
  sub->add_flag(
      "--swept", a->request.swept,
      "Draw the braking-interval swept volumes (from logged or differenced velocities) instead of the static ones");
  addBrakingOptions(*sub, a->braking);
  sub->add_flag("--plain", a->request.plain, "Volumes only: no legend, no status line");
  sub->add_option("--legend", a->request.legend,
                  "Where the colour legend goes: auto (the corner of the picture where it hides the fewest pixels of "
                  "the volumes drawn; it moves only when another corner has been clearer for 8 frames), top-left, "
                  "top-right, bottom-left, bottom-right, outside (a strip under the picture that also holds the status "
                  "line: the output frames are taller than the input) or off")
      ->capture_default_str();
  sub->add_flag("--visuals", a->request.visuals,
                "Also draw the model's visual geometry (visuals:) at the logged state, tinted in its own colours: "
                "where it misses the robot in the video, the camera, the log's clock or the model is off");
  sub->add_option(
      "--masks", a->request.masks,
      "Folder of robot masks, frame_000000.png ... (one per frame, any segmentation tool's output, non-zero = robot; "
      "frames without a file are skipped): each frame's IoU with the robot drawn at its logged state goes into the "
      "report, the summary, the timeline and the contact sheet's captions; frames far below the run's median stand "
      "out (a wrong clock offset, a joint offset, a moved camera). --masks auto: each frame's mask made from the "
      "recording itself (a fixed camera): what differs from its background, learnt over 40 frames spread over it "
      "away from the robot drawn at their logged states, taken where the background is known (not where the robot "
      "never moves away); only the bodies that move are drawn");
  sub->add_option("--mask-bodies", a->mask_bodies,
                  "Comma-separated bodies of the model that the masks show (default: all bodies)");
  sub->add_option("--codec", a->request.codec, "FourCC of the output video (default by extension)");
  sub->add_option("-j,--jobs", a->request.jobs,
                  "Worker threads, 0 ... 256 (each with its own GL context; 0: hardware threads)")
      ->capture_default_str();
  sub->add_flag("--json", a->json, "Print the summary as JSON");
  sub->add_flag(
      "--timings", a->request.timings,
      "Where the time went: set-up and per frame decode, state, query, render, read-back, warp, composite and encode "
      "(ms per frame on stderr; \"timings\" in --report and --json)");
  sub->add_flag("-q,--quiet", a->quiet, "No progress and no summary");
  sub->footer(
      "Each frame's time (index / fps, or --frame-times) plus --time-offset is looked up in the state log: a sample\n"
      "(exact), a linear interpolation between two samples at most --max-gap apart, or no state. Without a state only\n"
      "the bodies fixed in the world are drawn (grey); the frame is counted and reported as no_state.\n"
      "Colours: green clear, amber within the safety margin, red colliding or unsafe, grey no state.\n"
      "Text, legend and status line scale with the frame's height; a status line too wide for the frame drops its\n"
      "least important parts first (the state's match, swept, the time, then the pairs within the margin).\n"
      "Outputs are written under temporary names and moved into place only when every frame is done.\n"
      "Exit status: 0 written, 2 bad input (nothing written), 3 a frame's query status is unsafe (everything still "
      "written).");
  return [a, sub] {
    a->braking_given = brakingGiven(*sub);
    return runOverlay(*a);
  };
}

}  // namespace kccd::cli
