#include "kccd/overlay/recording/video_sink.hpp"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "kccd/calib/image_encode.hpp"
#include "kccd/overlay/recording/video_file.hpp"

namespace kccd::overlay {

std::string videoFourcc(const std::string& path, const std::string& codec) {
  if (codec.size() == 4) {
    // The usual codecs in their containers' own spelling, whatever the case given.
    std::string c = codec;
    for (const char* known :
         {"MJPG", "FFV1", "FFVH", "mp4v", "XVID", "DIVX", "avc1", "H264", "hvc1", "HEVC", "VP80", "VP90", "FMP4"}) {
      bool same = true;
      for (std::size_t k = 0; k < 4; ++k)
        same = same && std::tolower(static_cast<unsigned char>(codec[k])) == std::tolower(known[k]);
      if (same) c = known;
    }
    return c;
  }
  const std::string ext = lowerExtension(path);
  if (ext == ".mkv") return "FFV1";
  if (ext == ".avi") return "MJPG";
  return "mp4v";
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
    try {
      writer_ = std::make_unique<VideoFileWriter>(video_->path().string(), videoFourcc(options_.video, options_.codec),
                                                  fps, width, height);
    } catch (const VideoFileError& e) {
      throw OutputError(options_.video_label + ": cannot write this container and codec (" + e.what() + ")");
    }
  }
  if (!options_.png_dir.empty()) png_.emplace(options_.png_dir, StagedOutput::Kind::Folder, options_.png_label);
}

VideoSink::~VideoSink() = default;

void VideoSink::write(std::size_t index, const cv::Mat& bgr) {
  if (bgr.type() != CV_8UC3 || bgr.cols != width_ || bgr.rows != height_)
    throw std::logic_error("overlay frame of the wrong size or type");
  if (writer_) {
    try {
      writer_->write(bgr);
    } catch (const VideoFileError& e) {
      throw OutputError(options_.video_label + ": frame " + std::to_string(index) + " (" + e.what() + ")");
    }
  }
  if (png_) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06zu.png", index);
    try {
      const std::vector<std::uint8_t> png = calib::encodePng(bgr);
      std::ofstream file(png_->path() / name, std::ios::binary);
      file.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
      if (!file.flush()) throw OutputError(options_.png_label + ": cannot write " + name);
    } catch (const calib::ImageEncodeError& e) {
      throw OutputError(options_.png_label + ": cannot write " + name + " (" + e.what() + ")");
    }
  }
}

void VideoSink::commit() {
  if (writer_) {
    try {
      writer_->finish();
    } catch (const VideoFileError& e) {
      throw OutputError(options_.video_label + ": " + e.what());
    }
    writer_.reset();
  }
  if (video_) video_->commit();
  if (png_) png_->commit();
}

void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& label) {
  const std::string name = label.empty() ? path : label;
  std::vector<std::uint8_t> png;
  try {
    png = calib::encodePng(image);
  } catch (const calib::ImageEncodeError& e) {
    throw OutputError(name + ": cannot encode the image (" + e.what() + ")");
  }
  writeFileAtomically(path, std::string(png.begin(), png.end()), name);
}

}  // namespace kccd::overlay
