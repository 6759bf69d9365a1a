// Synthetic recordings with ground truth (`kccd synth`): the robot's visible geometry moving along a
// smooth trajectory with near-collisions and one real collision, in a room with AprilTags, seen
// through a distorting camera with blur and noise; written as a folder with the video, the state
// log (also, with the frames, as a ROS 2 bag on request), the true camera, the intrinsics, the tag
// layout, per-frame masks and the truth (synth.json).
//
// The job's parts, one unit each: the trajectory search (synth_trajectory.hpp), the room, its tags
// and the default camera (synth_scene.hpp), the sensor model and frame drawing (synth_sensor.hpp),
// the truth and the text files (synth_truth.hpp); synthesizeRecording() runs them in order.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"

namespace kccd::overlay {

/// Input that cannot make a recording: a bad option, a model that cannot collide, no trajectory
/// found, a camera that sees too few tags, an output folder that exists. One line. An option out
/// of range is named by its SynthOptions field (location().field, no source: "fps: must be 1 ...
/// 240"), for a front end to say in its own spelling; the output folder as `kccd synth` says it
/// ("-o DIR: ...").
class SynthError : public InputError {
 public:
  using InputError::InputError;
};

/// What the robot looks like in the recording.
enum class SynthAppearance {
  Auto,     ///< Visuals when the model has visuals:, else Volumes
  Volumes,  ///< every body's SSCH, its radius scaled by SynthOptions::visible_scale
  Visuals,  ///< the model's visual meshes and primitives
};

/// Everything that shapes a recording. The same options and seed give the same files.
struct SynthOptions {
  static constexpr int kDefaultWidth = 1280, kDefaultHeight = 720;
  static constexpr double kDefaultVisibleScale = 0.8;

  std::string model;                    ///< model file (kccd: 1 YAML); named in errors and in synth.json as given
  std::string output;                   ///< output folder (created; it appears only when the recording is complete)
  std::string camera;                   ///< camera file to film with; empty: a default camera placed to see the robot
  double seconds = 5.0;                 ///< length (0.04 ... 600 s; at least one frame)
  double fps = 25.0;                    ///< video frame rate (1 ... 240)
  double log_rate = 125.0;              ///< state log rate (Hz), must differ from fps
  double time_offset = 0.137;           ///< log clock minus video clock (s; the log starts at log time 0)
  std::optional<int> width, height;     ///< default camera's image size (64 ... 4096 px); not with a camera file
  std::optional<double> visible_scale;  ///< Volumes: radius fraction of the SSCHs (default 0.8)
  SynthAppearance appearance = SynthAppearance::Auto;
  double blur = 0.7;       ///< Gaussian blur of every frame (sigma, px)
  double noise = 2.5;      ///< Gaussian sensor noise (sigma, grey levels)
  std::uint64_t seed = 1;  ///< trajectory search and noise
  /// ffvhuff (video.mkv, lossless, fast), ffv1 (video.mkv, lossless, smaller), mjpg (video.avi) or
  /// mp4v (video.mp4)
  std::string codec = "ffvhuff";
  bool collision = true;  ///< one real collision (false: only near-collisions)
  bool replace = false;   ///< replace an existing non-empty output folder
  /// Also states.mcap: the state log and the frames as a ROS 2 bag (StateLogBagWriter's defaults; frame
  /// i stamped at log time i / fps + time_offset, on the log's clock).
  bool bag = false;
  /// How hints name these fields ("seed" -> "--seed", "collision" -> "--no-collision"; default: as they are).
  FieldSpelling spell;
};

/// What was written, for the caller to report.
struct SynthResult {
  std::filesystem::path folder;  ///< the output folder (SynthOptions::output)
  std::string video_file;        ///< the video's name in the folder (video.mkv, .avi, .mp4)
  std::string bag_file;          ///< "states.mcap" with SynthOptions::bag, else empty
  int frames = 0, width = 0, height = 0;
  double fps = 0, log_rate = 0, time_offset = 0;
  std::size_t log_rows = 0;                             ///< rows of states.csv
  std::size_t tags = 0;                                 ///< tags in tags.yaml
  bool visuals = false;                                 ///< drawn with the model's visuals
  std::vector<double> min_distance;                     ///< per frame: the smallest distance bound at its logged state
  std::vector<int> colliding_frames, near_frames;       ///< frames colliding / within the safety margin
  std::vector<std::array<int, 2>> collision_intervals;  ///< first and last frame of each colliding run
  double seconds = 0;                                   ///< wall time of the whole job
};

/// Called with the fraction of frames written (0 ... 1] after each frame.
using SynthProgress = std::function<void(double fraction)>;

/// Makes the recording described by `options` in `options.output` (built under a temporary name
/// beside it and renamed into place at the end: see StagedOutput): video, states.csv (and with
/// `bag` states.mcap), camera_true.yaml, intrinsics.yaml, tags.yaml, masks/frame_%06d.png and synth.json. Throws
/// SynthError (or another InputError: the model, camera or a visual's mesh cannot be read) for
/// input that cannot make a recording, OutputError when the folder cannot be written; nothing is
/// left at the target then.
SynthResult synthesizeRecording(const SynthOptions& options, const SynthProgress& progress = {});

}  // namespace kccd::overlay
