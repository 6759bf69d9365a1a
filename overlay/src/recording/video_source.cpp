#include "kccd/overlay/recording/video_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

#include "kccd/calib/image_file.hpp"
#include "kccd/overlay/recording/video_file.hpp"

namespace kccd::overlay {

namespace {

// The file of an image sequence's frame `index` (the pattern's printf number).
std::string sequenceFile(const std::string& pattern, std::size_t index) {
  std::vector<char> name(pattern.size() + 64);
  const int n = std::snprintf(name.data(), name.size(), pattern.c_str(), static_cast<int>(index));
  return n < 0 ? std::string() : std::string(name.data(), std::min(name.size() - 1, static_cast<std::size_t>(n)));
}

bool isFile(const std::string& path) {
  std::error_code ec;
  return !path.empty() && std::filesystem::is_regular_file(path, ec);
}

// One printf conversion of an integer (%d, %06d, %4i, ...) and no other: anything else in a
// pattern would read memory that is not there.
bool onePrintfNumber(const std::string& pattern) {
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') continue;
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < pattern.size() && (pattern[j] == '0' || pattern[j] == '-' || pattern[j] == ' ' || pattern[j] == '+'))
      ++j;
    while (j < pattern.size() && pattern[j] >= '0' && pattern[j] <= '9') ++j;
    if (j >= pattern.size() || (pattern[j] != 'd' && pattern[j] != 'i')) return false;
    ++conversions;
    i = j;
  }
  return conversions == 1;
}

}  // namespace

VideoSource::VideoSource(const std::string& path, const std::string& label)
    : label_(label.empty() ? path : label), sequence_(path.find('%') != std::string::npos) {
  std::error_code ec;
  if (sequence_) {
    // Image sequences are read here, each frame by calib::readImageFile (so a damaged PNG is one
    // line, never libpng's own message): numbered from 0, or from 1 when there is no frame 0, up
    // to the first missing number.
    if (!onePrintfNumber(path))
      throw VideoError(label_ + ": an image sequence's name needs one printf number such as %06d, and no other %");
    pattern_ = path;
    first_ = isFile(sequenceFile(path, 0)) ? 0 : 1;
    while (isFile(sequenceFile(path, first_ + length_))) ++length_;
    if (length_ == 0)
      throw VideoError(label_ + ": no image of the sequence can be read (no file " + sequenceFile(path, 0) + " or " +
                       sequenceFile(path, 1) + ")");
    return;
  }
  if (!std::filesystem::is_regular_file(path, ec))
    throw VideoError(label_ + ": " + (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file") +
                     " (a video file, or an image sequence such as frames/frame_%06d.png)");
  try {
    file_ = std::make_unique<VideoFileReader>(path);
  } catch (const VideoFileError& e) {
    throw VideoError(label_ + ": cannot open the video: " + printable(e.what(), 200));
  }
}

VideoSource::~VideoSource() = default;

double VideoSource::fps() const {
  if (sequence_) return 0.0;
  return file_->fps();
}

std::string VideoSource::codec() const {
  if (sequence_) return {};
  return file_->fourcc();
}

std::size_t VideoSource::declaredFrames() const {
  if (sequence_) return length_;
  return file_->declaredFrames();
}

bool VideoSource::read(cv::Mat& frame) {
  if (sequence_) {
    if (next_ >= length_) return false;
    try {
      frame = calib::readImageFile(sequenceFile(pattern_, first_ + next_), calib::ImageColour::Bgr);
    } catch (const calib::ImageError& e) {
      throw VideoError(label_ + ": frame " + std::to_string(next_) + " cannot be decoded (" + printable(e.what(), 300) +
                       ")");
    }
    ++next_;
    return true;
  }
  bool got = false;
  try {
    got = file_->read(frame);
  } catch (const VideoFileError& e) {
    throw VideoError(label_ + ": frame " + std::to_string(next_) + " cannot be decoded (" + printable(e.what(), 200) +
                     ")");
  }
  if (!got || frame.empty()) return false;
  ++next_;
  return true;
}

}  // namespace kccd::overlay
