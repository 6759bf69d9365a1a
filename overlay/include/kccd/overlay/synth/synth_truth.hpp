// What a synthetic recording knows of itself, as files: the tag layout and the intrinsics in the
// formats `kccd calib` reads, and synth.json (the truth: camera, clocks, rates, per-frame state,
// smallest distance and safety status, collision frames, the trajectory's events, timings).
#pragma once

#include <array>
#include <filesystem>
#include <string>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/synth/synth.hpp"
#include "kccd/overlay/synth/synth_scene.hpp"
#include "kccd/overlay/synth/synth_trajectory.hpp"

namespace kccd::overlay {

/// tags.yaml: the layout as `kccd calib --tags` reads it (every number with 17 significant digits).
std::string tagLayoutText(const calib::TagLayout& layout);

/// intrinsics.yaml: image size, camera matrix and distortion, no pose (OpenCV FileStorage YAML).
std::string intrinsicsText(const calib::Camera& camera);

/// How the frames were made and how long each part took, for synth.json.
struct SynthRun {
  std::string video_file;                            ///< name in the folder (videoFormat)
  std::string bag_file;                              ///< the state log's bag in the folder; empty: none
  bool visuals = false;                              ///< drawn with the model's visuals (else its shrunken volumes)
  double supersample = 1.0, mask_supersample = 1.0;  ///< the renderer's options
  std::string renderer;                              ///< the GL renderer's name
  double total_s = 0, trajectory_s = 0, background_s = 0;
  double render_s = 0;               ///< rendering and compositing, all frames
  std::array<double, 4> writer_s{};  ///< SensorWriter::stageSeconds()
};

/// synth.json (format: docs/formats.md). Every frame's status is kccd::toString(safetyStatus(d,
/// margin)) of its smallest distance bound d; `collision.frames` and `near_collision_frames` list
/// the colliding and within-margin frames.
std::string truthText(const SynthOptions& options, const Model& m, const SynthMotion& motion, const SynthScene& scene,
                      const SynthRun& run);

/// Writes states.csv, camera_true.yaml, intrinsics.yaml and tags.yaml into `dir` (each through
/// writeFileAtomically).
void writeRecordingFiles(const std::filesystem::path& dir, const SynthMotion& motion, const SynthScene& scene);

}  // namespace kccd::overlay
