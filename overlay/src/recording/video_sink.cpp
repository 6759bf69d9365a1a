#include "kccd/overlay/recording/video_sink.hpp"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

namespace kccd::overlay {

int videoFourcc(const std::string& path, const std::string& codec) {
  if (codec.size() == 4) {
    // The usual codecs in their containers' own spelling, whatever the case given: FFmpeg maps a
    // FourCC to a codec ignoring case, but a muxer that wants another spelling makes OpenCV print
    // a warning of its own on the way.
    std::string c = codec;
    for (const char* known :
         {"MJPG", "FFV1", "mp4v", "XVID", "DIVX", "avc1", "H264", "hvc1", "HEVC", "VP80", "VP90", "FMP4"}) {
      bool same = true;
      for (std::size_t k = 0; k < 4; ++k)
        same = same && std::tolower(static_cast<unsigned char>(codec[k])) == std::tolower(known[k]);
      if (same) c = known;
    }
    return cv::VideoWriter::fourcc(c[0], c[1], c[2], c[3]);
  }
  const std::string ext = lowerExtension(path);
  if (ext == ".mkv") return cv::VideoWriter::fourcc('F', 'F', 'V', '1');
  if (ext == ".avi") return cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  return cv::VideoWriter::fourcc('m', 'p', '4', 'v');
}

VideoSink::VideoSink(const VideoSinkOptions& options) : options_(options) {
  if (options_.video_label.empty()) options_.video_label = options_.video;
  if (options_.png_label.empty()) options_.png_label = options_.png_dir;
}

void VideoSink::begin(double fps, int width, int height) {
  width_ = width;
  height_ = height;
  if (!options_.video.empty()) {
    video_.emplace(options_.video, StagedOutput::Kind::File, options_.video_label);
    writer_ = std::make_unique<cv::VideoWriter>();
    bool ok = false;
    try {
      ok = writer_->open(video_->path().string(), cv::CAP_FFMPEG, videoFourcc(options_.video, options_.codec), fps,
                         cv::Size(width, height), true);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) throw OutputError(options_.video_label + ": cannot open a video writer for this container and codec");
  }
  if (!options_.png_dir.empty()) png_.emplace(options_.png_dir, StagedOutput::Kind::Folder, options_.png_label);
}

VideoSink::~VideoSink() = default;

void VideoSink::write(std::size_t index, const cv::Mat& bgr) {
  if (bgr.type() != CV_8UC3 || bgr.cols != width_ || bgr.rows != height_)
    throw std::logic_error("overlay frame of the wrong size or type");
  if (writer_) writer_->write(bgr);
  if (png_) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06zu.png", index);
    bool ok = false;
    try {
      ok = cv::imwrite((png_->path() / name).string(), bgr);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) throw OutputError(options_.png_label + ": cannot write " + name);
  }
}

void VideoSink::commit() {
  if (writer_) writer_->release();
  if (video_) video_->commit();
  if (png_) png_->commit();
}

void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& label) {
  const std::string name = label.empty() ? path : label;
  std::vector<uchar> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw OutputError(name + ": cannot encode the image");
  writeFileAtomically(path, std::string(png.begin(), png.end()), name);
}

}  // namespace kccd::overlay
