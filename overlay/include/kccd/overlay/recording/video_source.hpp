// Recordings in: one rule, for every command, for opening a recording and reading its frames.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include <opencv2/core/mat.hpp>

#include "kccd/input_error.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/overlay/recording/video_file.hpp"

namespace kccd::overlay {

/// A recording that cannot be opened or a frame that cannot be decoded. One line naming the
/// recording as the user gave it ("--video a.mkv: frame 12 cannot be decoded (...)").
class VideoError : public InputError {
 public:
  using InputError::InputError;
};

/// A recording's frames, read in order (seeking is not reliable in every codec). A path with a
/// '%' is an image sequence named by a printf pattern (`frames/frame_%06d.png`, numbered from 0,
/// or from 1 when there is no frame 0, up to the first missing number; each file read by
/// calib::readImageFile); any other path must be a regular file that FFmpeg decodes
/// (VideoFileReader).
class VideoSource final : public FrameSource {
 public:
  /// Opens `path`. `label` names it in errors (default: the path). Throws VideoError.
  explicit VideoSource(const std::string& path, const std::string& label = "");
  ~VideoSource() override;
  VideoSource(const VideoSource&) = delete;
  VideoSource& operator=(const VideoSource&) = delete;

  /// True for an image sequence.
  bool isSequence() const { return sequence_; }
  /// The frame rate the recording declares, or 0 when it declares none.
  double fps() const override;
  /// The number of frames the recording declares, or 0 when unknown.
  std::size_t declaredFrames() const override;
  /// The FourCC the video file declares for its codec ("av01", "avc1", "mp4v", ...; "" for an
  /// image sequence or when it declares none).
  std::string codec() const;
  /// Reads the next frame into `frame` (BGR as decoded); false at the end. Throws VideoError
  /// naming the frame's index when the decoder fails on it.
  bool read(cv::Mat& frame) override;
  /// Index of the next frame read() returns (0 before the first).
  std::size_t nextIndex() const override { return next_; }

 private:
  std::unique_ptr<VideoFileReader> file_;  ///< a video file
  std::string label_;
  bool sequence_ = false;
  std::string pattern_;                 ///< an image sequence: its printf pattern,
  std::size_t first_ = 0, length_ = 0;  ///< first number and frame count
  std::size_t next_ = 0;
};

}  // namespace kccd::overlay
