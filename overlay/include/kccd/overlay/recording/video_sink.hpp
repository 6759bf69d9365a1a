// Recordings out: annotated frames to a video file and/or a folder of PNGs, each appearing whole
// or not at all (staged outputs), and single pictures written the same way.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/recording/video_file.hpp"

namespace kccd::overlay {

/// Where a run's frames go, in input order: begin() once before the first frame, then write()
/// once per frame handed on.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  /// The frames to come: their nominal rate and size. Throws an InputError-derived error when the
  /// sink cannot take them.
  virtual void begin(double fps, int width, int height) = 0;
  /// Takes frame `index` (8-bit BGR); throws an InputError-derived error when it cannot be kept.
  virtual void write(std::size_t index, const cv::Mat& bgr) = 0;
};

/// The FourCC a video file gets by default from its extension: FFV1 (lossless) for .mkv, MJPG for
/// .avi, mp4v otherwise; a 4-character `codec` overrides it.
std::string videoFourcc(const std::string& path, const std::string& codec = "");

/// What a VideoSink writes. Empty paths are not written; labels name the outputs in errors.
struct VideoSinkOptions {
  std::string video;        ///< a .mp4, .mkv or .avi file (see videoFourcc)
  std::string codec;        ///< a FourCC, or empty for the extension's default
  std::string video_label;  ///< e.g. "-o out.mp4" (default: the path)
  std::string png_dir;      ///< a new or empty folder of frame_%06d.png (input indices)
  std::string png_label;    ///< e.g. "--png-dir frames" (default: the path)
};

/// A video file and/or a PNG folder written under temporary names; commit() moves them into
/// place, destroying the sink without commit() removes them.
class VideoSink final : public FrameSink {
 public:
  /// Keeps the options; nothing is created before begin().
  explicit VideoSink(const VideoSinkOptions& options);
  ~VideoSink() override;
  VideoSink(const VideoSink&) = delete;
  VideoSink& operator=(const VideoSink&) = delete;

  /// True when there is a video or a folder to write.
  bool active() const { return !options_.video.empty() || !options_.png_dir.empty(); }
  /// Stages the outputs and opens the video writer at `fps`. Throws OutputError ("LABEL: cannot
  /// open a video writer for this container and codec", or the staging's own errors).
  void begin(double fps, int width, int height) override;
  /// Appends the frame to the video and writes frame_%06d.png (`index` in the name) into the
  /// folder. A frame of another size or type is a logic_error (a video writer would drop it).
  void write(std::size_t index, const cv::Mat& bgr) override;
  /// Finishes the video and moves every output into place. Throws OutputError.
  void commit();

 private:
  VideoSinkOptions options_;
  int width_ = 0, height_ = 0;
  std::optional<StagedOutput> video_, png_;
  std::unique_ptr<VideoFileWriter> writer_;
};

/// Encodes `image` as PNG in memory and writes it through writeFileAtomically. Throws
/// OutputError "LABEL: cannot encode the image" (`label` default: the path).
void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& label = "");

}  // namespace kccd::overlay
