// `kccd synth MODEL -o DIR`: a synthetic recording with ground truth (kccd::overlay::
// synthesizeRecording, kccd/overlay/synth/synth.hpp) — the options, the call, the summary line.
#include <iostream>
#include <memory>
#include <string>

#include "cli_args.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/overlay/synth/synth.hpp"

namespace kccd::cli {
namespace {

// The command line's values; those that are optional in SynthOptions are copied only when given.
struct SynthArgs {
  overlay::SynthOptions options;
  int width = overlay::SynthOptions::kDefaultWidth, height = overlay::SynthOptions::kDefaultHeight;
  double visible_scale = overlay::SynthOptions::kDefaultVisibleScale;
  std::string appearance = "auto";  // auto, volumes, visuals
  bool no_collision = false, quiet = false;
};

Exit runSynth(const overlay::SynthOptions& o, bool quiet) {
  Progress progress("synth", quiet);
  overlay::SynthResult r;
  try {
    r = overlay::synthesizeRecording(o, [&progress](double f) { progress.update(f); });
  } catch (const overlay::SynthError& e) {
    rethrowAsOption(e);
  }
  progress.finish();
  if (!quiet) {
    std::cout << "wrote " << o.output << ": " << r.frames << " frames " << r.width << "x" << r.height << " at " << r.fps
              << " fps (" << r.video_file << "), states.csv" << (r.bag_file.empty() ? "" : " and " + r.bag_file)
              << " at " << r.log_rate << " Hz (log time = video time + " << r.time_offset << " s), " << r.tags
              << " tags, in " << format(r.seconds, 3) << " s\n";
    if (!r.collision_intervals.empty())
      std::cout << "collision: frames " << r.collision_intervals[0][0] << "-" << r.collision_intervals[0][1] << "; "
                << r.near_frames.size() << " frames within the margin\n";
    else
      std::cout << "no collision; " << r.near_frames.size() << " frames within the margin\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addSynth(CLI::App& app) {
  auto a = std::make_shared<SynthArgs>();
  CLI::App* sub = app.add_subcommand(
      "synth", "Synthetic recording with ground truth: video, state log, true camera, tags, masks, summary");
  sub->add_option("model", a->options.model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("-o,--output", a->options.output, "Output folder (created; complete only when the command succeeds)")
      ->required();
  sub->add_option("--camera", a->options.camera,
                  "Camera file to film with (default: one placed to see the robot, the floor and two walls)");
  sub->add_option("--seconds", a->options.seconds, "Length of the recording (s)")
      ->capture_default_str()
      ->check(finiteIn(0.04, 600));
  sub->add_option("--fps", a->options.fps, "Video frame rate")->capture_default_str()->check(finiteIn(1, 240));
  CLI::Option* width = sub->add_option("--width", a->width, "Image width of the default camera (px)")
                           ->capture_default_str()
                           ->check(CLI::Range(64, 4096));
  CLI::Option* height = sub->add_option("--height", a->height, "Image height of the default camera (px)")
                            ->capture_default_str()
                            ->check(CLI::Range(64, 4096));
  sub->add_option("--seed", a->options.seed, "Seed of the trajectory search and the noise")
      ->capture_default_str()
      ->check(seedNumber());
  sub->add_option("--codec", a->options.codec,
                  "ffvhuff (video.mkv, lossless, fast), ffv1 (video.mkv, lossless, 0.8x the size, 4x slower to write), "
                  "mjpg (video.avi) or mp4v (video.mp4)")
      ->capture_default_str();
  sub->add_option("--log-rate", a->options.log_rate, "State log rate (Hz; must differ from --fps)")
      ->capture_default_str()
      ->check(finiteIn(1, 10000));
  sub->add_option("--time-offset", a->options.time_offset,
                  "Log clock minus video clock (s; the log starts at log time 0)")
      ->capture_default_str()
      ->check(finiteIn(0, 10));
  CLI::Option* shrink =
      sub->add_option("--visible-scale", a->visible_scale,
                      "Radius of the visible geometry as a fraction of the SSCH radius (--appearance volumes)")
          ->capture_default_str()
          ->check(finiteIn(0.1, 0.95));
  sub->add_option("--appearance", a->appearance,
                  "What the robot looks like: visuals (the model's visual meshes), volumes (its SSCHs shrunk by "
                  "--visible-scale), auto (visuals when the model has them)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "volumes", "visuals"}));
  sub->add_option("--blur", a->options.blur, "Gaussian blur of every frame (sigma, px)")
      ->capture_default_str()
      ->check(finiteIn(0, 10));
  sub->add_option("--noise", a->options.noise, "Gaussian sensor noise (sigma, grey levels)")
      ->capture_default_str()
      ->check(finiteIn(0, 50));
  sub->add_flag("--no-collision", a->no_collision, "Only near-collisions, no real one");
  sub->add_flag("--bag", a->options.bag,
                "Also write DIR/states.mcap: the recording as a ROS 2 bag, its joint states and camera frames (for "
                "kccd overlay --bag, check --bag, calib --bag, bag info, bag export)");
  sub->add_flag("--force", a->options.replace, "Replace an existing output folder");
  sub->add_flag("-q,--quiet", a->quiet, "No progress and no summary line");
  sub->footer(
      "Writes DIR/video.mkv (or .avi, .mp4), DIR/states.csv (time, every state value and its .vel),\n"
      "DIR/camera_true.yaml, DIR/intrinsics.yaml (no pose), DIR/tags.yaml, DIR/masks/frame_%06d.png (label\n"
      "mask of the visible geometry: 0 background, i + 1 body i; a visual counts for the first body in its\n"
      "frame, 0 when there is none) and DIR/synth.json (the truth: camera,\n"
      "clock offset, rates, per-frame state and smallest distance, collision frames).\n"
      "With --bag also DIR/states.mcap, the recording as a robot's log (MCAP, ROS 2 CDR): every row of\n"
      "states.csv as a sensor_msgs/msg/JointState on /joint_states (names the state values, positions,\n"
      "velocities), and every video frame as a sensor_msgs/msg/CompressedImage (JPEG, quality 90,\n"
      "format 'bgr8; jpeg compressed bgr8', frame_id camera) on /camera/image_raw/compressed, in\n"
      "log-time order. All on the log's clock from 1700000000 s (2023-11-14 22:13:20 UTC): a row at its\n"
      "time, frame i at i / fps + --time-offset (header stamp = log time = publish time), so the bag has\n"
      "no clock offset to find. E.g.: kccd synth arm.yaml -o rec --bag &&\n"
      "kccd overlay arm.yaml --camera rec/camera_true.yaml --bag rec/states.mcap -o out.mp4\n"
      "Collision means a smallest distance bound <= 0 at the logged state of the frame.\n"
      "Exit status: 0 written, 2 bad input (or no trajectory found for this model and seed).");
  return [a, width, height, shrink] {
    overlay::SynthOptions o = a->options;
    if (width->count() > 0) o.width = a->width;
    if (height->count() > 0) o.height = a->height;
    if (shrink->count() > 0) o.visible_scale = a->visible_scale;
    o.appearance = a->appearance == "visuals"   ? overlay::SynthAppearance::Visuals
                   : a->appearance == "volumes" ? overlay::SynthAppearance::Volumes
                                                : overlay::SynthAppearance::Auto;
    o.collision = !a->no_collision;
    o.spell = [](const std::string& field) {
      return optionSpelling(field, {{"output", "-o"}, {"collision", "--no-collision"}, {"replace", "--force"}});
    };
    return runSynth(o, a->quiet);
  };
}

}  // namespace kccd::cli
