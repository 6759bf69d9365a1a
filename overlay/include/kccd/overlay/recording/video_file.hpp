// Video files through FFmpeg (libavformat, libavcodec, libswscale): frames decoded to 8-bit BGR
// and 8-bit BGR frames encoded, nothing else. Every command that reads or writes a video file
// goes through these two classes; OpenCV's video back end is not loaded (it brings GStreamer,
// gphoto2 and OpenCV's image codecs into every process, ~0.13 s before main()). FFmpeg's own log
// lines stay unprinted (each failure is reported once, by the caller, in its words): the first
// reader or writer made sets the process's FFmpeg log level to quiet, or to the level
// KCCD_FFMPEG_LOGLEVEL gives (an FFmpeg level such as 32).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include <opencv2/core/mat.hpp>

namespace kccd::overlay {

/// A video file that cannot be opened, decoded or written: FFmpeg's reason in words, without the
/// file's name (the caller names it as the user gave it).
class VideoFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A FourCC as the four characters' codes, the first in the lowest byte (0 for a code that is not
/// four characters).
std::uint32_t fourccCode(const std::string& four);

/// FFmpeg's libraries are loaded the first time a reader or writer is made (by their sonames, so a
/// program that never opens a video does not load them). This loads them on a thread of its own
/// while it lives, for a command that will open a video after other set-up; the destructor waits
/// for the load to end. A load that fails is left to the first reader or writer to report.
class VideoLibraryPreparation {
 public:
  VideoLibraryPreparation();
  ~VideoLibraryPreparation();
  VideoLibraryPreparation(const VideoLibraryPreparation&) = delete;
  VideoLibraryPreparation& operator=(const VideoLibraryPreparation&) = delete;

 private:
  std::thread thread_;
};

/// A video file's first video stream, decoded in order. Frames are converted to 8-bit BGR at the
/// stream's size with swscale's bicubic filter, turned by the stream's display rotation (90, 180
/// or 270 degrees), as OpenCV's FFmpeg capture gives them.
class VideoFileReader {
 public:
  /// Opens `path` and its decoder. Throws VideoFileError.
  explicit VideoFileReader(const std::string& path);
  ~VideoFileReader();
  VideoFileReader(const VideoFileReader&) = delete;
  VideoFileReader& operator=(const VideoFileReader&) = delete;

  /// The frame rate the stream declares (its average rate, else its base rate), or 0.
  double fps() const;
  /// The number of frames the container declares, else its duration times fps() rounded, or 0.
  std::size_t declaredFrames() const;
  /// The codec's FourCC as the container stores it, else the usual one for the codec ("" when none).
  std::string fourcc() const;
  /// Decodes the next frame into `bgr` (reallocated as needed); false after the last. A packet the
  /// decoder refuses is skipped, as players do, until 64 in a row fail: then VideoFileError.
  bool read(cv::Mat& bgr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A video file written frame by frame: the container from the file's extension, the codec from
/// a FourCC (mp4v, XVID, DIVX, FMP4: MPEG-4 part 2; MJPG: Motion JPEG; FFV1: lossless; avc1,
/// H264: H.264; hvc1, HEVC: H.265; VP80, VP90), the encoder's settings those of OpenCV's FFmpeg
/// writer (bit rate fps x width x height, a key frame every 12 frames), one frame per 1/fps.
/// write() converts the pixels to the encoder's format in the caller's thread and hands the frame
/// to a thread of the writer's own that encodes the frames in order (up to 3 in flight).
class VideoFileWriter {
 public:
  /// Creates `path` and opens the encoder for `width` x `height` frames at `fps`. Throws
  /// VideoFileError when the container, the codec or the size is refused.
  VideoFileWriter(const std::string& path, const std::string& fourcc, double fps, int width, int height);
  /// Closes the file without finishing it (finish() was not called: the file is not whole).
  ~VideoFileWriter();
  VideoFileWriter(const VideoFileWriter&) = delete;
  VideoFileWriter& operator=(const VideoFileWriter&) = delete;

  /// Encodes one 8-bit BGR frame of the writer's size. Throws VideoFileError (also an earlier
  /// frame's encoding failure); a frame of another size or type is a std::logic_error.
  void write(const cv::Mat& bgr);
  /// Encodes what is queued, drains the encoder and writes the container's trailer. Throws
  /// VideoFileError.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kccd::overlay
