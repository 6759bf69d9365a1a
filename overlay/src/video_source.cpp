#include "kccd/overlay/video_source.hpp"

#include <cmath>
#include <filesystem>

#include <opencv2/videoio.hpp>

namespace kccd::overlay {
VideoSource::VideoSource(const std::string& path, const std::string& label)
    : capture_(std::make_unique<cv::VideoCapture>()), label_(label.empty() ? path : label),
      sequence_(path.find('%') != std::string::npos) {
  std::error_code ec;
  if (!sequence_ && !std::filesystem::is_regular_file(path, ec))
    throw VideoError(label_ + ": " +
                     (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file") +
                     " (a video file, or an image sequence such as frames/frame_%06d.png)");
  try {
    capture_->open(path, sequence_ ? cv::CAP_IMAGES : cv::CAP_FFMPEG);
  } catch (const cv::Exception&) {
  }
  if (!capture_->isOpened())
    throw VideoError(label_ + (sequence_ ? ": no image of the sequence can be read"
                                         : ": cannot open the video (not a video OpenCV reads)"));
}

VideoSource::~VideoSource() = default;

double VideoSource::fps() const {
  const double fps = capture_->get(cv::CAP_PROP_FPS);
  return std::isfinite(fps) && fps > 0.0 && fps < 1e6 ? fps : 0.0;
}

std::size_t VideoSource::declaredFrames() const {
  const double n = capture_->get(cv::CAP_PROP_FRAME_COUNT);
  return n > 0 && n < 1e9 ? static_cast<std::size_t>(std::llround(n)) : 0;
}

bool VideoSource::read(cv::Mat& frame) {
  bool got = false;
  try {
    got = capture_->read(frame);
  } catch (const cv::Exception& e) {
    throw VideoError(label_ + ": frame " + std::to_string(next_) + " cannot be decoded (" + printable(e.what(), 200) + ")");
  }
  if (!got || frame.empty()) return false;
  ++next_;
  return true;
}

}  // namespace kccd::overlay
