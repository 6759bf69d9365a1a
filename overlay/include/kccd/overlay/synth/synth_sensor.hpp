// Frames of a synthetic recording: the robot drawn over the static background (frame drawing), then
// the sensor model (lens vignetting, Gaussian blur, seeded sensor noise) and the writing of each
// frame to the video and its label mask to a PNG, on a thread of its own while the next frame
// renders.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/recording/video_file.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/render/visuals.hpp"

namespace kccd::overlay {

/// The video file a codec name writes and its FourCC: ffvhuff and ffv1 -> video.mkv, mjpg ->
/// video.avi, mp4v -> video.mp4. Throws SynthError for another name.
struct VideoFormat {
  std::string file;
  std::string fourcc;
};
VideoFormat videoFormat(const std::string& codec);

/// Colour of body i's visible volume: static bodies dark grey, moving links alternating light and
/// mid grey with blue accents (BGR).
cv::Scalar bodyColour(const Model& m, std::size_t i);

/// The robot's visible geometry drawn by the overlay's renderer and lens model (shaded, no legend,
/// supersampled 2 x 2, label mask 2 x 2): the model's visuals, or every body's SSCH with its radius
/// scaled.
class FramePainter {
 public:
  /// Throws calib::CameraError when the renderer refuses the camera.
  FramePainter(const Model& m, const calib::Camera& camera);
  /// What the robot looks like: `visuals` when not empty, else the volumes at `volume_scale`.
  void setAppearance(std::vector<render::LoadedVisual> visuals, double volume_scale);

  /// The visible geometry at q, rendered with its label mask (0 background, i + 1 body i).
  render::Frame robot(std::span<const double> q);
  /// Label mask of the full volumes at q (no colour image).
  cv::Mat fullMask(std::span<const double> q);
  /// The frame at q: `background` with the robot composited over it; `mask` gets its label mask.
  cv::Mat draw(const cv::Mat& background, std::span<const double> q, cv::Mat& mask);

  const render::RenderOptions& renderOptions() const { return options_; }
  std::string rendererString() const { return view_->renderer().rendererString(); }

 private:
  const Model& model_;
  calib::Camera camera_;
  render::RenderOptions options_;
  std::unique_ptr<render::ModelView> view_;
  std::vector<cv::Scalar> colours_;  // per body, bodyColour
  bool use_visuals_ = false;
  double scale_ = 1.0;
};

/// Natural vignetting gain per pixel (CV_8UC3, 255 = 1): 1 - 0.25 r^2, r the distance from the
/// principal point over the half diagonal (r^2 at most 2).
cv::Mat vignetteGain(const calib::Camera& camera);

/// The sensor model and the writer: each pushed frame is vignetted, blurred (sigma `blur`, px) and
/// given Gaussian noise (sigma `noise` grey levels: one field drawn from `seed`, each frame taking
/// it at an offset and sign seeded by the seed and its index), then written to `video`, and its
/// mask to `mask_dir`/frame_%06d.png, in push order, on a thread of its own; a frame sink, when
/// set, gets each frame too.
class SensorWriter {
 public:
  SensorWriter(VideoFileWriter& video, std::string mask_dir, double blur, double noise, std::uint64_t seed);
  ~SensorWriter();
  SensorWriter(const SensorWriter&) = delete;
  SensorWriter& operator=(const SensorWriter&) = delete;

  /// Lens vignetting (vignetteGain), applied before blur and noise; set before the first push.
  void setVignette(cv::Mat gain);
  /// Called on the writer's thread with each frame as the video got it (after the sensor model),
  /// in push order, once its mask is written; what it throws is that frame's error. Set before
  /// the first push.
  void setFrameSink(std::function<void(int index, const cv::Mat& frame)> sink);
  /// Queues frame `index` (BGR) and its label mask (CV_8UC1); waits while two are queued.
  void push(int index, cv::Mat frame, cv::Mat mask);
  /// Writes what is queued and stops the thread.
  void finish();
  /// Frames written (after finish()).
  int written() const;
  /// Seconds spent in vignetting and blur, noise, video encoding, mask writing (after finish()).
  const std::array<double, 4>& stageSeconds() const;
  /// The first error ("frame 3: ..."), empty when none; frames after it are dropped.
  const std::string& error() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kccd::overlay
